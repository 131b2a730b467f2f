// When a distributed layout's upkeep pays (docs/parallel.md items 4 and 8): a rank's ghost or
// layout rebuild runs on the host (on a GPU rank of two H200s ~0.13 s for 786 k tets, ~0.08 s
// for 1.1 M SPH particles, against millisecond steps), so the margins that decide how often one
// happens, and whether a re-cut is worth one, weigh the measured rebuild time. Pure functions, no
// MPI: the callers pass values that are the same on every rank (reduced), so every rank decides
// alike.
#pragma once

#include <algorithm>

namespace qdemsph {

// The margin (the bodies' contact slack, the fluid's ghost skin) for the next layout. When the
// last rebuild took more than a tenth of the stepping since the one before (`stepping_s`), the
// margin grows by the factor that would bring it to a tenth if the motion kept its speed (the
// stepping between rebuilds grows with the margin): at least 2, at most `step` a rebuild, and
// up to `most` in all. A wider band holds more ghosts and is rebuilt rarer; where ghosts are
// cheap (the bodies' contact vertices) one step to the factor saves the rebuilds that doubling
// rebuild after rebuild costs (~100 steps each on a GPU rank), where they carry work (the
// fluid's SPH passes) `step` 2 keeps the band from outgrowing what the run needs.
inline double widened_margin(double margin, double most, double rebuild_s, double stepping_s,
                             double step) {
  constexpr double kRebuildShare = 0.1;
  if (!(rebuild_s > kRebuildShare * stepping_s)) return margin;
  const double factor = std::clamp(rebuild_s / (kRebuildShare * stepping_s), 2.0, step);
  return std::min(factor * margin, most);
}
// Margins widen at most this factor over their first value. On a GPU rank a host-side rebuild
// costs tens of steps: at 4 x a flowing dam break still rebuilt its fluid layout every ~30
// steps, a quarter of its stepping (scaling/README.md); the 10 % rule, not this bound, should
// end the widening there. A wider band costs ghosts, whose refreshes the stepping time counts.
inline constexpr double kMaxMarginGrowth = 16;

// Whether cutting a partition again pays: the slowest rank's share above the mean, `excess`
// = 1 - mean / max of the owned cost, of each step of `step_s` seconds over the `every` steps
// until the next measurement saves more than a layout rebuild costs (`rebuild_s`).
inline bool recut_pays(double excess, double step_s, long every, double rebuild_s) {
  return excess * step_s * static_cast<double>(every) > rebuild_s;
}

// Whether the bodies' balancer cuts again (docs/parallel.md item 5), from a window's measured
// imbalance (max / mean - 1 of the ranks' busy seconds) and the partition model's (of the
// ranks' items at the weights fitted to those seconds). A new cut evens out the modelled cost,
// not the ranks' speeds or a window's noise, so both must exceed the threshold, and the smaller
// is what the cut saves (recut_pays, `step_s` the busiest rank's step). A threshold of 0 cuts at
// every measurement with any measured imbalance, as the tests need.
inline bool recut_due(double measured, double modelled, double threshold, double step_s, long every,
                      double rebuild_s) {
  if (!(measured > threshold)) return false;
  if (threshold == 0) return true;
  const double gain = std::min(measured, modelled);
  return gain > threshold && recut_pays(gain / (1 + gain), step_s, every, rebuild_s);
}

}  // namespace qdemsph
