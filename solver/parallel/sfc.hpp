// Space-filling-curve keys for integer cell coordinates in 3D (METHOD.md section 4).
//
// A key orders the cells of a cubic grid along a curve; cutting the sorted keys into
// contiguous pieces gives each rank a compact, connected region (partition.hpp).
//
//   Morton  (Z-order): key bits = interleaved coordinate bits (x most significant of each
//           triple); grid 2^order cells per axis, order <= 21. Cheap, but consecutive keys
//           jump (the curve is not continuous).
//   Hilbert: Skilling's table-free transpose method ("Programming the Hilbert curve", AIP
//           Conf. Proc. 707, 2004): coordinates -> transposed index by undoing excess work
//           and Gray coding, then interleaved; grid 2^order per axis, order <= 21.
//           Consecutive keys are face-adjacent cells.
//   Peano:  the 3^k serpentine curve (Peano's construction in n dimensions): key digits in
//           base 3, digit m belongs to axis m mod 3 (x first), and the coordinate digit is
//           the key digit reflected (d -> 2 - d) when the sum of all preceding key digits
//           of the two other axes is odd. Grid 3^order per axis, order <= 13 (3^39 < 2^63).
//           Consecutive keys are face-adjacent cells.
//
// All three are hierarchical: the leading 3*l bits (Morton, Hilbert) or 3*l base-3 digits
// (Peano) of a key depend only on the leading l digits of the coordinates, so the cells of
// the finest grid inside one cell of level l form one contiguous key range. cell_tree.hpp
// relies on this to nest the keys of refined cells in their parent's curve segment.
//
// Pure QDEMSPH_HD functions over plain integers: no loops over data, no allocation.
#pragma once

#include <cstdint>

#include "core/hd.hpp"

namespace qdemsph {

enum class Curve : std::uint8_t { Morton, Hilbert, Peano };

// Cells per axis of one refinement step: 2 for Morton and Hilbert, 3 for Peano.
QDEMSPH_HD std::uint32_t curve_base(Curve c) { return c == Curve::Peano ? 3u : 2u; }
// Largest supported order (refinement levels) so that keys fit in 63 bits.
QDEMSPH_HD int curve_max_order(Curve c) { return c == Curve::Peano ? 13 : 21; }

// ---- Morton ----------------------------------------------------------------------------

// Spreads the low 21 bits of v so that bit i moves to bit 3i.
QDEMSPH_HD std::uint64_t sfc_spread3(std::uint64_t v) {
  v &= 0x1fffffull;
  v = (v | (v << 32)) & 0x1f00000000ffffull;
  v = (v | (v << 16)) & 0x1f0000ff0000ffull;
  v = (v | (v << 8)) & 0x100f00f00f00f00full;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
  v = (v | (v << 2)) & 0x1249249249249249ull;
  return v;
}

// Inverse of sfc_spread3: gathers bits 0, 3, 6, ... into the low 21 bits.
QDEMSPH_HD std::uint32_t sfc_compact3(std::uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v | (v >> 2)) & 0x10c30c30c30c30c3ull;
  v = (v | (v >> 4)) & 0x100f00f00f00f00full;
  v = (v | (v >> 8)) & 0x1f0000ff0000ffull;
  v = (v | (v >> 16)) & 0x1f00000000ffffull;
  v = (v | (v >> 32)) & 0x1fffffull;
  return static_cast<std::uint32_t>(v);
}

// Key of cell (x, y, z) on a 2^order grid; x is the most significant bit of each triple.
QDEMSPH_HD std::uint64_t morton_key(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return (sfc_spread3(x) << 2) | (sfc_spread3(y) << 1) | sfc_spread3(z);
}

QDEMSPH_HD void morton_cell(std::uint64_t key, std::uint32_t& x, std::uint32_t& y,
                            std::uint32_t& z) {
  x = sfc_compact3(key >> 2);
  y = sfc_compact3(key >> 1);
  z = sfc_compact3(key);
}

// ---- Hilbert (Skilling) ----------------------------------------------------------------

// One step of Skilling's inverse undo for bit Q (P = Q - 1): the bits P of x0 inverted when bit
// Q of xi is set, else exchanged with those of xi. Without branches: masks instead of ifs on
// coordinate bits, which a processor cannot predict.
QDEMSPH_HD void hilbert_undo(std::uint32_t& x0, std::uint32_t& xi, std::uint32_t Q,
                             std::uint32_t P) {
  const std::uint32_t set = 0u - ((xi & Q) != 0);  // all ones when bit Q is set
  const std::uint32_t t = (x0 ^ xi) & P & ~set;
  x0 ^= t ^ (P & set);
  xi ^= t;
}

// Key of cell (x, y, z) on a 2^order grid, 1 <= order <= 21. At order 16 on the 2-core VM
// (-O3): ~50 ns a key, against ~75 ns with Skilling's ifs on cells in spatial order and ~105 on
// random cells.
QDEMSPH_HD std::uint64_t hilbert_key(std::uint32_t x, std::uint32_t y, std::uint32_t z, int order) {
  // Inverse undo, for each bit from the top (the coordinates in registers, not an array).
  for (std::uint32_t Q = 1u << (order - 1); Q > 1; Q >>= 1) {
    const std::uint32_t P = Q - 1;
    x ^= P & (0u - ((x & Q) != 0));  // against itself: inverted or nothing
    hilbert_undo(x, y, Q, P);
    hilbert_undo(x, z, Q, P);
  }
  // Gray encode.
  y ^= x;
  z ^= y;
  // t = the XOR of Q - 1 over the set bits Q > 1 of z: bit j of t is the parity of the bits of
  // z above j (a suffix XOR of z >> 1).
  std::uint32_t t = z >> 1;
  t ^= t >> 1;
  t ^= t >> 2;
  t ^= t >> 4;
  t ^= t >> 8;
  t ^= t >> 16;
  // The transposed index: bit b of the key triple j is bit j of x, y, z.
  return morton_key(x ^ t, y ^ t, z ^ t);
}

QDEMSPH_HD void hilbert_cell(std::uint64_t key, int order, std::uint32_t& x, std::uint32_t& y,
                             std::uint32_t& z) {
  std::uint32_t X[3];
  morton_cell(key, X[0], X[1], X[2]);
  const std::uint32_t N = 2u << (order - 1);
  // Gray decode by H ^ (H / 2).
  std::uint32_t t = X[2] >> 1;
  X[2] ^= X[1];
  X[1] ^= X[0];
  X[0] ^= t;
  // Undo excess work.
  for (std::uint32_t Q = 2; Q != N; Q <<= 1) {
    const std::uint32_t P = Q - 1;
    for (int i = 2; i >= 0; --i) {
      if (X[i] & Q) {
        X[0] ^= P;
      } else {
        t = (X[0] ^ X[i]) & P;
        X[0] ^= t;
        X[i] ^= t;
      }
    }
  }
  x = X[0];
  y = X[1];
  z = X[2];
}

// ---- Peano (3^k serpentine) ------------------------------------------------------------

QDEMSPH_HD std::uint32_t sfc_pow3(int k) {
  std::uint32_t p = 1;
  for (int i = 0; i < k; ++i) p *= 3;
  return p;
}

// Key of cell (x, y, z) on a 3^order grid, 1 <= order <= 13. A reflection keeps a digit's
// parity, so the parities that decide the reflections can be read from the coordinate
// digits as well as from the key digits.
QDEMSPH_HD std::uint64_t peano_key(std::uint32_t x, std::uint32_t y, std::uint32_t z, int order) {
  const std::uint32_t c[3] = {x, y, z};
  unsigned parity[3] = {0, 0, 0};  // parity of the preceding digits of each axis
  std::uint64_t key = 0;
  std::uint32_t scale = sfc_pow3(order - 1);
  for (int l = 0; l < order; ++l, scale /= 3) {
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t cd = (c[a] / scale) % 3;
      const unsigned others = parity[0] ^ parity[1] ^ parity[2] ^ parity[a];
      const std::uint32_t kd = others ? 2 - cd : cd;
      key = key * 3 + kd;
      parity[a] ^= kd & 1u;
    }
  }
  return key;
}

QDEMSPH_HD void peano_cell(std::uint64_t key, int order, std::uint32_t& x, std::uint32_t& y,
                           std::uint32_t& z) {
  std::uint32_t c[3] = {0, 0, 0};
  unsigned parity[3] = {0, 0, 0};
  std::uint64_t div = 1;
  for (int i = 1; i < 3 * order; ++i) div *= 3;
  for (int l = 0; l < order; ++l) {
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t kd = static_cast<std::uint32_t>((key / div) % 3);
      div /= 3;
      const unsigned others = parity[0] ^ parity[1] ^ parity[2] ^ parity[a];
      c[a] = c[a] * 3 + (others ? 2 - kd : kd);
      parity[a] ^= kd & 1u;
    }
  }
  x = c[0];
  y = c[1];
  z = c[2];
}

// ---- Selection -------------------------------------------------------------------------

// Key of cell (x, y, z) on a grid of curve_base(c)^order cells per axis.
QDEMSPH_HD std::uint64_t sfc_key(Curve c, std::uint32_t x, std::uint32_t y, std::uint32_t z,
                                 int order) {
  switch (c) {
    case Curve::Morton:
      return morton_key(x, y, z);
    case Curve::Hilbert:
      return hilbert_key(x, y, z, order);
    default:
      return peano_key(x, y, z, order);
  }
}

QDEMSPH_HD void sfc_cell(Curve c, std::uint64_t key, int order, std::uint32_t& x, std::uint32_t& y,
                         std::uint32_t& z) {
  switch (c) {
    case Curve::Morton:
      morton_cell(key, x, y, z);
      break;
    case Curve::Hilbert:
      hilbert_cell(key, order, x, y, z);
      break;
    default:
      peano_cell(key, order, x, y, z);
      break;
  }
}

}  // namespace qdemsph
