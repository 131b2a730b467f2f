// Error types. InputError: the user's input (scene, mesh, options) is wrong; the message
// names the file, line, key path or element and the rule broken. SimulationError: the run
// became invalid (NaN, inverted tet, instability); the message names where and when.
#pragma once

#include <stdexcept>
#include <string>

namespace qdemsph {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct SimulationError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace qdemsph
