// One detected contact between two features (point-face, edge-edge or vertex-wall): the
// vertices that share its force with their weights, the geometry and the history key.
// Transient (rebuilt every step), trivially copyable.
//
// Key: k1 = type << 60 | id1, k2 = id2 with global feature ids that survive any re-sorting:
//   point-face (vertex gid, surface triangle id), edge-edge (edge id, edge id; lower first),
//   wall (vertex gid, wall index).
// Side 1 vertices v[0 .. n1), side 2 v[n1 .. 4) (v = -1: unused); side 1 gets +w_k F,
// side 2 gets -w_k F; the weights of each side sum to 1 (eq. 8 / segment ratio).
#pragma once

#include <cstdint>

#include "core/vec.hpp"

namespace qdemsph {

enum ContactType : int { kPointFace = 0, kEdgeEdge = 1, kWall = 2 };

struct ContactRecord {
  std::uint64_t k1 = 0, k2 = 0;
  std::int32_t v[4] = {-1, -1, -1, -1};
  double w[4] = {0, 0, 0, 0};
  Vec3 n;        // from side 2 towards side 1
  double d = 0;  // signed gap along n
  std::int32_t type = 0, n1 = 1;
  std::int32_t body1 = 0, body2 = -1;  // body2 = -1: wall (index in `wall`)
  std::int32_t wall = -1;
  std::int32_t active = 1;
};

QDEMSPH_HD bool key_less(const ContactRecord& a, const ContactRecord& b) {
  return a.k1 != b.k1 ? a.k1 < b.k1 : a.k2 < b.k2;
}

QDEMSPH_HD std::uint64_t contact_key1(int type, std::uint64_t id1) {
  return (static_cast<std::uint64_t>(type) << 60) | id1;
}

}  // namespace qdemsph
