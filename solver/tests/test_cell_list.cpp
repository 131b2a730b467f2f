// The cell-list candidate pairs equal an O(N^2) brute-force search (STYLE.md item 9).
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <utility>

#include "core/exec_host.hpp"
#include "neighbor/pair_list.hpp"

using namespace qdemsph;

namespace {

struct Config {
  std::vector<Vec3> c;
  std::vector<double> r;
  std::vector<int> body;
  std::vector<int> fixed;  // per body
};

Config random_config(unsigned seed, int n, bool clustered) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  Config k;
  const int nb = 1 + n / 20;
  for (int b = 0; b < nb; ++b) k.fixed.push_back(U(rng) < 0.2);
  for (int i = 0; i < n; ++i) {
    Vec3 p{U(rng), U(rng), U(rng) * 0.5};
    if (clustered && i % 3 == 0) p = Vec3{0.5, 0.5, 0.25} + 0.02 * Vec3{U(rng), U(rng), U(rng)};
    k.c.push_back(p);
    k.r.push_back(0.005 + 0.04 * U(rng) * U(rng));  // a spread of sizes
    k.body.push_back(static_cast<int>(U(rng) * nb));
  }
  // Free bodies' items first, as the model orders them.
  std::vector<int> idx(n);
  for (int i = 0; i < n; ++i) idx[i] = i;
  std::stable_partition(idx.begin(), idx.end(), [&](int i) { return !k.fixed[k.body[i]]; });
  Config s = k;
  for (int i = 0; i < n; ++i) {
    s.c[i] = k.c[idx[i]];
    s.r[i] = k.r[idx[i]];
    s.body[i] = k.body[idx[i]];
  }
  return s;
}

}  // namespace

TEST(CellList, CandidatePairsEqualBruteForce) {
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const int n = 50 + 97 * seed;
    const Config k = random_config(seed, n, seed % 2 == 0);
    const double gap = 0.01;
    std::int64_t nfree = 0;
    for (int i = 0; i < n; ++i)
      if (!k.fixed[k.body[i]]) nfree = i + 1;
    Vec3Buffer cb;
    cb.assign(k.c);
    Buffer<double> rb;
    rb.assign(k.r);
    Buffer<int> bb, fb;
    bb.assign(k.body);
    fb.assign(k.fixed);
    double rmax = 0;
    Vec3 lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
    for (int i = 0; i < n; ++i) {
      rmax = std::max(rmax, k.r[i]);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], k.c[i][a]);
        hi[a] = std::max(hi[a], k.c[i][a]);
      }
    }
    CellList<HostExec> cells;
    // Cap the grid on some seeds to exercise the coarsening path.
    cells.set_grid(cover_capped(lo, hi, 2 * rmax + gap, seed % 3 == 0 ? 8 : 1 << 20));
    cells.build(cb.cview());
    CandidatePairs<HostExec> pairs;
    const auto body = bb.cview();
    const auto fixed = fb.cview();
    auto accept = [=](std::int64_t i, std::int64_t j) {
      return body[i] != body[j] && !(fixed[body[i]] && fixed[body[j]]);
    };
    pairs.build(cells, cb.cview(), rb.cview(), gap, nfree, accept);
    std::set<std::pair<int, int>> got, want;
    const auto st = pairs.start();
    const auto sec = pairs.second();
    for (std::int64_t i = 0; i < nfree; ++i)
      for (std::int64_t q = st[i]; q < st[i + 1]; ++q) {
        EXPECT_TRUE(got.emplace(static_cast<int>(i), sec[q]).second) << "duplicate pair";
      }
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        const double lim = k.r[i] + k.r[j] + gap;
        if (norm2(k.c[i] - k.c[j]) <= lim * lim && accept(i, j)) want.emplace(i, j);
      }
    EXPECT_EQ(got, want) << "seed " << seed;
    EXPECT_GT(want.size(), 0u);
  }
}
