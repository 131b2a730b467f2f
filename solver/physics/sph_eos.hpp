// Weakly compressible equation of state (Tait / Cole, Monaghan 1994):
//
//   p = B ((rho / rho0)^gamma - 1),  B = c0^2 rho0 / gamma,  gamma = 7
//   rho(p) = rho0 (1 + p / B)^(1/gamma)                 (inverse, for wall particles)
//   c(rho) = c0 (rho / rho0)^((gamma - 1) / 2)          (local sound speed)
//
// c0 is stated by the scene (fluid.sound_speed) or chosen as 10 sqrt(2 g H), which keeps the
// Mach number below 0.1 and the density variation below ~1 % (Monaghan 1994).
//
// Tension cut-off p_min <= 0 (fluid.min_pressure, default 0): the fluid's density is kept at or
// above rho_min = rho(p_min), so p >= p_min. Without it a particle that splashes away from a
// wall or from the bulk loses density through the continuity equation with nothing to restore
// it (the dam break's far-wall jet reached rho < 0.4 rho0 and then a negative density), and the
// tension pulls it into walls. Momentum conservation is unaffected (a per-particle state).
#pragma once

#include <cmath>

#include "core/hd.hpp"

namespace qdemsph {

struct TaitEos {
  double rho0 = 1000;  // reference density [kg/m^3]
  double inv_rho0 = 1e-3;
  double c0 = 10;      // reference sound speed [m/s]
  double B = 0;        // c0^2 rho0 / gamma [Pa]
  double p_min = 0;    // tension cut-off [Pa] (<= 0; -1e300: none)
  double rho_min = 0;  // density(p_min): the floor of the fluid's density

  static constexpr double gamma = 7.0;

  static TaitEos make(double rho0, double c0, double p_min = 0.0) {
    TaitEos e;
    e.rho0 = rho0;
    e.inv_rho0 = 1.0 / rho0;
    e.c0 = c0;
    e.B = c0 * c0 * rho0 / gamma;
    e.p_min = p_min;
    e.rho_min = e.density(p_min);
    return e;
  }
  QDEMSPH_HD double pressure(double rho) const {
    const double r = rho * inv_rho0;
    const double r2 = r * r, r4 = r2 * r2;
    const double p = B * (r4 * r2 * r - 1.0);
    return p > p_min ? p : p_min;
  }
  // The density after dt at the rate drho_dt, floored at rho_min (the tension cut-off).
  QDEMSPH_HD double next_density(double rho, double drho_dt, double dt) const {
    const double r = rho + dt * drho_dt;
    return r > rho_min ? r : rho_min;
  }
  QDEMSPH_HD double density(double p) const {
    const double s = 1.0 + p / B;
    return rho0 * pow(s > 1e-6 ? s : 1e-6, 1.0 / gamma);
  }
  QDEMSPH_HD double sound_speed(double rho) const {
    const double r = rho * inv_rho0;
    return c0 * r * r * r;  // (rho/rho0)^((7-1)/2)
  }
};

}  // namespace qdemsph
