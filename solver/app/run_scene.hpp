// Runs a scene end to end: model, backend, initial static solve (preload) or static mode,
// the time loop, probes, field snapshots, progress and summary.json.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "io/scene.hpp"

namespace qdemsph {

struct RunOptions {
  std::optional<std::filesystem::path> out;  // overrides output.dir
  std::optional<std::string> backend;        // overrides run.backend
  bool quiet = false;
};

// Returns the process exit code: 0 completed/converged, 3 static solve not converged.
// A SimulationError is reported in summary.json (status "failed") with a final diagnostic
// snapshot, then rethrown.
int run_scene(const Scene& scene, const RunOptions& options);

// `qdemsph info`: stages the scene needs, sizes, dt and memory.
void print_info(const Scene& scene);

// `qdemsph mesh`: each body's mesh as DIR/<body>.msh.
void export_meshes(const Scene& scene, const std::filesystem::path& dir);

}  // namespace qdemsph
