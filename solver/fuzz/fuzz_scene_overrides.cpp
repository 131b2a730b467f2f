// libFuzzer target: command-line overrides (--set dotted.key=yaml_value) applied to a valid
// scene (io/scene_yaml.hpp). Input: bytes split at '\n' into override strings (at most 8).
// parse_scene must return a Scene or throw InputError; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "io/scene_yaml.hpp"

namespace {
constexpr std::string_view kBase = R"(name: fuzz
run: {end_time: 0.01, dt_safety: 0.5}
gravity: [0, 0, -9.81]
materials:
  rubber: {law: svk, E: 1.0e6, nu: 0.3, density: 1000.0, viscosity: 10.0}
bodies:
  - {name: beam, material: rubber, mesh: {type: box, size: [1.0, 0.1, 0.1], cells: [4, 1, 1]}}
constraints:
  - {type: fixed, body: beam, region: {x: [-1.0e-9, 1.0e-9]}}
loads:
  - {type: traction, body: beam, region: {x: [0.999, 1.001]}, traction: [0, 0, -100.0]}
probes:
  - {name: tip, type: displacement, body: beam, region: {x: [0.999, 1.001]}}
output: {fields_every: 0}
)";
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> overrides;
  std::string cur;
  for (std::size_t i = 0; i < size && overrides.size() < 8; ++i) {
    if (data[i] == '\n') {
      overrides.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(static_cast<char>(data[i]));
    }
  }
  if (overrides.size() < 8) overrides.push_back(cur);
  try {
    (void)qdemsph::parse_scene(kBase, "/nonexistent-qdemsph-fuzz/scene.yaml", overrides);
  } catch (const qdemsph::InputError&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_scene_overrides: exception other than InputError escaped: %s\n",
                 e.what());
    std::abort();
  }
  return 0;
}
