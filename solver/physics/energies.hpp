// The energy budget of a run. total = kinetic + strain + potential + dissipated stays
// constant up to the work of prescribed velocities; potential counts gravity and the dead
// loads, -(m g + f_ext) . u.
#pragma once

namespace qdemsph {

struct Energies {
  double kinetic = 0, strain = 0, potential = 0, dissipated = 0;
  double total() const { return kinetic + strain + potential + dissipated; }
};

}  // namespace qdemsph
