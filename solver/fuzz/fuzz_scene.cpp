// libFuzzer target: the scene parser and validator (io/scene_yaml.hpp).
//
// Input: arbitrary bytes taken as the text of a scene file. parse_scene must either return a
// validated Scene or throw InputError; any other exception, a crash, a sanitizer report, a
// hang or a leak is a finding. The scene's own folder does not exist, so gmsh mesh paths
// resolve to missing files (reported as InputError when the parser checks them).
//
// Build and run: ci/fuzz.sh SECONDS (seed corpus: solver/tests/data/scenes/{good,bad}).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string_view>

#include "core/error.hpp"
#include "io/scene_yaml.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)qdemsph::parse_scene(text, "/nonexistent-qdemsph-fuzz/scene.yaml");
  } catch (const qdemsph::InputError&) {
    // the expected outcome for bad input
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_scene: exception other than InputError escaped parse_scene: %s\n",
                 e.what());
    std::abort();
  }
  return 0;
}
