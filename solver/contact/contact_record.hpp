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
#include <vector>

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

QDEMSPH_HD std::uint64_t contact_key1(int type, std::uint64_t id1) {
  return (static_cast<std::uint64_t>(type) << 60) | id1;
}

// The id1 bits of k1.
inline constexpr std::uint64_t kIdMask = (std::uint64_t{1} << 60) - 1;

// The key order (k1, then k2) in one 64-bit key, for sorting: the type, then id1's rank in its
// b1 bits, then k2 in its b2 bits. rank1: a number ordered as id1 among the records sorted
// together (id1 itself, or a vertex's place among its model's vertices by global id: fewer bits
// than a global id, as many at any rank count), rank1 < 2^b1, k2 < 2^b2, b1 + b2 <= 62
// (b12 = b1 + b2).
QDEMSPH_HD std::uint64_t sort_key(const ContactRecord& r, std::uint64_t rank1, int b2, int b12) {
  return (r.k1 >> 60) << b12 | rank1 << b2 | r.k2;
}

// A key of a rank's model in global feature ids: vertices are keyed by global id already
// (ContactTopology::vgid), edges and triangles are numbered per model (in global order) and
// translated by `edge` and `triangle` (local -> global).
QDEMSPH_HD std::uint64_t global_key1(std::uint64_t k1, const std::int64_t* edge) {
  const int type = static_cast<int>(k1 >> 60);
  if (type != kEdgeEdge) return k1;
  return contact_key1(type, static_cast<std::uint64_t>(edge[k1 & kIdMask]));
}
QDEMSPH_HD std::uint64_t global_key2(std::uint64_t k1, std::uint64_t k2,
                                     const std::int64_t* triangle, const std::int64_t* edge) {
  const int type = static_cast<int>(k1 >> 60);
  if (type == kPointFace) return static_cast<std::uint64_t>(triangle[k2]);
  if (type == kEdgeEdge) return static_cast<std::uint64_t>(edge[k2]);
  return k2;  // wall index
}

// A hash of a body's id, 22 bits (body_order).
QDEMSPH_HD std::uint64_t body_priority(std::int64_t body) {
  std::uint64_t z = static_cast<std::uint64_t>(body) + 0x9E3779B97F4A7C15ull;  // splitmix64
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return (z ^ (z >> 31)) >> 42;
}

// A distributed rank's view of a body (ContactModel::body_whole): whether one rank owns all of
// its free vertices, this one or another; a fixed body, or a free one the cut divides, is split.
enum BodyWhole : std::uint8_t { kSplit = 0, kWholeHere = 1, kWholeElsewhere = 2 };

// A body's place in the order of anchors (23 bits): whole bodies (vs.whole(body)) first, then
// by body_priority. An edge pair of two bodies is anchored on the edge of the body that comes
// first, and so are the point-face touches on its faces when it is whole (face_leads): then
// one rank evaluates every record of the two bodies. A pair across a border goes to the rank
// holding one of its bodies whole wherever there is one, and the border's body pairs split
// between its ranks (the smallest global id alone gave all of them to one rank).
template <class Vertices>
QDEMSPH_HD std::uint64_t body_order(const Vertices& vs, std::int64_t body) {
  return (vs.whole(body) ? 0 : std::uint64_t{1} << 22) | body_priority(body);
}

// Whether the faces of body `face` take the point-face touches of body `point`'s vertices: the
// face's body is whole and comes first by body_order (as its edges anchor the pair's edge
// pairs). Then a pair of primitives across a border is tested on that body's rank only (the
// other rank drops it from its candidates), and the duplicate filter still sees all of a
// vertex's hits on one body on one rank.
template <class Vertices>
QDEMSPH_HD bool face_leads(const Vertices& vs, std::int64_t point, std::int64_t face) {
  return point != face && vs.whole(face) && body_order(vs, face) < body_order(vs, point);
}

// The slot of the record's anchor vertex: in a distributed run the rank owning it evaluates
// the record (once over the ranks) and keeps its history. A point-face record's face vertex
// when the face's body leads (face_leads), else its side-1 vertex when it is free, as a wall
// record's (the duplicate filter compares one vertex's point-face hits on one body, so they
// stay together); else the free vertex with the smallest global id, for an edge pair among
// those of the body first by body_order; -1 when no vertex is free. v: the record's vertex
// ids (-1: unused); vs.free(id), vs.gid(id), vs.body(id), vs.whole(body).
template <class Id, class Vertices>
QDEMSPH_HD int anchor_slot(int type, const Id* v, const Vertices& vs) {
  if (type != kEdgeEdge && v[0] >= 0 && vs.free(v[0]))
    return type == kPointFace && vs.free(v[1]) && face_leads(vs, vs.body(v[0]), vs.body(v[1])) ? 1
                                                                                               : 0;
  int best = -1;
  std::uint64_t best_p = 0;
  for (int k = 0; k < 4; ++k) {
    if (v[k] < 0 || !vs.free(v[k])) continue;
    const std::uint64_t p = type == kEdgeEdge ? body_order(vs, vs.body(v[k])) : 0;
    if (best < 0 || p < best_p || (p == best_p && vs.gid(v[k]) < vs.gid(v[best]))) {
      best = k;
      best_p = p;
    }
  }
  return best;
}

// A contact force share for a vertex another rank owns (a distributed run), as it travels:
// written so by the rank that evaluated the record (ContactStage::compact_shares, with the
// layout's ShareRoutes), read as it is by the owner, which sums its vertex's shares with its own
// entries in key, then slot order: the one-rank order.
struct ContactShare {
  std::uint64_t k1 = 0, k2 = 0;  // the record's key in global feature ids
  std::int64_t vertex = -1;      // the vertex's index in its owner's model
  std::int32_t slot = 0;         // the vertex's slot in the record
  std::int32_t rank = -1;        // the vertex's owner
  Vec3 f;
};

// Where a rank's shares go (a distributed layout, ContactStage::set_share_routes): for each
// free vertex it holds but does not own (local index n_owned + k), the owner's rank and the
// vertex's index there; and the global ids of its model's surface triangles and edges, which
// key the shares.
struct ShareRoutes {
  std::vector<std::int32_t> rank, index;
  std::vector<std::int64_t> triangle, edge;
};

}  // namespace qdemsph
