#include "parallel/partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace qdemsph {

std::vector<int> partition_cells(std::span<const std::uint64_t> keys, std::span<const double> cost,
                                 int nranks) {
  if (nranks < 1) throw std::invalid_argument("partition_cells: nranks must be >= 1");
  if (keys.size() != cost.size())
    throw std::invalid_argument("partition_cells: " + std::to_string(keys.size()) + " keys but " +
                                std::to_string(cost.size()) + " costs");
  const std::size_t n = keys.size();
  double total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && keys[i] <= keys[i - 1])
      throw std::invalid_argument("partition_cells: keys not strictly increasing at cell " +
                                  std::to_string(i));
    if (!(cost[i] >= 0) || !std::isfinite(cost[i]))
      throw std::invalid_argument("partition_cells: cost of cell " + std::to_string(i) +
                                  " is negative or not finite");
    total += cost[i];
  }
  std::vector<int> owner(n, 0);
  if (n == 0 || nranks == 1) return owner;
  const bool by_count = !(total > 0);
  const double W = by_count ? static_cast<double>(n) : total;
  double before = 0;  // P_i, summed in curve order (the same on every rank)
  for (std::size_t i = 0; i < n; ++i) {
    const double c = by_count ? 1.0 : cost[i];
    const double mid = before + 0.5 * c;
    const int r = static_cast<int>(std::floor(mid * nranks / W));
    owner[i] = std::clamp(r, i > 0 ? owner[i - 1] : 0, nranks - 1);  // round-off guard
    before += c;
  }
  return owner;
}

std::vector<std::uint64_t> partition_splitters(std::span<const std::uint64_t> keys,
                                               std::span<const int> owner, int nranks) {
  if (keys.size() != owner.size())
    throw std::invalid_argument("partition_splitters: keys and owners differ in size");
  constexpr std::uint64_t kEnd = std::numeric_limits<std::uint64_t>::max();
  std::vector<std::uint64_t> s(nranks + 1, kEnd);
  for (std::size_t i = keys.size(); i-- > 0;) s[owner[i]] = keys[i];  // first cell's key
  for (int r = nranks - 1; r >= 0; --r) s[r] = std::min(s[r], s[r + 1]);
  // Keys before the first cell belong to its owner (ranks before it have no cells).
  const int first = keys.empty() ? 0 : owner[0];
  for (int r = 0; r <= first; ++r) s[r] = 0;
  return s;
}

int owner_of_key(std::span<const std::uint64_t> splitters, std::uint64_t key) {
  // The last rank r with splitters[r] <= key (ranks without cells have equal splitters).
  const auto it = std::upper_bound(splitters.begin(), splitters.end() - 1, key);
  return static_cast<int>(it - splitters.begin()) - 1;
}

PartitionStats partition_stats(std::span<const double> cost, std::span<const int> owner,
                               int nranks) {
  PartitionStats s;
  s.load.assign(nranks, 0.0);
  double total = 0;
  for (std::size_t i = 0; i < cost.size(); ++i) {
    s.load[owner[i]] += cost[i];
    total += cost[i];
    s.max_cell = std::max(s.max_cell, cost[i]);
  }
  s.mean = nranks > 0 ? total / nranks : 0;
  s.max = s.load.empty() ? 0 : *std::max_element(s.load.begin(), s.load.end());
  s.imbalance = s.mean > 0 ? s.max / s.mean - 1 : 0;
  return s;
}

}  // namespace qdemsph
