// The band around a rank's items (docs/parallel.md items 4 and "Fluid"): a fixed grid of
// cells of width `band`; every point within two band widths of a point of a cell lies in the
// 5^3 cells around it, so the ranks with items in those cells are all that may need a copy.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/vec.hpp"

namespace qdemsph {

// Band cells: a fixed grid of width `band` anchored at the origin; coordinates packed in 21
// bits each (offset by 2^20; the grid spans +-2^20 cells).
inline std::uint64_t band_key(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
  constexpr std::int64_t off = std::int64_t{1} << 20, top = (std::int64_t{1} << 21) - 1;
  auto c = [&](std::int64_t i) {
    return static_cast<std::uint64_t>(std::clamp(i + off, std::int64_t{0}, top));
  };
  return (c(ix) << 42) | (c(iy) << 21) | c(iz);
}

struct BandCell {
  std::int64_t i[3];
};

inline BandCell band_cell(Vec3 p, double band) {
  // Clamped before the conversion (a blown-up run's NaN or huge values stay defined; the
  // run-time checks report them).
  auto c = [&](double v) {
    const double q = std::floor(v / band);
    return static_cast<std::int64_t>(q > -2e6 ? (q < 2e6 ? q : 2e6) : -2e6);
  };
  return {{c(p.x), c(p.y), c(p.z)}};
}

// The 5^3 cells within two cells of c: any point within 2 band widths of a point of c.
template <class F>
void for_each_band_neighbour(const BandCell& c, F f) {
  for (int a = -2; a <= 2; ++a)
    for (int b = -2; b <= 2; ++b)
      for (int d = -2; d <= 2; ++d) f(band_key(c.i[0] + a, c.i[1] + b, c.i[2] + d));
}

}  // namespace qdemsph
