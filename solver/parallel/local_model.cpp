#include "parallel/local_model.hpp"

#include <algorithm>
#include <atomic>
#include <numeric>
#include <stdexcept>
#include <string>

#include "contact/contact_record.hpp"
#include "core/exec_host.hpp"
#include "core/radix_sort.hpp"
#include "core/select_host.hpp"

namespace qdemsph {

namespace {

template <class T>
std::int64_t find_sorted(const std::vector<T>& v, T x) {
  const auto it = std::lower_bound(v.begin(), v.end(), x);
  return it != v.end() && *it == x ? it - v.begin() : -1;
}

constexpr std::uint64_t kIdMask = (std::uint64_t{1} << 60) - 1;

}  // namespace

ModelIndex index_model(const Model& g) {
  ModelIndex ix;
  const std::int64_t nv = g.n_vertices(), nft = g.n_free_tets;
  ix.corner_off.assign(4 * nv + 1, 0);
  for (std::int64_t t = 0; t < nft; ++t)
    for (int k = 0; k < 4; ++k) ++ix.corner_off[4 * g.tets[t][k] + k + 1];
  std::partial_sum(ix.corner_off.begin(), ix.corner_off.end(), ix.corner_off.begin());
  ix.corner_tet.resize(ix.corner_off.back());
  std::vector<std::int64_t> fill(ix.corner_off.begin(), ix.corner_off.end() - 1);
  for (std::int64_t t = 0; t < nft; ++t)
    for (int k = 0; k < 4; ++k)
      ix.corner_tet[fill[4 * g.tets[t][k] + k]++] = static_cast<std::int32_t>(t);
  ix.tets_at.assign(nv, 0);
  for (std::int64_t t = 0; t < nft; ++t)
    ++ix.tets_at[*std::min_element(g.tets[t].begin(), g.tets[t].end())];
  ix.contact_vertex.assign(nv, 0);
  ix.wall_vertex.assign(nv, 0);
  const ContactModel& c = g.contact;
  if (!c.enabled) return ix;
  const std::int64_t np = static_cast<std::int64_t>(c.prim_v.size());
  for (std::int64_t p = 0; p < np; ++p) {
    Vec3 ctr{0, 0, 0};
    int n = 0;
    for (int k = 0; k < 4 && c.prim_v[p][k] >= 0; ++k, ++n) {
      ix.contact_vertex[c.prim_v[p][k]] = 1;
      ctr += g.X[c.prim_v[p][k]];
    }
    ctr = ctr / static_cast<double>(n);
    for (int k = 0; k < n; ++k)
      ix.prim_radius = std::max(ix.prim_radius, norm(g.X[c.prim_v[p][k]] - ctr));
  }
  for (auto w : c.wall_vertices) ix.wall_vertex[w] = 1;
  ix.tri_edges.resize(c.tri_v.size());
  for (std::size_t s = 0; s < c.tri_v.size(); ++s)
    for (int q = 0; q < 3; ++q) {
      const std::int32_t a = c.tri_v[s][q], b = c.tri_v[s][(q + 1) % 3];
      const std::array<std::int32_t, 2> e{std::min(a, b), std::max(a, b)};
      ix.tri_edges[s][q] = static_cast<std::int32_t>(
          std::lower_bound(c.edges.begin(), c.edges.end(), e) - c.edges.begin());
    }
  return ix;
}

void FeatureIds::finish() {
  const auto n = static_cast<std::int64_t>(vertex.size());
  vertex_inv_.resize(n);
  for_each(HostExec{}, n, [&](std::int64_t i) { vertex_inv_[i] = {vertex[i], i}; });
  std::vector<std::pair<std::uint64_t, std::int64_t>> scratch;
  radix_sort(vertex_inv_, scratch);  // unique global ids
}

std::int64_t FeatureIds::local_vertex(std::int64_t gid) const {
  if (gid < 0) return -1;
  const auto g = static_cast<std::uint64_t>(gid);
  const auto it = std::lower_bound(vertex_inv_.begin(), vertex_inv_.end(),
                                   std::pair<std::uint64_t, std::int64_t>{g, -1});
  return it != vertex_inv_.end() && it->first == g ? it->second : -1;
}

// Vertex features are keyed by global id already (ContactTopology::vgid): only edges and
// triangles, numbered per model, are translated.
std::uint64_t FeatureIds::k1_to_global(std::uint64_t k1) const {
  const int type = static_cast<int>(k1 >> 60);
  if (type != kEdgeEdge) return k1;
  return contact_key1(type, static_cast<std::uint64_t>(edge[k1 & kIdMask]));
}

std::uint64_t FeatureIds::k2_to_global(std::uint64_t k1, std::uint64_t k2) const {
  const int type = static_cast<int>(k1 >> 60);
  if (type == kPointFace) return static_cast<std::uint64_t>(triangle[k2]);
  if (type == kEdgeEdge) return static_cast<std::uint64_t>(edge[k2]);
  return k2;  // wall index
}

std::uint64_t FeatureIds::k1_to_local(std::uint64_t k1) const {
  const int type = static_cast<int>(k1 >> 60);
  const std::int64_t id = static_cast<std::int64_t>(k1 & kIdMask);
  const std::int64_t l = type == kEdgeEdge ? find_sorted(edge, id) : local_vertex(id);
  if (l < 0) return kNone;
  return type == kEdgeEdge ? contact_key1(type, static_cast<std::uint64_t>(l)) : k1;
}

std::uint64_t FeatureIds::k2_to_local(std::uint64_t k1, std::uint64_t k2) const {
  const int type = static_cast<int>(k1 >> 60);
  if (type == kWall) return k2;
  const std::int64_t l =
      find_sorted(type == kPointFace ? triangle : edge, static_cast<std::int64_t>(k2));
  return l < 0 ? kNone : static_cast<std::uint64_t>(l);
}

ContactShare FeatureIds::to_global(ContactShare s) const {
  s.k2 = k2_to_global(s.k1, s.k2);
  s.k1 = k1_to_global(s.k1);
  s.vertex = vertex[s.vertex];
  return s;
}

ContactShare FeatureIds::to_local(ContactShare s) const {
  const std::uint64_t k1 = k1_to_local(s.k1);
  const std::uint64_t k2 = k1 == kNone ? kNone : k2_to_local(s.k1, s.k2);
  const std::int64_t v = local_vertex(s.vertex);
  if (k2 == kNone || v < 0)
    throw std::logic_error("contact share of vertex " + std::to_string(s.vertex) +
                           " names a feature this rank does not hold (key " + std::to_string(s.k1) +
                           ", " + std::to_string(s.k2) + ")");
  s.k1 = k1;
  s.k2 = k2;
  s.vertex = v;
  return s;
}

LocalModel build_local_model(const Model& g, const ModelIndex& ix, const LocalLayout& L,
                             const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                             bool with_contact) {
  LocalModel out;
  build_local_model(g, ix, L, x, v, out, with_contact);
  return out;
}

// Every array of `out` is overwritten whole (resized, then written), never appended to.
void build_local_model(const Model& g, const ModelIndex& ix, const LocalLayout& L,
                       const std::vector<Vec3>& x, const std::vector<Vec3>& v, LocalModel& out,
                       bool with_contact) {
  const std::int64_t nv = static_cast<std::int64_t>(L.vertices.size());
  if (static_cast<std::int64_t>(x.size()) != nv || static_cast<std::int64_t>(v.size()) != nv)
    throw std::invalid_argument("build_local_model: x and v need one entry per listed vertex");
  Model& m = out.model;
  // Global -> local numbers (-1: not held), written in parallel into the kept arrays.
  auto number = [](std::vector<std::int32_t>& to_local, std::int64_t n_global,
                   const std::vector<std::int64_t>& held) {
    resize_for_overwrite(to_local, static_cast<std::size_t>(n_global));
    for_each(HostExec{}, n_global, [&](std::int64_t i) { to_local[i] = -1; });
    for_each(HostExec{}, static_cast<std::int64_t>(held.size()),
             [&](std::int64_t i) { to_local[held[i]] = static_cast<std::int32_t>(i); });
  };
  std::vector<std::int32_t>& g2l = out.vertex_local;
  number(g2l, g.n_vertices(), L.vertices);
  auto local = [&](std::int64_t gid) {
    const std::int32_t l = g2l[gid];
    if (l < 0)
      throw std::logic_error("build_local_model: vertex " + std::to_string(gid) +
                             " of a held item is not in the layout");
    return l;
  };
  // Per-item copies from the global model, in parallel.
  auto gather = [](const auto& from, const std::vector<std::int64_t>& idx, auto& to) {
    to.resize(idx.size());
    for_each(HostExec{}, static_cast<std::int64_t>(idx.size()),
             [&](std::int64_t i) { to[i] = from[idx[i]]; });
  };
  gather(g.X, L.vertices, m.X);
  gather(g.fext, L.vertices, m.fext);
  gather(g.fpre, L.vertices, m.fpre);
  gather(g.mass, L.vertices, m.mass);
  gather(g.inv_mass, L.vertices, m.inv_mass);
  gather(g.relax_inv_mass, L.vertices, m.relax_inv_mass);
  gather(g.flags, L.vertices, m.flags);
  gather(g.gid, L.vertices, m.gid);
  gather(g.body, L.vertices, m.body);
  m.x = x;
  m.v = v;
  gather(g.dX_inv, L.tets, m.dX_inv);
  gather(g.vol0, L.tets, m.vol0);
  gather(g.tet_material, L.tets, m.tet_material);
  gather(g.tet_gid, L.tets, m.tet_gid);
  const std::int64_t nt = static_cast<std::int64_t>(L.tets.size());
  m.tets.resize(nt);
  std::atomic<std::int64_t> missing{-1};  // a vertex of a held tet not in the layout
  for_each(HostExec{}, nt, [&](std::int64_t j) {
    for (int k = 0; k < 4; ++k) {
      const std::int64_t gi = g.tets[L.tets[j]][k];
      m.tets[j][k] = g2l[gi];
      if (g2l[gi] < 0) missing.store(gi, std::memory_order_relaxed);
    }
  });
  if (missing >= 0) local(missing);
  // CSR offsets, counted in parallel.
  auto offsets = [](std::int64_t n, std::vector<std::int64_t>& off, auto count) {
    off.assign(n + 1, 0);
    for_each(HostExec{}, n, [&](std::int64_t j) { off[j + 1] = count(j); });
    std::partial_sum(off.begin(), off.end(), off.begin());
  };
  // The owned vertices' corner lists (Model::corner_off): the global lists by corner, each in
  // tet gid order, renumbered (every free tet of an owned vertex is held), so in the one-rank
  // order with no sort.
  std::vector<std::int32_t>& tl = out.tet_local;
  number(tl, g.n_tets(), L.tets);
  const std::int64_t no = L.n_owned;
  offsets(no, m.corner_off, [&](std::int64_t i) {
    return ix.corner_off[4 * L.vertices[i] + 4] - ix.corner_off[4 * L.vertices[i]];
  });
  m.corner_ent.resize(m.corner_off[no]);
  std::atomic<std::int64_t> unheld{-1};  // a tet of an owned vertex not held
  for_each(HostExec{}, no, [&](std::int64_t i) {
    const std::int64_t gv = L.vertices[i];
    std::int64_t o = m.corner_off[i];
    for (std::int64_t k = 0; k < 4; ++k)
      for (std::int64_t q = ix.corner_off[4 * gv + k]; q < ix.corner_off[4 * gv + k + 1]; ++q) {
        const std::int32_t t = tl[ix.corner_tet[q]];
        if (t < 0) unheld.store(ix.corner_tet[q], std::memory_order_relaxed);
        m.corner_ent[o++] = k * nt + t;
      }
  });
  if (unheld >= 0)
    throw std::logic_error("build_local_model: tet " + std::to_string(unheld) +
                           " of an owned vertex is not in the layout");
  m.materials = g.materials;
  m.bodies = g.bodies;
  m.n_free_vertices = L.n_owned;
  m.n_free_tets = static_cast<std::int64_t>(L.tets.size());
  m.n_counted_tets = L.n_home;
  m.gravity = g.gravity;
  m.mass_damping = g.mass_damping;
  m.relax_dt = g.relax_dt;
  m.dt_critical = g.dt_critical;
  m.dt_critical_tet = g.dt_critical_tet;
  out.ids.vertex = L.vertices;

  const ContactModel& gc = g.contact;
  ContactModel& c = m.contact;
  if (!with_contact || !gc.enabled) {
    c = ContactModel{};
    c.mode = gc.mode;
    c.n_surface_tets = gc.n_surface_tets;
    out.ids.triangle.clear();
    out.ids.edge.clear();
    out.ids.finish();
    return;
  }
  c.mode = gc.mode;
  c.n_surface_tets = gc.n_surface_tets;
  c.enabled = true;
  c.d_dem = gc.d_dem;
  c.self_contact = gc.self_contact;
  c.kn_factor = gc.kn_factor;
  c.kt_ratio = gc.kt_ratio;
  c.skin = gc.skin;
  c.max_penetration = gc.max_penetration;
  c.walls = gc.walls;
  c.body_h = gc.body_h;
  c.body_fixed = gc.body_fixed;
  c.body_mat = gc.body_mat;
  c.n_mat = gc.n_mat;
  c.pair_mu = gc.pair_mu;
  c.pair_zeta = gc.pair_zeta;
  c.pair_kn = gc.pair_kn;
  c.pair_E = gc.pair_E;
  c.dt_limit = gc.dt_limit;

  // Primitives with every vertex local, in global order (free bodies first): each global
  // primitive tested in parallel, the kept ones collected in order.
  const std::int64_t ngp = static_cast<std::int64_t>(gc.prim_v.size());
  std::vector<std::uint8_t> keep(ngp);
  for_each(HostExec{}, ngp, [&](std::int64_t p) {
    bool all = true;
    for (int k = 0; k < 4; ++k) all = all && (gc.prim_v[p][k] < 0 || g2l[gc.prim_v[p][k]] >= 0);
    keep[p] = all;
  });
  const std::vector<std::int64_t> prims =
      select_indices(HostExec{}, ngp, [&](std::int64_t p) { return keep[p] != 0; });
  const auto npl = static_cast<std::int64_t>(prims.size());
  // Their triangles and the triangles' edges, in global order (marked, then collected), and
  // global -> local numbers (-1: not held).
  auto mark = [](std::int32_t& m) {
    std::atomic_ref<std::int32_t>(m).store(1, std::memory_order_relaxed);
  };
  auto collect = [](std::vector<std::int32_t>& marks, std::vector<std::int64_t>& out) {
    const auto n = static_cast<std::int64_t>(marks.size());
    out = select_indices(HostExec{}, n, [&](std::int64_t e) { return marks[e] != 0; });
    for_each(HostExec{}, n, [&](std::int64_t e) { marks[e] = -1; });
    for_each(HostExec{}, static_cast<std::int64_t>(out.size()),
             [&](std::int64_t j) { marks[out[j]] = static_cast<std::int32_t>(j); });
  };
  std::vector<std::int64_t>& tris = out.ids.triangle;
  std::vector<std::int32_t> tri_l(gc.tri_v.size(), 0);
  for_each(HostExec{}, npl, [&](std::int64_t j) {
    for (std::int64_t q = gc.prim_tri_off[prims[j]]; q < gc.prim_tri_off[prims[j] + 1]; ++q)
      mark(tri_l[gc.prim_tri[q]]);
  });
  collect(tri_l, tris);
  const auto ntl = static_cast<std::int64_t>(tris.size());
  std::vector<std::int64_t>& edges = out.ids.edge;
  std::vector<std::int32_t> edge_l(gc.edges.size(), 0);
  for_each(HostExec{}, ntl, [&](std::int64_t j) {
    for (int q = 0; q < 3; ++q) mark(edge_l[ix.tri_edges[tris[j]][q]]);
  });
  collect(edge_l, edges);
  const auto nel = static_cast<std::int64_t>(edges.size());
  // The local lists, written in parallel (CSR offsets first).
  auto lv = [&](std::int64_t gid) {  // local index; a missing vertex is recorded
    const std::int32_t l = g2l[gid];
    if (l < 0) missing.store(gid, std::memory_order_relaxed);
    return l;
  };
  c.tri_v.resize(ntl);
  c.tri_body.resize(ntl);
  offsets(ntl, c.own_v_off,
          [&](std::int64_t j) { return gc.own_v_off[tris[j] + 1] - gc.own_v_off[tris[j]]; });
  offsets(ntl, c.own_e_off,
          [&](std::int64_t j) { return gc.own_e_off[tris[j] + 1] - gc.own_e_off[tris[j]]; });
  c.own_v.resize(c.own_v_off[ntl]);
  c.own_e.resize(c.own_e_off[ntl]);
  for_each(HostExec{}, ntl, [&](std::int64_t j) {
    const std::int64_t s = tris[j];
    c.tri_v[j] = {lv(gc.tri_v[s][0]), lv(gc.tri_v[s][1]), lv(gc.tri_v[s][2])};
    c.tri_body[j] = gc.tri_body[s];
    std::int64_t o = c.own_v_off[j];
    for (std::int64_t q = gc.own_v_off[s]; q < gc.own_v_off[s + 1]; ++q)
      c.own_v[o++] = lv(gc.own_v[q]);
    o = c.own_e_off[j];
    for (std::int64_t q = gc.own_e_off[s]; q < gc.own_e_off[s + 1]; ++q)
      c.own_e[o++] = edge_l[gc.own_e[q]];
  });
  c.edges.resize(nel);
  c.edge_tri.resize(nel);
  for_each(HostExec{}, nel, [&](std::int64_t j) {
    const std::int64_t e = edges[j];
    // Endpoints keep the global order (edge-edge geometry is evaluated a0 -> a1).
    c.edges[j] = {lv(gc.edges[e][0]), lv(gc.edges[e][1])};
    for (int k = 0; k < 2; ++k)
      c.edge_tri[j][k] = gc.edge_tri[e][k] >= 0 ? tri_l[gc.edge_tri[e][k]] : -1;
  });
  c.prim_v.resize(npl);
  c.prim_body.resize(npl);
  offsets(npl, c.prim_tri_off, [&](std::int64_t j) {
    return gc.prim_tri_off[prims[j] + 1] - gc.prim_tri_off[prims[j]];
  });
  c.prim_tri.resize(c.prim_tri_off[npl]);
  for_each(HostExec{}, npl, [&](std::int64_t j) {
    const std::int64_t p = prims[j];
    for (int k = 0; k < 4; ++k) c.prim_v[j][k] = gc.prim_v[p][k] >= 0 ? lv(gc.prim_v[p][k]) : -1;
    c.prim_body[j] = gc.prim_body[p];
    std::int64_t o = c.prim_tri_off[j];
    for (std::int64_t q = gc.prim_tri_off[p]; q < gc.prim_tri_off[p + 1]; ++q)
      c.prim_tri[o++] = tri_l[gc.prim_tri[q]];
  });
  if (missing >= 0) local(missing);
  // Free bodies' primitives come first: the count up to the last free one.
  c.n_free_prims = npl;
  while (c.n_free_prims > 0 && gc.body_fixed[c.prim_body[c.n_free_prims - 1]]) --c.n_free_prims;
  const std::vector<std::int64_t> wall = select_indices(
      HostExec{}, L.n_owned, [&](std::int64_t i) { return ix.wall_vertex[L.vertices[i]] != 0; });
  c.wall_vertices.assign(wall.begin(), wall.end());
  out.ids.finish();
}

}  // namespace qdemsph
