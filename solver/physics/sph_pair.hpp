// WCSPH pair interaction between particles i and j (fluid-fluid or fluid-wall): momentum,
// viscosity, continuity and density diffusion. Pure functions of two particles' values.
//
// Momentum (Monaghan 1992, symmetric form), force on i from j:
//   F_ij = -m_i m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad_i W_ij  [+ laminar term]
// Artificial viscosity (Monaghan 1992), only for approaching pairs (v_ij . r_ij < 0):
//   Pi_ij = -alpha cbar h mu_ij / rhobar,  mu_ij = v_ij . r_ij / (r^2 + eta^2),  eta = 0.1 h
//         = -alpha (c_i + c_j) h (v_ij . r_ij) / ((r^2 + eta^2)(rho_i + rho_j))  (one division)
// Each particle's p/rho^2 is computed once per step (PairState::pr), not once per pair.
// Laminar viscosity (Lo & Shao 2002, as in DualSPHysics), nu kinematic [m^2/s]:
//   F_ij += m_i m_j 4 nu (r_ij . grad_i W_ij) / ((rho_i + rho_j)(r^2 + eta^2)) v_ij
// Every factor is symmetric in (i, j) and r_ij, v_ij change sign exactly: F_ji = -F_ij bit for
// bit, so momentum is conserved to summation round-off whatever order the pairs are visited.
// Fluid-boundary pairs use sph_boundary_force (below); the boundary gets its exact negative.
//
// Continuity: drho_i/dt = sum_j m_j v_ij . grad_i W_ij
// delta-SPH density diffusion (Molteni & Colagrossi 2009) with the hydrostatic correction of
// Fourtakas et al. 2019 (diffuse only the dynamic part of the density difference):
//   D_i = delta h c0 sum_j V_j 2 (rho_j - rho_i - drho^H_ji) (r_ji . grad_i W_ij) / (r^2 + eta^2)
//   drho^H_ji = rho0 g . (x_j - x_i) / c0^2          (linearised Tait, hydrostatic)
// Diffusion is applied between fluid particles only (wall densities come from Adami).
#pragma once

#include "core/hd.hpp"
#include "core/vec.hpp"
#include "physics/sph_eos.hpp"
#include "physics/sph_kernel.hpp"

namespace qdemsph {

enum class SphViscosity : int { Artificial = 0, Laminar = 1 };

struct SphParams {
  WendlandC2 kernel;
  TaitEos eos;
  SphViscosity visc_type = SphViscosity::Artificial;
  double alpha = 0.01;         // artificial viscosity coefficient
  double nu = 0;               // laminar kinematic viscosity [m^2/s]
  double delta = 0.1;          // density diffusion coefficient (0: off)
  bool wall_viscosity = true;  // viscosity also between fluid and wall (no-slip-like)
  Vec3 gravity{0, 0, 0};
};

// A particle's state as a pair interaction reads it: pr = p / rho^2 (its sign is p's).
struct PairState {
  Vec3 x, v;
  double rho, m, pr;
};
QDEMSPH_HD PairState pair_state(Vec3 x, Vec3 v, double rho, double p, double m) {
  return {x, v, rho, m, p / (rho * rho)};
}

// The pair force for a given pressure coefficient s (p_i/rho_i^2 + p_j/rho_j^2 or the boundary
// form below); adds the viscosity term when `viscous`.
QDEMSPH_HD Vec3 sph_pair_force_with(const SphParams& P, const PairState& a, const PairState& b,
                                    double s, bool viscous) {
  const Vec3 r = a.x - b.x;
  const double r2 = norm2(r);
  const double F = P.kernel.f(r2);
  if (F == 0.0) return Vec3{};
  const double eta2 = 0.01 * P.kernel.h * P.kernel.h;
  const Vec3 vij = a.v - b.v;
  Vec3 lam{};
  if (viscous) {
    const double vr = dot(vij, r);
    if (P.visc_type == SphViscosity::Artificial) {
      if (vr < 0.0) {
        const double c2 = P.eos.sound_speed(a.rho) + P.eos.sound_speed(b.rho);
        s -= P.alpha * c2 * P.kernel.h * vr / ((r2 + eta2) * (a.rho + b.rho));
      }
    } else {
      const double k = 4.0 * P.nu * (r2 * F) / ((a.rho + b.rho) * (r2 + eta2));
      lam = ((a.m * b.m) * k) * vij;
    }
  }
  return ((-(a.m * b.m) * s) * F) * r + lam;
}

// Force on fluid particle i from fluid particle j [N] (without gravity). `viscous`: include the
// viscosity term.
QDEMSPH_HD Vec3 sph_pair_force(const SphParams& P, const PairState& a, const PairState& b,
                               bool viscous) {
  return sph_pair_force_with(P, a, b, a.pr + b.pr, viscous);
}

// Force on fluid particle f from boundary particle w (wall or body marker, pressure p_w >= 0
// from the Adami extrapolation) [N]; the boundary receives exactly its negative.
//   s = p_f^+/rho_f^2 + p_w/rho_w^2  when p_w > 0 (a wet boundary particle)
//   s = 0                             when p_w = 0 (a dry one)
// p_f^+ = max(p_f, 0): a wall only pushes, so fluid in tension (after a violent impact, in a
// thin jet) is not drawn into the wall layers. A dry boundary particle (its extrapolated
// pressure <= 0: it lies above the local free surface, e.g. the tank wall above the water line)
// stands for air: it must not complete the kernel of the fluid beside it, or the p_f term
// pushes the surface layer down along the wall (in the quasi-2D hydrostatic tank that carried
// 0.8 % of the weight to the floor). Viscosity as between fluid particles.
QDEMSPH_HD Vec3 sph_boundary_force(const SphParams& P, const PairState& f, const PairState& w,
                                   bool viscous) {
  const double s = w.pr > 0.0 ? (f.pr > 0.0 ? f.pr : 0.0) + w.pr : 0.0;
  return sph_pair_force_with(P, f, w, s, viscous);
}

// drho_i/dt contribution from j: continuity m_j v_ij . grad_i W_ij, plus the delta-SPH diffusion
// term when j is a fluid particle (`diffuse`). One kernel evaluation for both.
QDEMSPH_HD double sph_density_rate(const SphParams& P, const PairState& a, const PairState& b,
                                   bool diffuse) {
  const Vec3 r = a.x - b.x;
  const double r2 = norm2(r);
  const double F = P.kernel.f(r2);
  double d = b.m * F * dot(a.v - b.v, r);
  if (diffuse && P.delta != 0.0) {
    const double c0 = P.eos.c0;
    const double drho_h = P.eos.rho0 * dot(P.gravity, b.x - a.x) / (c0 * c0);
    const double eta2 = 0.01 * P.kernel.h * P.kernel.h;
    // (x_j - x_i) . grad_i W = -r^2 F >= 0
    d += P.delta * P.kernel.h * c0 * b.m * 2.0 * (b.rho - a.rho - drho_h) * (-r2 * F) /
         (b.rho * (r2 + eta2));
  }
  return d;
}

}  // namespace qdemsph
