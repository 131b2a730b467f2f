// Constitutive laws of the QDEM element, as pure host/device functions.
//
// Elastic part, written as a first Piola-Kirchhoff stress P(F) and energy density W(F):
//  - Linear (the report's small-strain Hooke law, identical to P1 linear elasticity):
//      eps = sym(F) - I,  P = sigma = lambda tr(eps) I + 2 mu eps,  W = sigma:eps / 2.
//    Not rotation invariant: only for small rotations (cantilever, patch test).
//  - St. Venant-Kirchhoff (default; a rigid rotation gives exactly zero stress):
//      E = (F^T F - I)/2,  S = lambda tr(E) I + 2 mu E,  P = F S,
//      W = lambda tr(E)^2 / 2 + mu E:E.
// Viscous part (Kelvin-Voigt), from the velocity gradient L = dv dx^-1 = Fdot F^-1 (METHOD
// eq. 2) expressed through Fdot = dv dX^-1, acting like the elastic moduli scaled by eta/E,
// so a mode of angular frequency omega has damping ratio zeta = eta omega / (2E):
//  - Linear: P_v = (eta/E) C : sym(Fdot)
//  - SVK:    P_v = F (eta/E) C : Edot,  Edot = sym(F^T Fdot) = F^T sym(L) F.
#pragma once

#include <cstdint>

#include "core/vec.hpp"

namespace qdemsph {

struct Material {
  std::int32_t law = 1;  // 0: linear, 1: St. Venant-Kirchhoff
  double lambda = 0, mu = 0;
  double density = 0;
  double visc_ratio = 0;  // eta / E [s]
};

QDEMSPH_HD Material make_material(int law, double E, double nu, double density, double viscosity) {
  Material m;
  m.law = law;
  m.lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  m.mu = E / (2 * (1 + nu));
  m.density = density;
  m.visc_ratio = viscosity / E;
  return m;
}

// Isotropic Hooke tensor applied to a symmetric strain: C : e.
QDEMSPH_HD Mat3 hooke(const Material& m, const Mat3& e) {
  return m.lambda * trace(e) * Mat3::identity() + 2.0 * m.mu * e;
}

// P-wave speed sqrt((lambda + 2 mu) / rho).
QDEMSPH_HD double p_wave_speed(const Material& m) {
  return sqrt((m.lambda + 2 * m.mu) / m.density);
}

struct StressResult {
  Mat3 P;                 // first Piola-Kirchhoff stress, elastic + viscous
  Mat3 P_elastic;         // elastic part alone
  double energy_density;  // W per reference volume
  double dissipation;     // viscous power per reference volume, P_v : Fdot >= 0
};

QDEMSPH_HD StressResult material_stress(const Material& m, const Mat3& F, const Mat3& Fdot) {
  StressResult r;
  const Mat3 I = Mat3::identity();
  if (m.law == 0) {
    const Mat3 eps = sym(F) - I;
    const Mat3 sigma = hooke(m, eps);
    const Mat3 epsdot = sym(Fdot);
    const Mat3 sigma_v = m.visc_ratio * hooke(m, epsdot);
    r.P_elastic = sigma;
    r.P = sigma + sigma_v;
    r.energy_density = 0.5 * ddot(sigma, eps);
    r.dissipation = ddot(sigma_v, epsdot);
  } else {
    const Mat3 E = 0.5 * (transpose(F) * F - I);
    const Mat3 S = hooke(m, E);
    const Mat3 Edot = sym(transpose(F) * Fdot);
    const Mat3 S_v = m.visc_ratio * hooke(m, Edot);
    r.P_elastic = F * S;
    r.P = F * (S + S_v);
    const double trE = trace(E);
    r.energy_density = 0.5 * m.lambda * trE * trE + m.mu * ddot(E, E);
    r.dissipation = ddot(S_v, Edot);
  }
  return r;
}

// Cauchy stress sigma = P F^T / det F (for the linear law P is already sigma).
QDEMSPH_HD Mat3 cauchy_stress(const Material& m, const Mat3& P, const Mat3& F) {
  if (m.law == 0) return P;
  return (1.0 / det(F)) * (P * transpose(F));
}

QDEMSPH_HD double von_mises(const Mat3& s) {
  const double a = s.m[0][0] - s.m[1][1], b = s.m[1][1] - s.m[2][2], c = s.m[2][2] - s.m[0][0];
  const double sh = s.m[0][1] * s.m[0][1] + s.m[1][2] * s.m[1][2] + s.m[0][2] * s.m[0][2];
  return sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * sh);
}

}  // namespace qdemsph
