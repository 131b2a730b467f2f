// DEM contact law between two virtual particles of diameter D_DEM (METHOD.md section 3):
// linear normal spring-dashpot and a tangential spring with a Coulomb limit and history.
//
//   delta = D_DEM - d  (overlap; d = signed distance of the two surface points along n)
//   F_n = max(0, k_n delta - c_n v_n),  v_n = v_rel . n,  c_n = 2 zeta sqrt(m_eff k_n),
//   zeta = -ln e / sqrt(pi^2 + ln^2 e)  (e: coefficient of restitution)
//   xi  <- P_n xi + v_t dt  (tangential spring, kept in the current tangent plane, rescaled
//                            to keep its length when the plane rotates)
//   F_t = -k_t xi - c_t v_t,  c_t = 2 zeta sqrt(m_eff k_t);  if |F_t| > mu F_n:
//   F_t <- mu F_n F_t / |F_t|,  xi <- -(F_t + c_t v_t) / k_t   (sliding)
// The force returned acts on side 1 (v_rel = v_1 - v_2, n from side 2 towards side 1);
// side 2 receives the opposite. ~70 flops.
//
// Energy (contact_energy, for the budget in physics/energies.hpp). The power of the contact
// force on the bodies is F . v_rel (the weights that spread F over the vertices also average
// their velocities into v_1, v_2). Split F = k_n delta n + h: the normal spring is a potential,
// E_n = 1/2 k_n delta^2; h (tangential spring, dashpots, the cut-off while F_n is clamped at
// zero) does work that the tangential spring stores, E_t = 1/2 k_t |xi|^2, or dissipates.
// Velocity Verlet applies each evaluation's force over two half steps, so the work of h over a
// step is the trapezoid of its values at the step's ends times v at the half step:
//   stored      E = 1/2 k_n delta^2 + 1/2 k_t |xi|^2
//   dissipated  1/2 k_t (|xi_old|^2 - |xi|^2) - (h_old + h) / 2 . v_rel dt
// with h_old the previous evaluation's h of the same feature pair (0 for a new touch): sticking
// without damping this is 0, the dashpots give (c_n v_n^2 + c_t |v_t|^2) dt, sliding mu F_n
// times the slip. The budget then closes to second order in dt. A touch that ends leaves its
// spring energy and the second half of its last h's work; the contact stage adds both.
#pragma once

#include <cstdint>

#include "core/vec.hpp"

namespace qdemsph {

struct ContactLaw {
  double kn = 0;    // normal stiffness [N/m]
  double kt = 0;    // tangential stiffness [N/m]
  double zeta = 0;  // damping ratio from the restitution coefficient
  double mu = 0;    // Coulomb friction coefficient
};

// Damping ratio of a linear spring-dashpot that rebounds with restitution e in (0, 1].
QDEMSPH_HD double damping_ratio_from_restitution(double e) {
  if (!(e > 0)) return 1.0;
  if (e >= 1) return 0.0;
  const double l = log(e);
  return -l / sqrt(3.14159265358979323846 * 3.14159265358979323846 + l * l);
}

struct ContactForce {
  Vec3 f;         // on side 1
  Vec3 xi;        // updated tangential spring
  double fn = 0;  // normal force magnitude
};

// The old spring turned into the tangent plane of n, keeping its length.
QDEMSPH_HD Vec3 rotate_spring(Vec3 xi_old, Vec3 n) {
  const double l0 = norm(xi_old);
  Vec3 xi = xi_old - dot(xi_old, n) * n;
  const double l1 = norm(xi);
  return l1 > 0 ? (l0 / l1) * xi : xi;
}

QDEMSPH_HD ContactForce contact_force(const ContactLaw& law, Vec3 n, double delta, Vec3 v_rel,
                                      Vec3 xi_old, double dt, double m_eff) {
  ContactForce r;
  const double vn = dot(v_rel, n);
  const Vec3 vt = v_rel - vn * n;
  const double cn = 2.0 * law.zeta * sqrt(m_eff * law.kn);
  double fn = law.kn * delta - cn * vn;
  fn = fn > 0 ? fn : 0.0;
  Vec3 xi = rotate_spring(xi_old, n) + dt * vt;
  const double ct = 2.0 * law.zeta * sqrt(m_eff * law.kt);
  Vec3 ft = -law.kt * xi - ct * vt;
  const double ftn = norm(ft), lim = law.mu * fn;
  if (ftn > lim) {
    ft = ftn > 0 ? (lim / ftn) * ft : Vec3{};
    xi = law.kt > 0 ? (-1.0 / law.kt) * (ft + ct * vt) : Vec3{};
  }
  r.f = fn * n + ft;
  r.xi = xi;
  r.fn = fn;
  return r;
}

struct ContactEnergy {
  double stored = 0;      // 1/2 k_n delta^2 + 1/2 k_t |xi|^2 [J]
  double stored_t = 0;    // the tangential part, dropped if the touch ends [J]
  double dissipated = 0;  // over this step [J]
  Vec3 h;                 // F - k_n delta n on side 1: the next step's h_old [N]
};

// xi_old, h_old: the feature pair's spring and h of the previous step (history); xi: the spring
// kept after this step; cf: contact_force's result for these arguments.
QDEMSPH_HD ContactEnergy contact_energy(const ContactLaw& law, Vec3 n, double delta, Vec3 v_rel,
                                        Vec3 xi_old, Vec3 xi, Vec3 h_old, const ContactForce& cf,
                                        double dt) {
  ContactEnergy e;
  e.h = cf.f - (law.kn * delta) * n;
  e.stored_t = 0.5 * law.kt * norm2(xi);
  e.stored = 0.5 * law.kn * delta * delta + e.stored_t;
  e.dissipated = (0.5 * law.kt * norm2(xi_old) - e.stored_t) - 0.5 * dot(h_old + e.h, v_rel) * dt;
  return e;
}

}  // namespace qdemsph
