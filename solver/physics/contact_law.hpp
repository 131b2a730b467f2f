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

QDEMSPH_HD ContactForce contact_force(const ContactLaw& law, Vec3 n, double delta, Vec3 v_rel,
                                      Vec3 xi_old, double dt, double m_eff) {
  ContactForce r;
  const double vn = dot(v_rel, n);
  const Vec3 vt = v_rel - vn * n;
  const double cn = 2.0 * law.zeta * sqrt(m_eff * law.kn);
  double fn = law.kn * delta - cn * vn;
  fn = fn > 0 ? fn : 0.0;
  // Rotate the old spring into the current tangent plane, keeping its length.
  const double l0 = norm(xi_old);
  Vec3 xi = xi_old - dot(xi_old, n) * n;
  const double l1 = norm(xi);
  if (l1 > 0) xi = (l0 / l1) * xi;
  xi += dt * vt;
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

}  // namespace qdemsph
