// Candidate pairs from a cell list in two passes (count, scan, fill), written once over an
// execution space; the cell list is neighbor/cell_grid.hpp's counting sort.
//
// A pair (i, j), i < j, is a candidate when the bounding spheres (centre c, radius r) grown
// by `gap` overlap, |c_i - c_j| <= r_i + r_j + gap, and accept(i, j) holds (e.g. different
// bodies). With cell width L >= 2 max r + gap (report eq. 9-10: L_cell >= D_max + D_DEM,
// D_max = 2 max_j |x_j - centroid|) every such pair lies in adjacent cells, so only the 27
// neighbouring cells are searched. Output: start[i] .. start[i + 1] index `second`, the
// partners j > i of item i, in a fixed order (cells by key, items by index): deterministic;
// first[q] = i for each pair q of item i, so that a loop may run one thread per pair (the
// contact narrow phase: items' pair counts are uneven, a thread per item idles most of a GPU
// warp). Cost: count and fill each read 4 doubles per visited item.
#pragma once

#include <cstdint>

#include "core/memory.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/scan.hpp"

namespace qdemsph {

// A grid over [lo, hi] with cells >= min_cell, coarsened until it has at most max_cells.
inline CellGrid cover_capped(Vec3 lo, Vec3 hi, double min_cell, std::int64_t max_cells) {
  CellGrid g = CellGrid::cover(lo, hi, min_cell);
  while (g.count() > max_cells) g = CellGrid::cover(lo, hi, g.cell * 1.5);
  return g;
}

template <class Exec>
class CandidatePairs {
  static constexpr Space S = Exec::space;

 public:
  template <class Accept>
  std::int64_t build(const CellList<Exec>& cells, Vec3CView c, View<const double> r, double gap,
                     std::int64_t n, Accept accept) {
    if (start_.size() < n + 1) start_.resize(n + 1);
    const auto start = start_.view();
    const CellGrid g = cells.grid();
    const std::int64_t* cs = cells.start().p;
    const auto order = cells.order();
    auto visit = QDEMSPH_LAMBDA(std::int64_t i, int* out)->std::int64_t {
      const Vec3 ci = c[i];
      const double ri = r[i];
      std::int64_t k = 0;
      for_each_near(g, cs, ci, [&](std::int64_t q) {
        const std::int64_t j = order[q];
        if (j <= i) return;
        const double lim = ri + r[j] + gap;
        if (norm2(c[j] - ci) > lim * lim) return;
        if (!accept(i, j)) return;
        if (out) out[k] = static_cast<int>(j);
        ++k;
      });
      return k;
    };
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t i) { start[i] = visit(i, nullptr); });
    const std::int64_t total = exclusive_scan(Exec{}, start, n);
    if (second_.size() < total) second_.resize(total + total / 4 + 16);
    if (first_.size() < total) first_.resize(total + total / 4 + 16);
    const auto second = second_.view();
    const auto first = first_.view();
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t i) {
          visit(i, second.p + start[i]);
          for (std::int64_t q = start[i]; q < start[i + 1]; ++q) first[q] = static_cast<int>(i);
        });
    n_ = n;
    total_ = total;
    return total;
  }

  View<const std::int64_t> start() const { return {start_.cview().p, n_ + 1}; }
  View<const int> second() const { return {second_.cview().p, total_}; }
  View<const int> first() const { return {first_.cview().p, total_}; }
  std::int64_t size() const { return total_; }
  void clear() { n_ = total_ = 0; }  // no pairs; the storage stays
  std::size_t bytes() const { return start_.bytes() + second_.bytes() + first_.bytes(); }

 private:
  std::int64_t n_ = 0, total_ = 0;
  Buffer<std::int64_t> start_{S};
  Buffer<int> second_{S}, first_{S};
};

}  // namespace qdemsph
