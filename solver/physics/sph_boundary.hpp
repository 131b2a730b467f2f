// Wall (dummy) particle pressure by extrapolation from the fluid (Adami, Hu & Adams 2012,
// J. Comput. Phys. 231, eq. 27):
//
//   p_w = ( sum_f p_f W_wf + (g - a_w) . sum_f rho_f (x_w - x_f) W_wf ) / sum_f W_wf
//   rho_w = rho(p_w) by the inverse equation of state
//
// a_w is the wall's acceleration (0 for fixed walls). A wall particle with no fluid neighbour
// keeps p = 0, rho = rho0. The accumulator is summed over the fluid neighbours, then finished.
#pragma once

#include "core/hd.hpp"
#include "core/vec.hpp"
#include "physics/sph_eos.hpp"
#include "physics/sph_kernel.hpp"

namespace qdemsph {

struct AdamiSum {
  double pw = 0;  // sum p_f W
  Vec3 rw{};      // sum rho_f (x_w - x_f) W
  double w = 0;   // sum W
};

QDEMSPH_HD void adami_add(AdamiSum& s, const WendlandC2& k, Vec3 xw, Vec3 xf, double pf,
                          double rhof) {
  const Vec3 r = xw - xf;
  const double W = k.w(norm2(r));
  s.pw += pf * W;
  s.rw += (rhof * W) * r;
  s.w += W;
}

// Wall pressure; clipped at 0 from below (no suction on walls, as Adami et al. do at free
// surfaces).
QDEMSPH_HD double adami_pressure(const AdamiSum& s, Vec3 gravity, Vec3 wall_acc) {
  if (s.w <= 0.0) return 0.0;
  const double p = (s.pw + dot(gravity - wall_acc, s.rw)) / s.w;
  return p > 0.0 ? p : 0.0;
}

}  // namespace qdemsph
