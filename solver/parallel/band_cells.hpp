// The band around a rank's items (docs/parallel.md items 4 and "Fluid"): a fixed grid of
// cells of width `band`; every point within two band widths of a point of a cell lies in the
// 5^3 cells around it, so the ranks with items in those cells are all that may need a copy.
// BandGrid adds a periodic z (the SPH fluid's `periodic_z`): the cells wrap across the seam.
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

// The cell of a key (band_key's inverse for unclamped coordinates).
inline BandCell band_cell_of_key(std::uint64_t key) {
  constexpr std::int64_t off = std::int64_t{1} << 20;
  return {{static_cast<std::int64_t>(key >> 42) - off,
           static_cast<std::int64_t>((key >> 21) & 0x1fffff) - off,
           static_cast<std::int64_t>(key & 0x1fffff) - off}};
}

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

// Band cells, periodic in z over [z0, z0 + period) when period > 0: then nz = floor(period /
// band) (at least 1) cells of width period / nz >= band tile the period and z indices wrap
// (mod nz), so the 5^3 cells around a cell still hold every point within two band widths of
// it, across the seam too (with nz < 5 a cell appears more than once among them).
struct BandGrid {
  double band = 1;
  double z0 = 0, band_z = 1;
  std::int64_t nz = 0;  // periodic: cells per period; 0: not periodic

  explicit BandGrid(double width, double z_0 = 0, double period = 0)
      : band(width), z0(z_0), band_z(width) {
    if (!(period > 0)) return;
    nz = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::floor(period / width)));
    band_z = period / static_cast<double>(nz);
  }
  BandCell cell(Vec3 p) const {
    BandCell c = band_cell(p, band);
    if (nz > 0) c.i[2] = wrap(band_cell(Vec3{0, 0, p.z - z0}, band_z).i[2]);
    return c;
  }
  template <class F>
  void for_each_neighbour(const BandCell& c, F f) const {
    if (nz == 0) return for_each_band_neighbour(c, f);
    for (int a = -2; a <= 2; ++a)
      for (int b = -2; b <= 2; ++b)
        for (int d = -2; d <= 2; ++d) f(band_key(c.i[0] + a, c.i[1] + b, wrap(c.i[2] + d)));
  }
  // The lower coordinate of cells i along axis a (i unwrapped).
  double lo(std::int64_t i, int a) const {
    return a == 2 && nz > 0 ? z0 + static_cast<double>(i) * band_z : static_cast<double>(i) * band;
  }

 private:
  std::int64_t wrap(std::int64_t i) const { return ((i % nz) + nz) % nz; }
};

}  // namespace qdemsph
