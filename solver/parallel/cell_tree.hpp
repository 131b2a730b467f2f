// Cells refined as a tree where particles crowd (METHOD.md section 4), so that no cell
// costs more than a threshold and the partition (partition.hpp) can cut the curve evenly.
//
// The domain is a cube of side^3 finest cells, side = b^order (b = 2 for Morton and
// Hilbert, 3 for Peano). A tree cell of level l covers (b^(order - l))^3 finest cells; its
// finest keys form one contiguous segment [key, key + span) of the curve (sfc.hpp: keys are
// hierarchical), and its b^3 children (8, or 27 for Peano) are the b^3 equal sub-segments in
// curve order. So refining a cell keeps the order of every other cell, and the leaves,
// sorted by key, tile the domain along the curve. Costs are attached to finest keys (one
// item per vertex, tet, contact pair or SPH particle, weighted by its measured time).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "core/hd.hpp"
#include "core/vec.hpp"
#include "parallel/sfc.hpp"

namespace qdemsph {

// Maps positions to finest cells of a cubic grid [lo, lo + side * h)^3 and their keys.
// Positions outside are clamped to the boundary cells.
struct SfcGrid {
  Curve curve = Curve::Hilbert;
  int order = 1;  // side = curve_base(curve)^order
  Vec3 lo{0, 0, 0};
  double h = 1;  // finest cell size

  QDEMSPH_HD std::uint32_t side() const {  // a shift, not a loop, on the key's hot path
    return curve == Curve::Peano ? sfc_pow3(order) : 1u << order;
  }
  QDEMSPH_HD std::uint32_t coord(double p, double p0) const {
    const double c = std::floor((p - p0) / h);
    const double top = static_cast<double>(side() - 1);
    return static_cast<std::uint32_t>(!(c > 0) ? 0 : (c > top ? top : c));  // NaN: cell 0
  }
  QDEMSPH_HD std::uint64_t key(Vec3 p) const {
    return sfc_key(curve, coord(p.x, lo.x), coord(p.y, lo.y), coord(p.z, lo.z), order);
  }
};

struct TreeCell {
  std::uint64_t key = 0;              // first finest key of the cell's curve segment
  std::uint64_t span = 1;             // finest cells covered: (b^(order - level))^3
  std::uint32_t x = 0, y = 0, z = 0;  // coordinates on the grid of its level
  std::int32_t level = 0;
  double cost = 0;
};

// The leaves of the refined tree, in curve order, tiling the whole domain (empty leaves
// included, so that any position has an owner). A cell is split into its b^3 children when
// its cost exceeds max_cost and its level is below `order`; cells above min_level are always
// split. item_keys: finest keys (any order); item_cost: one cost per item (>= 0).
std::vector<TreeCell> refine_cells(Curve curve, int order, std::span<const std::uint64_t> item_keys,
                                   std::span<const double> item_cost, double max_cost,
                                   int min_level = 0);

// The same refinement with the costs from a callback, level by level: cost_of(keys, spans,
// costs) fills the cost of every cell [key, key + span) of one tree level in one call, so
// that a distributed caller (parallel/balance.hpp) sums the ranks' local costs with one
// reduction per level instead of gathering every item. cost_of must return the same values on
// every rank (the tree is then the same everywhere).
using CellCostFn =
    std::function<void(std::span<const std::uint64_t> keys, std::span<const std::uint64_t> spans,
                       std::span<double> costs)>;
std::vector<TreeCell> refine_cells_by(Curve curve, int order, double max_cost, int min_level,
                                      const CellCostFn& cost_of);

// Index of the leaf whose segment contains a finest key.
inline std::size_t find_leaf(std::span<const TreeCell> leaves, std::uint64_t key) {
  const auto it = std::upper_bound(leaves.begin(), leaves.end(), key,
                                   [](std::uint64_t k, const TreeCell& c) { return k < c.key; });
  return static_cast<std::size_t>(it - leaves.begin()) - 1;
}

}  // namespace qdemsph
