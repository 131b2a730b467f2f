// Space-filling-curve keys (parallel/sfc.hpp): bijective on the whole grid, Hilbert and
// Peano consecutive keys are face-adjacent cells, Morton keys order by interleaved bits,
// and keys of a cell's descendants are nested in one contiguous segment.
#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#include "parallel/sfc.hpp"

using namespace qdemsph;

namespace {

std::uint64_t grid_cells(Curve c, int order) {
  std::uint64_t side = 1;
  for (int i = 0; i < order; ++i) side *= curve_base(c);
  return side;
}

// Every cell gets a distinct key in [0, side^3) and decoding the key gives the cell back.
void check_bijective(Curve c, int order) {
  const std::uint64_t side = grid_cells(c, order), n = side * side * side;
  std::vector<int> seen(n, 0);
  for (std::uint32_t x = 0; x < side; ++x)
    for (std::uint32_t y = 0; y < side; ++y)
      for (std::uint32_t z = 0; z < side; ++z) {
        const std::uint64_t k = sfc_key(c, x, y, z, order);
        ASSERT_LT(k, n) << "cell " << x << " " << y << " " << z;
        ++seen[k];
        std::uint32_t a, b, d;
        sfc_cell(c, k, order, a, b, d);
        ASSERT_EQ(a, x);
        ASSERT_EQ(b, y);
        ASSERT_EQ(d, z);
      }
  for (std::uint64_t k = 0; k < n; ++k) ASSERT_EQ(seen[k], 1) << "key " << k;
}

// Consecutive keys decode to cells that share a face (Manhattan distance 1).
void check_local(Curve c, int order) {
  const std::uint64_t side = grid_cells(c, order), n = side * side * side;
  std::uint32_t px, py, pz;
  sfc_cell(c, 0, order, px, py, pz);
  for (std::uint64_t k = 1; k < n; ++k) {
    std::uint32_t x, y, z;
    sfc_cell(c, k, order, x, y, z);
    const long d = std::labs(long(x) - long(px)) + std::labs(long(y) - long(py)) +
                   std::labs(long(z) - long(pz));
    ASSERT_EQ(d, 1) << "keys " << k - 1 << " and " << k;
    px = x;
    py = y;
    pz = z;
  }
}

// The finest cells inside one cell of level l share the leading digits of their keys.
void check_nested(Curve c, int order, int level) {
  const std::uint64_t side = grid_cells(c, order), b = curve_base(c);
  std::uint64_t sub = 1;  // finest cells per axis inside one level-l cell
  for (int i = level; i < order; ++i) sub *= b;
  const std::uint64_t span = sub * sub * sub;
  for (std::uint32_t x = 0; x < side; ++x)
    for (std::uint32_t y = 0; y < side; ++y)
      for (std::uint32_t z = 0; z < side; ++z) {
        // The parent's segment is [first, first + span): same leading digits as the
        // parent's first corner cell.
        const std::uint64_t k = sfc_key(c, x, y, z, order);
        const std::uint64_t k0 =
            sfc_key(c, (x / sub) * sub, (y / sub) * sub, (z / sub) * sub, order);
        ASSERT_EQ(k / span, k0 / span) << "level " << level;
      }
}

}  // namespace

TEST(Sfc, MortonBijective) {
  for (int order : {1, 2, 3, 5}) check_bijective(Curve::Morton, order);
}
TEST(Sfc, HilbertBijective) {
  for (int order : {1, 2, 3, 5}) check_bijective(Curve::Hilbert, order);
}
TEST(Sfc, PeanoBijective) {
  for (int order : {1, 2, 3}) check_bijective(Curve::Peano, order);
}

TEST(Sfc, HilbertLocal) {
  for (int order : {1, 2, 3, 5}) check_local(Curve::Hilbert, order);
}
TEST(Sfc, PeanoLocal) {
  for (int order : {1, 2, 3}) check_local(Curve::Peano, order);
}

TEST(Sfc, MortonOrdering) {
  // Known values: the eight cells of a 2x2x2 grid in z-order, x most significant.
  EXPECT_EQ(morton_key(0, 0, 0), 0u);
  EXPECT_EQ(morton_key(0, 0, 1), 1u);
  EXPECT_EQ(morton_key(0, 1, 0), 2u);
  EXPECT_EQ(morton_key(1, 0, 0), 4u);
  EXPECT_EQ(morton_key(1, 1, 1), 7u);
  EXPECT_EQ(morton_key(2, 0, 0), 32u);
  // Order rule: the keys compare as the coordinates on the axis with the highest
  // differing bit (ties to x, then y).
  auto msb = [](std::uint32_t v) { return v == 0 ? -1 : 31 - __builtin_clz(v); };
  const std::uint32_t side = 16;
  for (std::uint32_t i = 0; i < side * side * side; i += 7)
    for (std::uint32_t j = 0; j < side * side * side; j += 11) {
      const std::uint32_t a[3] = {i % side, (i / side) % side, i / (side * side)};
      const std::uint32_t b[3] = {j % side, (j / side) % side, j / (side * side)};
      int axis = -1, top = -1;
      for (int d = 0; d < 3; ++d)
        if (msb(a[d] ^ b[d]) > top) {
          top = msb(a[d] ^ b[d]);
          axis = d;
        }
      const std::uint64_t ka = morton_key(a[0], a[1], a[2]);
      const std::uint64_t kb = morton_key(b[0], b[1], b[2]);
      if (axis < 0) {
        ASSERT_EQ(ka, kb);
      } else {
        ASSERT_EQ(ka < kb, a[axis] < b[axis]) << i << " " << j;
      }
    }
  // Monotone along each axis: increasing one coordinate increases the key.
  for (std::uint32_t x = 0; x + 1 < 32; ++x) {
    EXPECT_LT(morton_key(x, 5, 9), morton_key(x + 1, 5, 9));
    EXPECT_LT(morton_key(5, x, 9), morton_key(5, x + 1, 9));
    EXPECT_LT(morton_key(9, 5, x), morton_key(9, 5, x + 1));
  }
}

TEST(Sfc, KeysNestedInParentSegment) {
  for (Curve c : {Curve::Morton, Curve::Hilbert})
    for (int level : {0, 1, 2, 3}) check_nested(c, 4, level);
  for (int level : {0, 1, 2}) check_nested(Curve::Peano, 3, level);
}

TEST(Sfc, LargestOrderRoundTrips) {
  for (Curve c : {Curve::Morton, Curve::Hilbert, Curve::Peano}) {
    const int order = curve_max_order(c);
    std::uint64_t side = 1;
    for (int i = 0; i < order; ++i) side *= curve_base(c);
    const std::uint32_t m = static_cast<std::uint32_t>(side - 1);
    const std::uint32_t pts[4][3] = {{0, 0, 0}, {m, m, m}, {m, 0, m / 2}, {m / 3, m, 1}};
    for (auto& p : pts) {
      const std::uint64_t k = sfc_key(c, p[0], p[1], p[2], order);
      EXPECT_LT(k, side * side * side);
      std::uint32_t x, y, z;
      sfc_cell(c, k, order, x, y, z);
      EXPECT_EQ(x, p[0]);
      EXPECT_EQ(y, p[1]);
      EXPECT_EQ(z, p[2]);
    }
  }
}
