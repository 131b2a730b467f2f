#include "parallel/partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace qdemsph {

namespace {

// The cumulative targets S_1 .. S_{n-1} of `share` (empty when the shares are equal); throws
// on bad shares.
std::vector<double> share_bounds(std::span<const double> share, int nranks) {
  if (share.empty()) return {};
  if (static_cast<int>(share.size()) != nranks)
    throw std::invalid_argument("partition_cells: " + std::to_string(share.size()) +
                                " shares for " + std::to_string(nranks) + " ranks");
  double sum = 0;
  std::vector<double> bound;
  for (int r = 0; r < nranks; ++r) {
    if (!(share[r] >= 0) || !std::isfinite(share[r]))
      throw std::invalid_argument("partition_cells: share of rank " + std::to_string(r) +
                                  " is negative or not finite");
    sum += share[r];
    if (r + 1 < nranks) bound.push_back(sum);
  }
  if (std::abs(sum - 1) > 1e-9)
    throw std::invalid_argument("partition_cells: shares sum to " + std::to_string(sum) +
                                ", not 1");
  return bound;
}

}  // namespace

std::vector<int> partition_cells(std::span<const std::uint64_t> keys, std::span<const double> cost,
                                 int nranks, std::span<const double> share) {
  if (nranks < 1) throw std::invalid_argument("partition_cells: nranks must be >= 1");
  const std::vector<double> bound = share_bounds(share, nranks);
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
    const int r = bound.empty()
                      ? static_cast<int>(std::floor(mid * nranks / W))
                      : static_cast<int>(std::upper_bound(bound.begin(), bound.end(), mid / W) -
                                         bound.begin());
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

PartitionStats partition_stats(std::span<const double> cost, std::span<const int> owner, int nranks,
                               std::span<const double> share) {
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
  if (!share.empty() && total > 0) {
    double worst = 0;
    for (int r = 0; r < nranks; ++r)
      worst = std::max(worst, share[r] > 0 ? s.load[r] / (share[r] * total) : 0.0);
    s.imbalance = worst - 1;
  }
  return s;
}

std::vector<double> speed_shares(std::span<const double> load, std::span<const double> busy) {
  if (load.size() != busy.size())
    throw std::invalid_argument("speed_shares: loads and times differ in size");
  const std::size_t n = load.size();
  std::vector<double> speed(n, 0.0);
  double sum = 0;
  int known = 0;
  for (std::size_t r = 0; r < n; ++r)
    if (load[r] > 0 && busy[r] > 0 && std::isfinite(load[r] / busy[r])) {
      speed[r] = load[r] / busy[r];
      sum += speed[r];
      ++known;
    }
  if (known == 0) return std::vector<double>(n, 1.0 / static_cast<double>(n));
  const double mean = sum / known;
  double total = 0;
  for (double& s : speed) {
    s = s > 0 ? std::clamp(s, 0.25 * mean, 4.0 * mean) : mean;
    total += s;
  }
  for (double& s : speed) s /= total;
  return speed;
}

}  // namespace qdemsph
