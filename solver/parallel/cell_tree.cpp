#include "parallel/cell_tree.hpp"

#include <numeric>
#include <stdexcept>
#include <string>

namespace qdemsph {

std::vector<TreeCell> refine_cells_by(Curve curve, int order, double max_cost, int min_level,
                                      const CellCostFn& cost_of) {
  if (order < 1 || order > curve_max_order(curve))
    throw std::invalid_argument("refine_cells: order " + std::to_string(order) + " outside [1, " +
                                std::to_string(curve_max_order(curve)) + "]");
  const std::uint64_t b = curve_base(curve), nb = b * b * b;
  std::uint64_t side = 1;
  for (int i = 0; i < order; ++i) side *= b;
  // Breadth first: the cells of one level, their costs in one call, then the children of
  // those that are split. Children are the nb equal sub-segments of the parent's segment.
  std::vector<std::uint64_t> keys{0}, spans{side * side * side};
  std::vector<TreeCell> leaves;
  for (int level = 0; !keys.empty(); ++level) {
    std::vector<double> cost(keys.size(), 0.0);
    cost_of(keys, spans, cost);
    std::vector<std::uint64_t> next_keys, next_spans;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (level < order && (level < min_level || cost[i] > max_cost)) {
        const std::uint64_t child = spans[i] / nb;
        for (std::uint64_t j = 0; j < nb; ++j) {
          next_keys.push_back(keys[i] + j * child);
          next_spans.push_back(child);
        }
        continue;
      }
      TreeCell t;
      t.key = keys[i];
      t.span = spans[i];
      t.level = level;
      t.cost = cost[i];
      std::uint32_t x, y, z;
      sfc_cell(curve, t.key, order, x, y, z);
      std::uint32_t sub = 1;  // finest cells per axis of this cell
      for (int l = level; l < order; ++l) sub *= static_cast<std::uint32_t>(b);
      t.x = x / sub;
      t.y = y / sub;
      t.z = z / sub;
      leaves.push_back(t);
    }
    keys.swap(next_keys);
    spans.swap(next_spans);
  }
  // Segments are nested, so key order is curve order.
  std::sort(leaves.begin(), leaves.end(),
            [](const TreeCell& a, const TreeCell& c) { return a.key < c.key; });
  return leaves;
}

std::vector<TreeCell> refine_cells(Curve curve, int order, std::span<const std::uint64_t> item_keys,
                                   std::span<const double> item_cost, double max_cost,
                                   int min_level) {
  if (item_keys.size() != item_cost.size())
    throw std::invalid_argument("refine_cells: keys and costs differ in size");
  // Items sorted by key with prefix sums of their costs: a cell's cost is a difference.
  std::vector<std::size_t> idx(item_keys.size());
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::sort(idx.begin(), idx.end(),
            [&](std::size_t a, std::size_t b) { return item_keys[a] < item_keys[b]; });
  std::vector<std::uint64_t> sorted(idx.size());
  std::vector<double> prefix(idx.size() + 1, 0.0);
  for (std::size_t i = 0; i < idx.size(); ++i) {
    sorted[i] = item_keys[idx[i]];
    prefix[i + 1] = prefix[i] + item_cost[idx[i]];
  }
  return refine_cells_by(curve, order, max_cost, min_level,
                         [&](std::span<const std::uint64_t> keys,
                             std::span<const std::uint64_t> spans, std::span<double> costs) {
                           for (std::size_t c = 0; c < keys.size(); ++c) {
                             const auto a = std::lower_bound(sorted.begin(), sorted.end(), keys[c]);
                             const auto e = std::lower_bound(a, sorted.end(), keys[c] + spans[c]);
                             costs[c] = prefix[e - sorted.begin()] - prefix[a - sorted.begin()];
                           }
                         });
}

}  // namespace qdemsph
