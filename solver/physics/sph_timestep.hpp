// WCSPH time-step limits (Monaghan 1992; Morris et al. 1997; Adami et al. 2012):
//   CFL:     dt <= 0.25 h / (c_max + |v|_max)
//   force:   dt <= 0.25 sqrt(h / |a|_max)
//   viscous: dt <= 0.125 h^2 / nu                (laminar viscosity only)
#pragma once

#include <cmath>
#include <limits>

namespace qdemsph {

struct SphDtLimits {
  double cfl = std::numeric_limits<double>::infinity();
  double force = std::numeric_limits<double>::infinity();
  double viscous = std::numeric_limits<double>::infinity();
  double min() const { return std::fmin(cfl, std::fmin(force, viscous)); }
};

inline SphDtLimits sph_dt_limits(double h, double c_max, double v_max, double a_max, double nu) {
  SphDtLimits d;
  d.cfl = 0.25 * h / (c_max + v_max);
  if (a_max > 0) d.force = 0.25 * std::sqrt(h / a_max);
  if (nu > 0) d.viscous = 0.125 * h * h / nu;
  return d;
}

}  // namespace qdemsph
