// The QDEM element: nodal forces of one linear tetrahedron (METHOD.md section 2).
//
//   dX = [X1-X0, X2-X0, X3-X0] (reference, inverse precomputed), dx likewise (current),
//   F = dx dX^-1 (eq. 1), Fdot = dv dX^-1, P = P(F, Fdot) from material.hpp,
//   H = -V0 P dX^-T,  f_k = column k-1 of H for k = 1..3,  f_0 = -(f_1 + f_2 + f_3).
// This is f_i = -V T grad N_i written in the reference configuration; it equals -dE/dx_i
// for the elastic part, so forces sum to zero and (SVK) vanish under rigid motion.
// Cost per tet: reads 24 doubles (x, v of 4 vertices) + 10 (dX^-1, V0), ~400 flops.
#pragma once

#include "core/vec.hpp"
#include "physics/material.hpp"

namespace qdemsph {

struct ElementForces {
  Vec3 f[4];
  Mat3 F;
  StressResult stress;
};

QDEMSPH_HD Mat3 edge_matrix(const Vec3 p[4]) {
  return Mat3::from_columns(p[1] - p[0], p[2] - p[0], p[3] - p[0]);
}

QDEMSPH_HD ElementForces tet_forces(const Material& m, const Vec3 x[4], const Vec3 v[4],
                                    const Mat3& dX_inv, double V0) {
  ElementForces r;
  r.F = edge_matrix(x) * dX_inv;
  const Mat3 Fdot = edge_matrix(v) * dX_inv;
  r.stress = material_stress(m, r.F, Fdot);
  const Mat3 H = (-V0) * (r.stress.P * transpose(dX_inv));
  r.f[1] = H.col(0);
  r.f[2] = H.col(1);
  r.f[3] = H.col(2);
  r.f[0] = -(r.f[1] + r.f[2] + r.f[3]);
  return r;
}

// Smallest altitude of a tet: 3 V / largest face area.
QDEMSPH_HD double min_altitude(const Vec3 p[4]) {
  const double V = fabs(det(edge_matrix(p))) / 6.0;
  double amax = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec3 a = p[(k + 1) % 4], b = p[(k + 2) % 4], c = p[(k + 3) % 4];
    const double area = 0.5 * norm(cross(b - a, c - a));
    amax = area > amax ? area : amax;
  }
  return 3.0 * V / amax;
}

// Stability limit of explicit central differences for one tet: l_min / c_p, reduced for
// Kelvin-Voigt damping by the factor sqrt(1 + z^2) - z with z = zeta at the highest
// frequency omega_max = 2 c_p / l_min (BENCHMARKS.md section 3).
QDEMSPH_HD double tet_critical_dt(const Material& m, double l_min) {
  const double cp = p_wave_speed(m);
  const double dt = l_min / cp;
  const double z = m.visc_ratio * cp / l_min;
  return dt * (sqrt(1.0 + z * z) - z);
}

}  // namespace qdemsph
