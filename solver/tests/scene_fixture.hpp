// Helpers for tests that run small scenes: a scene from YAML text, the model and a CPU
// backend built from it, and a scratch folder.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "integrate/backend.hpp"
#include "io/scene_yaml.hpp"
#include "model/model.hpp"

namespace qdemsph::testing {

inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("qdemsph_test_" + name);
  std::filesystem::create_directories(d);
  return d;
}

struct Problem {
  Scene scene;
  Model model;
  std::unique_ptr<Backend> backend;
};

// `yaml` is a complete scene; `file` names it (and anchors relative mesh paths).
inline Problem make_problem(const std::string& yaml,
                            const std::filesystem::path& file = "test.yaml",
                            const std::string& backend = "cpu") {
  Problem p;
  p.scene = parse_scene(yaml, file);
  p.model = build_model(p.scene);
  p.backend = make_backend(backend);
  p.backend->upload(p.model);
  return p;
}

}  // namespace qdemsph::testing
