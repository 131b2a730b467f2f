// Host orchestration primitives of a distributed rank's layout rebuild: stream compaction and
// bucketing by key (core/select_host.hpp), the sorting permutation (core/radix_sort.hpp), the
// prefix sum of counts and the atomic maximum (neighbor/scan.hpp) and the several maxima of one
// pass (core/exec_host.hpp) give the serial answers, the same for any number of threads; a few
// coarse items run on the threads; and the default thread count of a rank.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "core/exec_host.hpp"
#include "core/radix_sort.hpp"
#include "core/select_host.hpp"
#include "neighbor/scan.hpp"

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

// Into a kept vector (a layout rebuild's), the same indices in the same storage while they fit.
TEST(HostSelect, IntoAKeptVectorReusesItsStorage) {
  const std::int64_t n = 5 * kMinParallel + 17;
  auto keep = [](std::int64_t i) { return (i * 7919) % 13 < 4; };
  std::vector<std::int64_t> out;
  select_indices(HostExec{}, n, keep, out);
  EXPECT_EQ(out, select_indices(HostExec{}, n, keep));
  const std::int64_t* storage = out.data();
  select_indices(HostExec{}, n - 1000, keep, out);  // fewer kept
  EXPECT_EQ(out, select_indices(HostExec{}, n - 1000, keep));
  EXPECT_EQ(out.data(), storage);
}

TEST(HostSelect, BucketsByKeyInOrderForAnyThreadCount) {
  const std::int64_t n = 4 * kMinParallel + 5;
  auto key = [](std::int64_t i) { return static_cast<int>((i * 31) % 7) - 1; };  // -1..5
  Buckets serial;
  serial.start.push_back(0);
  for (int k = 0; k < 4; ++k) {  // keys 0..3 kept, -1, 4 and 5 dropped
    for (std::int64_t i = 0; i < n; ++i)
      if (key(i) == k) serial.index.push_back(i);
    serial.start.push_back(static_cast<std::int64_t>(serial.index.size()));
  }
  for (int t : {1, 2, 3, 8}) {
    const Buckets b = with_threads(t, [&] { return bucket_indices(HostExec{}, n, 4, key); });
    EXPECT_EQ(b.index, serial.index) << t << " threads";
    EXPECT_EQ(b.start, serial.start) << t << " threads";
  }
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

TEST(HostSelect, ExclusiveScanForAnyThreadCount) {
  const std::int64_t n = 3 * kMinParallel + 11;
  std::vector<std::int64_t> counts(n + 1, -1), serial(n + 1);
  for (std::int64_t i = 0; i < n; ++i) counts[i] = (i * 7919) % 5;
  serial[0] = 0;
  for (std::int64_t i = 0; i < n; ++i) serial[i + 1] = serial[i] + counts[i];
  for (int t : {1, 2, 3, 8}) {
    std::vector<std::int64_t> c = counts;
    const std::int64_t total = with_threads(t, [&] {
      return exclusive_scan(HostExec{}, View<std::int64_t>{c.data(), n + 1}, n);
    });
    EXPECT_EQ(total, serial[n]) << t << " threads";
    EXPECT_EQ(c, serial) << t << " threads";
  }
  std::vector<std::int64_t> none{7};
  EXPECT_EQ(exclusive_scan(HostExec{}, View<std::int64_t>{none.data(), 1}, 0), 0);
  EXPECT_EQ(none[0], 0);
}

TEST(HostSelect, ReduceMaxEachForAnyThreadCount) {
  const std::int64_t n = 3 * kMinParallel + 5;
  auto f = [](std::int64_t i) {
    const double v = static_cast<double>((i * 2654435761u) % 100003);
    return std::array<double, 3>{v, -v, i == 17 ? std::nan("") : 0.5 * v};  // NaN skipped
  };
  for (int t : {1, 2, 3, 8}) {
    const auto m = with_threads(t, [&] { return reduce_max_each<3>(HostExec{}, n, f, -1e300); });
    double want[3] = {-1e300, -1e300, -1e300};
    for (std::int64_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        if (f(i)[k] > want[k]) want[k] = f(i)[k];
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m[k], want[k]) << t << " threads, value " << k;
  }
  const auto none = [](std::int64_t) { return std::array<double, 2>{1.0, 2.0}; };
  EXPECT_EQ((reduce_max_each<2>(HostExec{}, 0, none, 3.0)), (std::array<double, 2>{3.0, 3.0}));
}

// atomic_max_positive from many threads keeps the largest positive value; NaN, zero and
// negative values change nothing.
TEST(HostSelect, AtomicMaxPositiveForAnyThreadCount) {
  const std::int64_t n = 3 * kMinParallel + 5;
  auto f = [](std::int64_t i) {
    if (i == 17) return std::nan("");
    return static_cast<double>((i * 2654435761u) % 100003) - 50000.0;
  };
  double want = 0;
  for (std::int64_t i = 0; i < n; ++i)
    if (f(i) > want) want = f(i);
  for (int t : {1, 2, 3, 8}) {
    const double m = with_threads(t, [&] {
      double acc = 0;
      for_each(HostExec{}, n, [&](std::int64_t i) { atomic_max_positive(&acc, f(i)); });
      return acc;
    });
    EXPECT_EQ(m, want) << t << " threads";
  }
  double acc = 2.5;
  atomic_max_positive(&acc, -7.0);
  atomic_max_positive(&acc, std::nan(""));
  atomic_max_positive(&acc, 1.0);
  EXPECT_EQ(acc, 2.5);
}

// for_each_coarse visits each of a few items once, on as many threads as there are items (up to
// the threads), where for_each runs so short a loop on one thread.
TEST(HostSelect, CoarseItemsSpreadOverTheThreads) {
  for (int t : {1, 2, 3}) {
    const auto seen = with_threads(t, [&] {
      std::vector<int> thread(5, -1), visits(5, 0);
      for_each_coarse(HostExec{}, 5, [&](std::int64_t i) {
        thread[i] = omp_get_thread_num();
        ++visits[i];
      });
      EXPECT_EQ(visits, std::vector<int>(5, 1)) << t << " threads";
      return static_cast<int>(*std::max_element(thread.begin(), thread.end())) + 1;
    });
    EXPECT_EQ(seen, t);
  }
  const auto one = with_threads(3, [&] {
    std::vector<int> thread(5, -1);
    for_each(HostExec{}, 5, [&](std::int64_t i) { thread[i] = omp_get_thread_num(); });
    return *std::max_element(thread.begin(), thread.end()) + 1;
  });
  EXPECT_EQ(one, 1);
}

TEST(HostThreads, ARankTakesItsShareOfTheNodeBoundedByItsCoresAndAGpuRankAtMostEight) {
  EXPECT_EQ(default_host_threads(64, 64, 1, false), 64);  // one CPU rank: every core
  EXPECT_EQ(default_host_threads(64, 64, 4, false), 16);  // unbound: its share
  EXPECT_EQ(default_host_threads(8, 64, 4, false), 8);    // bound to 8 cores
  EXPECT_EQ(default_host_threads(1, 64, 2, true), 1);     // mpirun's default: one core a rank
  EXPECT_EQ(default_host_threads(64, 64, 2, true), kGpuRankThreads);
  EXPECT_EQ(default_host_threads(4, 4, 2, true), 2);
  EXPECT_EQ(default_host_threads(2, 2, 4, false), 1);  // more ranks than cores
}

}  // namespace
}  // namespace qdemsph
