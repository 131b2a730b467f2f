// The host radix sort (core/radix_sort.hpp): the stable order by key (records of equal keys in
// their input order), on one thread and on several, for keys of a few bits to all 64.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "core/radix_sort.hpp"
#include "neighbor/cell_grid.hpp"

using namespace qdemsph;

namespace {

using Records = std::vector<std::pair<std::uint64_t, std::int64_t>>;

Records sorted_by(int threads, Records a, int bits) {
#ifdef _OPENMP
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
#endif
  Records tmp;
  radix_sort(a, tmp, bits);
#ifdef _OPENMP
  omp_set_num_threads(before);
#endif
  return a;
}

}  // namespace

TEST(RadixSort, StableOrderOnAnyThreadCount) {
  std::mt19937_64 rng(7);
  for (std::int64_t n : {0, 1, 1000, 100000})
    for (int bits : {8, 20, 48, 64}) {
      Records a(n);
      for (std::int64_t i = 0; i < n; ++i) {
        // Few distinct keys at 8 bits (many equal), spread over all the bits otherwise.
        const std::uint64_t k = bits == 64 ? rng() : rng() & ((std::uint64_t{1} << bits) - 1);
        a[i] = {k, i};
      }
      Records want = a;
      std::stable_sort(want.begin(), want.end(),
                       [](const auto& x, const auto& y) { return x.first < y.first; });
      EXPECT_EQ(sorted_by(1, a, bits), want) << n << " records, " << bits << " bits";
      EXPECT_EQ(sorted_by(3, a, bits), want) << n << " records, " << bits << " bits";
    }
}

TEST(RadixSort, SkipsADigitCommonToAllKeys) {
  // Keys that differ only in their second byte: the first pass moves nothing.
  Records a = {{0x300, 0}, {0x100, 1}, {0x200, 2}, {0x100, 3}};
  Records tmp;
  radix_sort(a, tmp, 16);
  EXPECT_EQ(a, (Records{{0x100, 1}, {0x100, 3}, {0x200, 2}, {0x300, 0}}));
}

// merge_runs: records in ascending runs (a rank's vertices by global id: owned, each
// neighbour's ghosts, fixed) come out in the stable order by key for any count of runs, equal
// keys across runs in input order, on one thread and on several; from one run up to every
// record its own run (random keys).
TEST(RadixSort, MergeRunsGivesTheStableOrder) {
  std::mt19937_64 rng(11);
  for (std::int64_t n : {0, 1, 7, 1000, 100000})
    for (int runs : {1, 2, 3, 5, 17, 0}) {  // 0: random keys
      Records a(n);
      std::int64_t begin = 0;
      for (int r = 0; r < runs; ++r) {
        const std::int64_t end =
            r + 1 == runs ? n : std::min<std::int64_t>(n, begin + rng() % (2 * n / runs + 1));
        std::vector<std::uint64_t> keys(end - begin);
        for (auto& k : keys) k = rng() % (n + 1);  // repeats within and across runs
        std::sort(keys.begin(), keys.end());
        for (std::int64_t i = begin; i < end; ++i) a[i] = {keys[i - begin], i};
        begin = end;
      }
      if (runs == 0)
        for (std::int64_t i = 0; i < n; ++i) a[i] = {rng() % (n + 1), i};
      Records want = a;
      std::stable_sort(want.begin(), want.end(),
                       [](const auto& x, const auto& y) { return x.first < y.first; });
      for (int threads : {1, 3}) {
#ifdef _OPENMP
        const int before = omp_get_max_threads();
        omp_set_num_threads(threads);
#endif
        Records got = a, tmp;
        merge_runs(got, tmp);
#ifdef _OPENMP
        omp_set_num_threads(before);
#endif
        EXPECT_EQ(got, want) << n << " records, " << runs << " runs, " << threads << " threads";
      }
    }
}

// sort_order (neighbor/cell_grid.hpp): the stable order of items by keys too wide for
// sort_by_key's offsets (the SPH layout's order keys), through the radix sort.
TEST(RadixSort, SortOrderGivesTheStableOrderOfWideKeys) {
  std::mt19937_64 rng(11);
  const std::int64_t n = 20000;
  Buffer<std::int64_t> keys(Space::Host, n), order(Space::Host, n), scratch;
  for (std::int64_t i = 0; i < n; ++i)
    keys.view()[i] = std::int64_t(rng() & ((1ull << 40) - 1)) & ~0xffll;
  std::vector<std::int64_t> want(n);
  for (std::int64_t i = 0; i < n; ++i) want[i] = i;
  std::stable_sort(want.begin(), want.end(),
                   [&](std::int64_t a, std::int64_t b) { return keys.view()[a] < keys.view()[b]; });
  sort_order(HostExec{}, keys.cview(), 40, order.view(), scratch);
  EXPECT_EQ(order.to_host(), want);
}
