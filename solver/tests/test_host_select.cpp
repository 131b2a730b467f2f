// Host orchestration primitives of a distributed rank's layout rebuild: stream compaction
// (core/select_host.hpp) and the sorting permutation (core/parallel_sort.hpp) give the serial
// answers, the same for any number of threads.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "core/parallel_sort.hpp"
#include "core/select_host.hpp"

namespace qdemsph {
namespace {

// Runs f with `threads` OpenMP threads, then restores the setting.
template <class F>
auto with_threads(int threads, F f) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  auto r = f();
  omp_set_num_threads(before);
  return r;
}

TEST(HostSelect, IndicesInOrderForAnyThreadCount) {
  const std::int64_t n = 5 * kMinParallel + 17;  // long enough to run in parallel
  auto keep = [](std::int64_t i) { return (i * 7919) % 13 < 4; };
  std::vector<std::int64_t> serial;
  for (std::int64_t i = 0; i < n; ++i)
    if (keep(i)) serial.push_back(i);
  for (int t : {1, 2, 3, 8})
    EXPECT_EQ(with_threads(t, [&] { return select_indices(HostExec{}, n, keep); }), serial)
        << t << " threads";
  EXPECT_TRUE(select_indices(HostExec{}, 0, keep).empty());
  EXPECT_EQ(select_indices(HostExec{}, 5, [](std::int64_t i) { return i != 2; }),
            (std::vector<std::int64_t>{0, 1, 3, 4}));
}

TEST(HostSelect, SortedOrderOfUniqueKeysForAnyThreadCount) {
  const std::int64_t n = 3 * kMinParallel;
  std::vector<std::uint64_t> keys(n);
  for (std::int64_t i = 0; i < n; ++i)
    keys[i] = (static_cast<std::uint64_t>(i) * 2654435761u) % 1000003;
  std::vector<std::int64_t> serial(n);
  std::iota(serial.begin(), serial.end(), std::int64_t{0});
  std::sort(serial.begin(), serial.end(), [&](auto a, auto b) { return keys[a] < keys[b]; });
  for (int t : {1, 2, 3, 8})
    EXPECT_EQ(with_threads(t, [&] { return sorted_order(keys); }), serial) << t << " threads";
  const std::vector<std::int64_t> g = gathered<std::int64_t>(keys, serial);
  EXPECT_TRUE(std::is_sorted(g.begin(), g.end()));
  EXPECT_EQ(g.front(), static_cast<std::int64_t>(keys[serial.front()]));
}

}  // namespace
}  // namespace qdemsph
