// Scene files: YAML text -> validated Scene (the format is documented in docs/scene-format.md).
//
// All input validation happens here, once, so that the solver can trust a Scene. Every error
// is an InputError whose message reads
//   FILE:LINE: key.path: rule (got VALUE)
// where key.path uses the same dotted syntax as overrides (bodies.0.mesh.cells), so a user
// can fix a scene from the command line with the path the error printed. Errors in a value
// that came from an override name the override instead of a line:
//   FILE: override 'run.dt=-1': run.dt: must be > 0 (got -1)
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "io/scene.hpp"

namespace qdemsph {

// Reads and validates a scene file. `overrides` are "dotted.key.path=yaml_value" strings
// (e.g. "bodies.0.mesh.cells=[40,4,4]", "run.end_time=0.5") applied to the YAML tree, in
// order, before validation. Sequence elements are addressed by index; an index equal to the
// sequence length appends. Missing map keys (and missing intermediate maps) are created, so
// a misspelt key is reported by validation as an unknown key. Throws InputError.
Scene load_scene(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

// Same as load_scene on text already in memory (tests, fuzzing). `file` is used only to name
// the source in messages and to resolve relative mesh paths against its folder.
Scene parse_scene(std::string_view text, const std::filesystem::path& file,
                  const std::vector<std::string>& overrides = {});

}  // namespace qdemsph
