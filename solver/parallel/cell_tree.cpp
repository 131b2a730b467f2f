#include "parallel/cell_tree.hpp"

#include <numeric>
#include <stdexcept>
#include <string>

namespace qdemsph {

namespace {

struct Refiner {
  Curve curve;
  int order;
  double max_cost;
  int min_level;
  std::vector<std::uint64_t> keys;  // sorted item keys
  std::vector<double> prefix;       // prefix[i] = cost of items [0, i)
  std::vector<TreeCell> leaves;

  double cost(std::uint64_t k0, std::uint64_t span) const {
    const auto a = std::lower_bound(keys.begin(), keys.end(), k0) - keys.begin();
    const auto b = std::lower_bound(keys.begin() + a, keys.end(), k0 + span) - keys.begin();
    return prefix[b] - prefix[a];
  }

  void visit(std::uint64_t k0, std::uint64_t span, int level) {
    const double c = cost(k0, span);
    if (level < order && (level < min_level || c > max_cost)) {
      const std::uint64_t nb =
          std::uint64_t(curve_base(curve)) * curve_base(curve) * curve_base(curve);
      const std::uint64_t child = span / nb;
      for (std::uint64_t j = 0; j < nb; ++j) visit(k0 + j * child, child, level + 1);
      return;
    }
    TreeCell t;
    t.key = k0;
    t.span = span;
    t.level = level;
    t.cost = c;
    std::uint32_t x, y, z;
    sfc_cell(curve, k0, order, x, y, z);
    std::uint32_t sub = 1;  // finest cells per axis of this cell
    for (int i = level; i < order; ++i) sub *= curve_base(curve);
    t.x = x / sub;
    t.y = y / sub;
    t.z = z / sub;
    leaves.push_back(t);
  }
};

}  // namespace

std::vector<TreeCell> refine_cells(Curve curve, int order, std::span<const std::uint64_t> item_keys,
                                   std::span<const double> item_cost, double max_cost,
                                   int min_level) {
  if (order < 1 || order > curve_max_order(curve))
    throw std::invalid_argument("refine_cells: order " + std::to_string(order) + " outside [1, " +
                                std::to_string(curve_max_order(curve)) + "]");
  if (item_keys.size() != item_cost.size())
    throw std::invalid_argument("refine_cells: keys and costs differ in size");
  Refiner r{curve, order, max_cost, min_level, {}, {}, {}};
  // Sort items by key, carrying their costs.
  std::vector<std::size_t> idx(item_keys.size());
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::sort(idx.begin(), idx.end(),
            [&](std::size_t a, std::size_t b) { return item_keys[a] < item_keys[b]; });
  r.keys.resize(idx.size());
  r.prefix.assign(idx.size() + 1, 0.0);
  for (std::size_t i = 0; i < idx.size(); ++i) {
    r.keys[i] = item_keys[idx[i]];
    r.prefix[i + 1] = r.prefix[i] + item_cost[idx[i]];
  }
  std::uint64_t side = 1;
  for (int i = 0; i < order; ++i) side *= curve_base(curve);
  r.visit(0, side * side * side, 0);
  return r.leaves;
}

}  // namespace qdemsph
