// SPH smoothing kernel: Wendland C2 in 3D (Wendland 1995; Dehnen & Aly 2012 notation with
// support radius 2h).
//
//   W(r, h) = aD (1 - q/2)^4 (2q + 1),  q = r/h in [0, 2],  aD = 21 / (16 pi h^3)
//   grad_i W(x_i - x_j) = (x_i - x_j) F(r),  F(r) = -5 aD (1 - q/2)^3 / h^2   (F <= 0)
//
// F is smooth at r = 0, so the gradient needs no division by r. Both functions are odd/even in
// r exactly in floating point (they depend on r only through r^2 and the vector r_ij), which the
// exact momentum conservation of the pair forces relies on.
#pragma once

#include <cmath>

#include "core/hd.hpp"
#include "core/vec.hpp"

namespace qdemsph {

struct WendlandC2 {
  double h = 1;         // smoothing length [m]
  double inv_h = 1;     // 1/h
  double aD = 0;        // 21 / (16 pi h^3)
  double support2 = 4;  // (2h)^2

  static WendlandC2 make(double h) {
    WendlandC2 k;
    k.h = h;
    k.inv_h = 1.0 / h;
    k.aD = 21.0 / (16.0 * M_PI * h * h * h);
    k.support2 = 4.0 * h * h;
    return k;
  }
  QDEMSPH_HD double support() const { return 2.0 * h; }

  QDEMSPH_HD double w(double r2) const {
    if (r2 >= support2) return 0.0;
    const double q = sqrt(r2) * inv_h;
    const double a = 1.0 - 0.5 * q;
    const double a2 = a * a;
    return aD * a2 * a2 * (2.0 * q + 1.0);
  }
  // F(r) with grad_i W = r_ij F; 0 outside the support.
  QDEMSPH_HD double f(double r2) const {
    if (r2 >= support2) return 0.0;
    const double q = sqrt(r2) * inv_h;
    const double a = 1.0 - 0.5 * q;
    return -5.0 * aD * a * a * a * inv_h * inv_h;
  }
  QDEMSPH_HD Vec3 grad(Vec3 rij) const { return f(norm2(rij)) * rij; }
};

}  // namespace qdemsph
