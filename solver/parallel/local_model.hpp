// A rank's part of a distributed model (docs/parallel.md): the vertices and tets it holds,
// renumbered locally, as a Model its backend uploads unchanged. Pure functions, no MPI: the
// distributed backend (distributed_backend.cpp) decides what a rank holds, this file builds
// it from the global model, which every rank keeps as the immutable description of the scene
// (reference geometry, masses, loads, connectivity, contact topology). Only the dynamic state
// (x, v, dissipation, contact history) moves between ranks.
//
// Local order:
//   vertices  [owned free | free ghosts | fixed-body vertices]; the backend integrates and
//             gathers forces for [0, n_owned) only (Model::n_free_vertices = n_owned), ghost
//             x and v arrive by halo exchange, fixed bodies never move (x = X).
//   tets      free tets only: [interior home | boundary home | halo]; interior tets have all
//             four vertices owned (computed while the halo exchange is in flight), home tets
//             count in the energies (Model::n_counted_tets = n_home), halo tets are the
//             other ranks' tets with an owned vertex, computed here too so that every owned
//             vertex gathers its complete force locally. The backend sums the corners of a
//             vertex ordered by tet global id, so forces equal those of one rank bit for bit.
//   contact   the primitives whose vertices are all local, in global order (free bodies
//             first); their triangles, edges and feature ownership as in the global model.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "contact/contact_record.hpp"
#include "core/vec.hpp"
#include "model/model.hpp"

namespace qdemsph {

// Lookups over the global model, built once per run on every rank.
struct ModelIndex {
  // Vertex -> free tets containing it, by corner: the tets whose corner k is vertex v at
  // [corner_off[4 v + k], corner_off[4 v + k + 1]) of corner_tet, in increasing order (so the
  // whole list of v, [corner_off[4 v], corner_off[4 v + 4]), holds each of its tets once).
  std::vector<std::int64_t> corner_off;
  std::vector<std::int32_t> corner_tet;
  std::vector<std::int32_t> tets_at;  // free tets whose smallest vertex id is this vertex
  std::vector<std::array<std::int32_t, 3>> tri_edges;  // surface triangle -> its edges
  // Per body, its tets, contact primitives, triangles and edges (a tet's and an edge's body:
  // its first vertex's): items [off[b], off[b + 1]) of body b. index_model throws
  // std::logic_error for a model that does not group them by body in body order (build_model
  // does): a rank's layout searches only the bodies it touches (body_items).
  std::vector<std::int64_t> body_tet_off, body_prim_off, body_tri_off, body_edge_off;
  // Per body: its primitives name only its triangles, each of its triangles is named by one of
  // them, and its edges are those of its triangles. A part holding every vertex of such a body
  // holds all its primitives, triangles and edges, taken without a test.
  std::vector<std::uint8_t> body_closed;
  std::vector<std::uint8_t> contact_vertex;  // a vertex of some contact primitive
  std::vector<std::uint8_t> wall_vertex;     // tested against walls
  double prim_radius = 0;  // largest primitive radius (centroid to vertex) in the reference
};

ModelIndex index_model(const Model& global);

// The items of the chosen bodies, in order: [off[b], off[b + 1]) for each b with chosen[b]
// (off: one of ModelIndex's per-body offsets).
std::vector<std::int64_t> body_items(const std::vector<std::int64_t>& off,
                                     const std::vector<std::uint8_t>& chosen);

// What a rank holds, as global ids in local order (see above).
struct LocalLayout {
  std::vector<std::int64_t> vertices;
  std::int64_t n_owned = 0;  // owned free vertices first
  std::int64_t n_free = 0;   // owned + free ghosts; fixed-body vertices after
  std::vector<std::int64_t> tets;
  std::int64_t n_interior = 0, n_home = 0;
  // Per body, BodyWhole: whether one rank owns all its free vertices, this one or another
  // (ContactModel::body_whole; empty: every body split).
  std::vector<std::uint8_t> body_whole;
};

// Local <-> global ids of the features contact keys use (contact_record.hpp: k1 = type << 60
// | id1, k2 = id2; point-face (vertex, triangle), edge-edge (edge, edge), wall (vertex, wall)).
// Vertices are keyed by global id in every model; triangles and edges are numbered per model
// in global order, so translated keys sort the same way, and the contact records of a rank
// are in the same order as on one rank.
class FeatureIds {
 public:
  std::vector<std::int64_t> vertex, triangle, edge;  // local -> global
  // Global -> local, one entry per global vertex, triangle, edge (-1: not held): lookups in
  // O(1) for a rebuild's history, written where the lists are.
  std::vector<std::int32_t> vertex_local, triangle_local, edge_local;
  std::uint64_t k1_to_global(std::uint64_t k1) const;
  std::uint64_t k2_to_global(std::uint64_t k1, std::uint64_t k2) const;
  // kNone when the feature is not held locally.
  static constexpr std::uint64_t kNone = ~std::uint64_t{0};
  std::uint64_t k1_to_local(std::uint64_t k1) const;
  std::uint64_t k2_to_local(std::uint64_t k1, std::uint64_t k2) const;
  std::int64_t local_vertex(std::int64_t gid) const;  // -1 when not local
};

struct LocalModel {
  Model model;
  FeatureIds ids;
  // Global -> local tet numbers of the last build (-1: not held), kept so that a rebuild
  // writes them in place.
  std::vector<std::int32_t> tet_local;
};

// The rank's Model. x and v are given for the listed vertices (ghost values may be stale:
// the first halo exchange overwrites them); everything else comes from the global model.
// with_contact = false leaves the contact stage out (used for output-only models).
LocalModel build_local_model(const Model& global, const ModelIndex& index,
                             const LocalLayout& layout, const std::vector<Vec3>& x,
                             const std::vector<Vec3>& v, bool with_contact = true);
// The same into `out`, whose arrays (an earlier part's) keep their storage: a rank rebuilding
// its part every few hundred steps touches no fresh pages for the large ones. same_tets: `out`
// was built for a layout with the same owned vertices and tets, in the same order (a rebuild
// of the ghosts alone): the tets' reference data, the owned vertices' reference data and
// corner lists, and the interior tets' vertex numbers stand; x and v, the ghosts and the other
// tets' vertex numbers are written again.
void build_local_model(const Model& global, const ModelIndex& index, const LocalLayout& layout,
                       const std::vector<Vec3>& x, const std::vector<Vec3>& v, LocalModel& out,
                       bool with_contact = true, bool same_tets = false);

}  // namespace qdemsph
