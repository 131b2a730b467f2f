// The energy budget of a run. total = kinetic + strain + potential + dissipated + contact +
// contact_dissipated stays constant up to the work of prescribed velocities and the time
// integration error; potential counts gravity and the dead loads, -(m g + f_ext) . u.
// contact: elastic energy stored in the contact springs (normal and tangential);
// contact_dissipated: energy dissipated by the contact dashpots and Coulomb slip
// (physics/contact_law.hpp, contact_energy).
#pragma once

namespace qdemsph {

struct Energies {
  double kinetic = 0, strain = 0, potential = 0, dissipated = 0;
  double contact = 0, contact_dissipated = 0;
  double total() const {
    return kinetic + strain + potential + dissipated + contact + contact_dissipated;
  }
};

}  // namespace qdemsph
