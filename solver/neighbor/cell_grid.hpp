// Uniform cell grid and counting-sort cell list (count, exclusive scan, fill), written for the
// SPH stage and meant to be shared with the contact broad phase.
//
// Layout: after build(), particles are described by `order` (particle indices sorted by cell,
// stable: increasing index within a cell) and `start` (ncells + 1 offsets): the particles of cell
// c are order[start[c] .. start[c+1]). Callers that keep their arrays sorted by cell (the SPH
// stage re-sorts every step) use start directly as ranges into their own arrays.
//
// Positions outside the grid box are clamped into the border cells. Clamping is non-expansive,
// so two points closer than one cell width still land in the same or adjacent cells: the search
// stays exact, it only gets slower for far-away particles.
//
// Periodic in z (period_z > 0, the SPH fluid's `periodic_z`): the n[2] cells tile the period
// from origin.z exactly and z cell coordinates wrap. A search around p walks unwrapped cells
// zz (any integer; cell zz mod n[2]) and sees each particle j of such a cell at image(x_j, zz),
// its position shifted by whole periods into that cell: every image within the search range
// once, for any number of cells across the period.
//
// The cell-key pass is a for_each (host or device); the sort is sort_by_key: a serial counting
// sort here (HostExec), a stable radix sort on the device in neighbor_cuda.cuh (CudaExec). Both
// give the same order and offsets, so neighbour sums run in the same order on either backend.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/exec_host.hpp"
#include "core/hd.hpp"
#include "core/memory.hpp"
#include "core/radix_sort.hpp"
#include "core/vec.hpp"

namespace qdemsph {

struct CellGrid {
  Vec3 origin{0, 0, 0};
  double cell = 1, inv_cell = 1;
  int n[3] = {1, 1, 1};
  // A window of a larger grid (window()): cells [first, first + n) of a grid of `full` cells
  // per axis; coordinates are those of the full grid (clamped to it) less `first`, so a cell
  // has the same place in both and neighbour walks visit cells in the same order.
  int first[3] = {0, 0, 0};
  int full[3] = {1, 1, 1};

  double period_z = 0;  // > 0: periodic in z with this period

  // A grid covering [lo, hi] with cells of at least `min_cell`, periodic in z over
  // [z0, z0 + period_z] when period_z > 0 (cells then tile the period: cell = period / n[2]).
  static CellGrid cover(Vec3 lo, Vec3 hi, double min_cell, double z0, double period_z) {
    if (!(period_z > 0)) return cover(lo, hi, min_cell);
    const int nz = std::max(1, static_cast<int>(std::floor(period_z / min_cell)));
    CellGrid g = cover(lo, hi, period_z / nz);
    g.origin.z = z0;
    g.full[2] = g.n[2] = nz;
    g.period_z = period_z;
    return g;
  }
  // A grid covering [lo, hi] with cells of at least `min_cell`.
  static CellGrid cover(Vec3 lo, Vec3 hi, double min_cell) {
    CellGrid g;
    g.origin = lo;
    g.cell = min_cell;
    g.inv_cell = 1.0 / min_cell;
    for (int a = 0; a < 3; ++a)
      g.full[a] = g.n[a] = std::max(1, static_cast<int>(std::ceil((hi[a] - lo[a]) / min_cell)));
    return g;
  }
  // The cells [lo, hi] (coordinates of this grid, inclusive) as a grid of their own.
  CellGrid window(const int lo[3], const int hi[3]) const {
    CellGrid g = *this;
    for (int a = 0; a < 3; ++a) {
      g.first[a] = first[a] + lo[a];
      g.n[a] = hi[a] - lo[a] + 1;
    }
    return g;
  }
  std::int64_t count() const { return std::int64_t(n[0]) * n[1] * n[2]; }
  QDEMSPH_HD int coord(double x, int a) const {
    const double o = a == 0 ? origin.x : (a == 1 ? origin.y : origin.z);
    int c = static_cast<int>(floor((x - o) * inv_cell));
    if (a == 2 && period_z > 0) {
      c %= n[2];
      return c < 0 ? c + n[2] : c;
    }
    c = c < 0 ? 0 : c;
    c = (c >= full[a] ? full[a] - 1 : c) - first[a];
    c = c < 0 ? 0 : c;
    return c >= n[a] ? n[a] - 1 : c;
  }
  // Periodic z: the unwrapped z cell of a position, and the image of x in unwrapped cell zz
  // (x itself when not periodic).
  QDEMSPH_HD int unwrapped_z(double z) const {
    return static_cast<int>(floor((z - origin.z) * inv_cell));
  }
  QDEMSPH_HD Vec3 image(Vec3 x, int zz) const {
    if (period_z > 0) x.z += ((zz - unwrapped_z(x.z)) / n[2]) * period_z;
    return x;
  }
  // Periodic z: the difference d of two positions moved by whole periods to its nearest image
  // (|d.z| <= period_z / 2); d itself when not periodic.
  QDEMSPH_HD Vec3 nearest(Vec3 d) const {
    if (period_z > 0) d.z -= period_z * floor(d.z / period_z + 0.5);
    return d;
  }
  // Periodic z: x moved by whole periods into [origin.z, origin.z + period_z).
  QDEMSPH_HD Vec3 wrap(Vec3 x) const {
    if (period_z > 0) x.z -= period_z * floor((x.z - origin.z) / period_z);
    return x;
  }
  QDEMSPH_HD std::int64_t key(int cx, int cy, int cz) const {
    return (std::int64_t(cz) * n[1] + cy) * n[0] + cx;
  }
  QDEMSPH_HD std::int64_t key_of(Vec3 p) const {
    return key(coord(p.x, 0), coord(p.y, 1), coord(p.z, 2));
  }
};

// Calls f(j) for every j in the 27 cells around p (ranges into arrays sorted by cell).
template <class F>
QDEMSPH_HD void for_each_near(const CellGrid& g, const std::int64_t* start, Vec3 p, F&& f) {
  const int cx = g.coord(p.x, 0), cy = g.coord(p.y, 1), cz = g.coord(p.z, 2);
  for (int z = cz - 1; z <= cz + 1; ++z) {
    if (z < 0 || z >= g.n[2]) continue;
    for (int y = cy - 1; y <= cy + 1; ++y) {
      if (y < 0 || y >= g.n[1]) continue;
      const std::int64_t row = g.key(0, y, z);
      const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx + 1 < g.n[0] ? cx + 1 : g.n[0] - 1;
      // Cells x0..x1 of one row are contiguous in the sorted order: one range.
      for (std::int64_t j = start[row + x0]; j < start[row + x1 + 1]; ++j) f(j);
    }
  }
}

// Stable sort of items [0, n) by key (keys[i] in [0, nkeys), n = keys.n): order[q] = the item
// at sorted position q (increasing index among equal keys), start[k] .. start[k + 1] = the
// positions of key k (start has nkeys + 1 entries). scratch: a work buffer the CUDA twin
// (neighbor_cuda.cuh) resizes; the host counting sort needs none.
inline void sort_by_key(HostExec, View<const std::int64_t> keys, std::int64_t nkeys,
                        View<std::int64_t> start, View<std::int64_t> order,
                        Buffer<std::int64_t>& /*scratch*/) {
  const std::int64_t n = keys.n;
  std::fill(start.p, start.p + nkeys + 1, std::int64_t{0});
  for (std::int64_t i = 0; i < n; ++i) ++start[keys[i] + 1];          // count
  for (std::int64_t c = 0; c < nkeys; ++c) start[c + 1] += start[c];  // exclusive scan
  for (std::int64_t i = 0; i < n; ++i) order[start[keys[i]]++] = i;   // fill: start[k] -> end of k
  for (std::int64_t c = nkeys; c > 0; --c) start[c] = start[c - 1];   // back to the beginnings
  start[0] = 0;
}

// The stable order of items [0, n) by key, for keys too wide for sort_by_key's offsets (keys[i]
// has only its low `bits` bits set, n = keys.n): order[q] = the item at sorted position q. A
// radix sort of (key, item) records on the host's threads (core/radix_sort.hpp, records kept
// per thread from one call to the next); the CUDA twin is CUB's (neighbor_cuda.cuh).
inline void sort_order(HostExec, View<const std::int64_t> keys, int bits, View<std::int64_t> order,
                       Buffer<std::int64_t>& /*scratch*/) {
  using Records = std::vector<std::pair<std::uint64_t, std::int64_t>>;
  thread_local Records kept, kept_tmp;
  Records &rec = kept, &tmp = kept_tmp;  // this thread's, named so for the loops' threads
  const std::int64_t n = keys.n;
  resize_for_overwrite(rec, static_cast<std::size_t>(n));
  for_each(HostExec{}, n, [&](std::int64_t i) { rec[i] = {std::uint64_t(keys[i]), i}; });
  radix_sort(rec, tmp, bits);
  for_each(HostExec{}, n, [&](std::int64_t q) { order[q] = rec[q].second; });
}

// Cell list over a Vec3 field in memory space S; keys, sort and offsets stay in that space.
template <class Exec>
class CellList {
  static constexpr Space S = Exec::space;

 public:
  void set_grid(const CellGrid& g) {
    grid_ = g;
    start_.resize(g.count() + 1);
  }
  const CellGrid& grid() const { return grid_; }
  // Builds order/start for positions x (n = x.n).
  void build(Vec3CView x) {
    const std::int64_t n = x.n;
    if (keys_.size() != n) {
      keys_.resize(n);
      order_.resize(n);
    }
    const auto k = keys_.view();
    const CellGrid g = grid_;
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t i) { k[i] = g.key_of(x[i]); });
    sort_by_key(Exec{}, keys_.cview(), grid_.count(), start_.view(), order_.view(), scratch_);
  }
  View<const std::int64_t> start() const { return start_.cview(); }
  View<const std::int64_t> order() const { return order_.cview(); }
  std::size_t bytes() const {
    return keys_.bytes() + start_.bytes() + order_.bytes() + scratch_.bytes();
  }

 private:
  CellGrid grid_;
  Buffer<std::int64_t> keys_{S}, start_{S}, order_{S}, scratch_{S};
};

}  // namespace qdemsph
