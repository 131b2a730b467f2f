#include "parallel/local_model.hpp"

#include <algorithm>
#include <atomic>
#include <numeric>
#include <stdexcept>
#include <string>

#include "contact/contact_record.hpp"
#include "core/exec_host.hpp"
#include "core/select_host.hpp"

namespace qdemsph {

namespace {

// A global id's local number in a global -> local array (-1: not held, or past its end).
std::int64_t local_of(const std::vector<std::int32_t>& to_local, std::int64_t gid) {
  return gid >= 0 && gid < static_cast<std::int64_t>(to_local.size()) ? to_local[gid] : -1;
}

// Per-body offsets of n items whose bodies body_of(i) never decrease (ModelIndex); `what`
// names the items in the error for a model that does not group them by body.
template <class BodyOf>
std::vector<std::int64_t> body_offsets(std::int64_t n_bodies, std::int64_t n, const char* what,
                                       BodyOf body_of) {
  std::vector<std::int64_t> off(n_bodies + 1, 0);
  for (std::int64_t i = 0; i < n; ++i) {
    if (i > 0 && body_of(i) < body_of(i - 1))
      throw std::logic_error(std::string("index_model: the model's ") + what + " " +
                             std::to_string(i - 1) + " and " + std::to_string(i) +
                             " are not in body order");
    ++off[body_of(i) + 1];
  }
  std::partial_sum(off.begin(), off.end(), off.begin());
  return off;
}

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
  const auto nb = static_cast<std::int64_t>(g.bodies.size());
  ix.body_tet_off =
      body_offsets(nb, g.n_tets(), "tets", [&](std::int64_t t) { return g.body[g.tets[t][0]]; });
  ix.contact_vertex.assign(nv, 0);
  ix.wall_vertex.assign(nv, 0);
  ix.body_closed.assign(nb, 0);
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
  ix.body_prim_off =
      body_offsets(nb, np, "contact primitives", [&](std::int64_t p) { return c.prim_body[p]; });
  ix.body_tri_off = body_offsets(nb, static_cast<std::int64_t>(c.tri_v.size()), "triangles",
                                 [&](std::int64_t s) { return c.tri_body[s]; });
  ix.body_edge_off = body_offsets(nb, static_cast<std::int64_t>(c.edges.size()), "edges",
                                  [&](std::int64_t e) { return g.body[c.edges[e][0]]; });
  ix.tri_edges.resize(c.tri_v.size());
  for (std::size_t s = 0; s < c.tri_v.size(); ++s)
    for (int q = 0; q < 3; ++q) {
      const std::int32_t a = c.tri_v[s][q], b = c.tri_v[s][(q + 1) % 3];
      const std::array<std::int32_t, 2> e{std::min(a, b), std::max(a, b)};
      ix.tri_edges[s][q] = static_cast<std::int32_t>(
          std::lower_bound(c.edges.begin(), c.edges.end(), e) - c.edges.begin());
    }
  // body_closed: every triangle named by a primitive of its body and no other, every edge a
  // side of a triangle of its body.
  std::vector<std::uint8_t> named(c.tri_v.size(), 0), sided(c.edges.size(), 0);
  ix.body_closed.assign(nb, 1);
  for (std::int64_t p = 0; p < np; ++p)
    for (std::int64_t q = c.prim_tri_off[p]; q < c.prim_tri_off[p + 1]; ++q) {
      const std::int32_t s = c.prim_tri[q];
      named[s] = 1;
      if (c.tri_body[s] != c.prim_body[p]) ix.body_closed[c.prim_body[p]] = 0;
    }
  for (std::size_t s = 0; s < c.tri_v.size(); ++s) {
    if (!named[s]) ix.body_closed[c.tri_body[s]] = 0;
    for (int q = 0; q < 3; ++q) {
      const std::int32_t e = ix.tri_edges[s][q];
      if (e >= static_cast<std::int64_t>(c.edges.size()) || g.body[c.edges[e][0]] != c.tri_body[s])
        ix.body_closed[c.tri_body[s]] = 0;
      else
        sided[e] = 1;
    }
  }
  for (std::size_t e = 0; e < c.edges.size(); ++e)
    if (!sided[e]) ix.body_closed[g.body[c.edges[e][0]]] = 0;
  return ix;
}

std::int64_t FeatureIds::local_vertex(std::int64_t gid) const {
  return local_of(vertex_local, gid);
}

std::vector<std::int64_t> body_items(const std::vector<std::int64_t>& off,
                                     const std::vector<std::uint8_t>& chosen) {
  const auto nb = static_cast<std::int64_t>(chosen.size());
  std::vector<std::int64_t> first(nb + 1, 0);
  for (std::int64_t b = 0; b < nb; ++b)
    first[b + 1] = first[b] + (chosen[b] ? off[b + 1] - off[b] : 0);
  std::vector<std::int64_t> items(first[nb]);
  for_each_coarse(HostExec{}, nb, [&](std::int64_t b) {
    for (std::int64_t k = first[b]; k < first[b + 1]; ++k) items[k] = off[b] + (k - first[b]);
  });
  return items;
}

std::uint64_t FeatureIds::k1_to_global(std::uint64_t k1) const {
  return global_key1(k1, edge.data());
}

std::uint64_t FeatureIds::k2_to_global(std::uint64_t k1, std::uint64_t k2) const {
  return global_key2(k1, k2, triangle.data(), edge.data());
}

std::uint64_t FeatureIds::k1_to_local(std::uint64_t k1) const {
  const int type = static_cast<int>(k1 >> 60);
  const std::int64_t id = static_cast<std::int64_t>(k1 & kIdMask);
  const std::int64_t l = type == kEdgeEdge ? local_of(edge_local, id) : local_vertex(id);
  if (l < 0) return kNone;
  return type == kEdgeEdge ? contact_key1(type, static_cast<std::uint64_t>(l)) : k1;
}

std::uint64_t FeatureIds::k2_to_local(std::uint64_t k1, std::uint64_t k2) const {
  const int type = static_cast<int>(k1 >> 60);
  if (type == kWall) return k2;
  const std::int64_t l =
      local_of(type == kPointFace ? triangle_local : edge_local, static_cast<std::int64_t>(k2));
  return l < 0 ? kNone : static_cast<std::uint64_t>(l);
}

LocalModel build_local_model(const Model& g, const ModelIndex& ix, const LocalLayout& L,
                             const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                             bool with_contact) {
  LocalModel out;
  build_local_model(g, ix, L, x, v, out, with_contact);
  return out;
}

// Every array of `out` is overwritten whole (resized, then written), never appended to; an
// array that must grow takes 1/8 more room (resize_for_overwrite), as a rank's part grows and
// shrinks a little from one layout to the next, and nothing of its old contents is copied.
void build_local_model(const Model& g, const ModelIndex& ix, const LocalLayout& L,
                       const std::vector<Vec3>& x, const std::vector<Vec3>& v, LocalModel& out,
                       bool with_contact, bool same_tets) {
  const std::int64_t nv = static_cast<std::int64_t>(L.vertices.size());
  if (static_cast<std::int64_t>(x.size()) != nv || static_cast<std::int64_t>(v.size()) != nv)
    throw std::invalid_argument("build_local_model: x and v need one entry per listed vertex");
  Model& m = out.model;
  FeatureIds& ids = out.ids;
  auto fit = [](std::int64_t n, auto&... a) {
    (resize_for_overwrite(a, static_cast<std::size_t>(n)), ...);
  };
  // Global -> local numbers (-1: not held), written in parallel into the kept arrays.
  auto number = [&](std::vector<std::int32_t>& to_local, std::int64_t n_global,
                    const std::vector<std::int64_t>& held) {
    fit(n_global, to_local);
    for_each(HostExec{}, n_global, [&](std::int64_t i) { to_local[i] = -1; });
    for_each(HostExec{}, static_cast<std::int64_t>(held.size()),
             [&](std::int64_t i) { to_local[held[i]] = static_cast<std::int32_t>(i); });
  };
  const std::vector<std::int32_t>& g2l = ids.vertex_local;
  number(ids.vertex_local, g.n_vertices(), L.vertices);
  auto local = [&](std::int64_t gid) {
    const std::int32_t l = g2l[gid];
    if (l < 0)
      throw std::logic_error("build_local_model: vertex " + std::to_string(gid) +
                             " of a held item is not in the layout");
    return l;
  };
  // Per-vertex and per-tet copies from the global model, one parallel pass each. same_tets:
  // the owned vertices' reference data and the interior tets' vertex numbers (owned vertices
  // only) stand, the arrays keep their prefix as the ghosts change; x and v are written whole.
  const std::int64_t no = L.n_owned;
  if (same_tets) {
    for (auto* a : {&m.X, &m.x, &m.v, &m.fext, &m.fpre}) a->resize(nv);
    for (auto* a : {&m.mass, &m.inv_mass, &m.relax_inv_mass}) a->resize(nv);
    m.flags.resize(nv);
    m.gid.resize(nv);
    m.body.resize(nv);
    fit(nv, ids.vertex);
  } else {
    fit(nv, m.X, m.x, m.v, m.fext, m.fpre, m.mass, m.inv_mass, m.relax_inv_mass, m.flags, m.gid,
        m.body, ids.vertex);
  }
  for_each(HostExec{}, nv, [&](std::int64_t i) {
    const std::int64_t gv = L.vertices[i];
    m.x[i] = x[i];
    m.v[i] = v[i];
    ids.vertex[i] = gv;
    if (same_tets && i < no) return;
    m.X[i] = g.X[gv];
    m.fext[i] = g.fext[gv];
    m.fpre[i] = g.fpre[gv];
    m.mass[i] = g.mass[gv];
    m.inv_mass[i] = g.inv_mass[gv];
    m.relax_inv_mass[i] = g.relax_inv_mass[gv];
    m.flags[i] = g.flags[gv];
    m.gid[i] = g.gid[gv];
    m.body[i] = g.body[gv];
  });
  const std::int64_t nt = static_cast<std::int64_t>(L.tets.size());
  if (same_tets && (static_cast<std::int64_t>(m.tet_gid.size()) != nt || m.n_free_vertices != no))
    throw std::logic_error("build_local_model: same_tets for a model of other tets");
  if (!same_tets) fit(nt, m.tets, m.dX_inv, m.vol0, m.tet_material, m.tet_gid);
  std::atomic<std::int64_t> missing{-1};  // a vertex of a held item not in the layout
  const std::int64_t t0 = same_tets ? L.n_interior : 0;
  for_each(HostExec{}, nt - t0, [&](std::int64_t jj) {
    const std::int64_t j = t0 + jj, t = L.tets[j];
    for (int k = 0; k < 4; ++k) {
      const std::int32_t gi = g.tets[t][k];
      m.tets[j][k] = g2l[gi];
      if (g2l[gi] < 0) missing.store(gi, std::memory_order_relaxed);
    }
    if (same_tets) return;
    m.dX_inv[j] = g.dX_inv[t];
    m.vol0[j] = g.vol0[t];
    m.tet_material[j] = g.tet_material[t];
    m.tet_gid[j] = g.tet_gid[t];
  });
  if (missing >= 0) local(missing);
  // CSR offsets, counted in parallel.
  auto offsets = [&](std::int64_t n, std::vector<std::int64_t>& off, auto count) {
    fit(n + 1, off);
    off[0] = 0;
    for_each(HostExec{}, n, [&](std::int64_t j) { off[j + 1] = count(j); });
    std::partial_sum(off.begin(), off.end(), off.begin());
  };
  // The owned vertices' corner lists (Model::corner_off): the global lists by corner, each in
  // tet gid order, renumbered (every free tet of an owned vertex is held), so in the one-rank
  // order with no sort (GPU-size dominoes, 786 k tets a rank, one thread: 6 ms, against 66 ms
  // for the upload's atomic fill and per-vertex sort by tet id).
  std::vector<std::int32_t>& tl = out.tet_local;
  std::atomic<std::int64_t> unheld{-1};  // a tet of an owned vertex not held
  if (!same_tets) {
    number(tl, g.n_tets(), L.tets);
    offsets(no, m.corner_off, [&](std::int64_t i) {
      return ix.corner_off[4 * L.vertices[i] + 4] - ix.corner_off[4 * L.vertices[i]];
    });
    fit(m.corner_off[no], m.corner_ent);
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
  }
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

  const ContactModel& gc = g.contact;
  ContactModel& c = m.contact;
  if (!with_contact || !gc.enabled) {
    c = ContactModel{};
    c.mode = gc.mode;
    c.n_surface_tets = gc.n_surface_tets;
    ids.triangle.clear();
    ids.edge.clear();
    ids.triangle_local.clear();
    ids.edge_local.clear();
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
  c.body_whole = L.body_whole;
  c.n_mat = gc.n_mat;
  c.pair_mu = gc.pair_mu;
  c.pair_zeta = gc.pair_zeta;
  c.pair_kn = gc.pair_kn;
  c.pair_E = gc.pair_E;
  c.dt_limit = gc.dt_limit;

  // Only the bodies with a local vertex can hold a primitive, triangle or edge: their items
  // (ModelIndex's per-body ranges) are the candidates, not the global model's, whose count
  // grows with the rank count.
  std::vector<std::uint8_t> touched(g.bodies.size(), 0);
  for_each(HostExec{}, nv, [&](std::int64_t i) {
    std::atomic_ref<std::uint8_t>(touched[g.body[L.vertices[i]]])
        .store(1, std::memory_order_relaxed);
  });
  // Primitives with every vertex local, in global order (free bodies first): each candidate
  // tested in parallel, the kept ones collected in order.
  const std::vector<std::int64_t> cand_prims = body_items(ix.body_prim_off, touched);
  std::vector<std::int64_t> prims =
      select_indices(HostExec{}, static_cast<std::int64_t>(cand_prims.size()), [&](std::int64_t k) {
        const std::array<std::int32_t, 4>& pv = gc.prim_v[cand_prims[k]];
        bool all = true;
        for (int q = 0; q < 4; ++q) all = all && (pv[q] < 0 || g2l[pv[q]] >= 0);
        return all;
      });
  for_each(HostExec{}, static_cast<std::int64_t>(prims.size()),
           [&](std::int64_t j) { prims[j] = cand_prims[prims[j]]; });
  const auto npl = static_cast<std::int64_t>(prims.size());
  // Their triangles and the triangles' edges, in global order, and global -> local numbers (-1:
  // not held) in the ids' kept arrays: the last build's entries are reset, then the held ones
  // written. A closed body this rank owns whole (`whole`) holds all its triangles and edges;
  // the other touched bodies' candidates are marked from their held primitives and triangles,
  // then collected (`part`), and the two merged body by body.
  auto mark = [](std::int32_t& m) {
    std::atomic_ref<std::int32_t>(m).store(1, std::memory_order_relaxed);
  };
  auto clear = [&](std::vector<std::int32_t>& marks, std::int64_t n,
                   const std::vector<std::int64_t>& last, const std::vector<std::int64_t>& cand) {
    if (static_cast<std::int64_t>(marks.size()) != n)
      marks.assign(static_cast<std::size_t>(n), -1);
    else
      for_each(HostExec{}, static_cast<std::int64_t>(last.size()),
               [&](std::int64_t j) { marks[last[j]] = -1; });
    for_each(HostExec{}, static_cast<std::int64_t>(cand.size()),
             [&](std::int64_t k) { marks[cand[k]] = 0; });
  };
  // The marked candidates, in order; every candidate's mark is reset.
  auto collect = [](std::vector<std::int32_t>& marks, const std::vector<std::int64_t>& cand) {
    const auto nc = static_cast<std::int64_t>(cand.size());
    std::vector<std::int64_t> out =
        select_indices(HostExec{}, nc, [&](std::int64_t k) { return marks[cand[k]] != 0; });
    for_each(HostExec{}, nc, [&](std::int64_t k) { marks[cand[k]] = -1; });
    for_each(HostExec{}, static_cast<std::int64_t>(out.size()),
             [&](std::int64_t j) { out[j] = cand[out[j]]; });
    return out;
  };
  const auto nb = static_cast<std::int64_t>(g.bodies.size());
  std::vector<std::uint8_t> whole(nb, 0), some(nb, 0);
  for (std::int64_t b = 0; b < nb; ++b) {
    whole[b] = touched[b] && ix.body_closed[b] &&
               b < static_cast<std::int64_t>(L.body_whole.size()) && L.body_whole[b] == kWholeHere;
    some[b] = touched[b] && !whole[b];
  }
  // The held items: a whole body's range and the others' collected ones (disjoint, both in
  // global order), numbered in `marks`.
  auto merge = [&](const std::vector<std::int64_t>& off, const std::vector<std::int64_t>& part,
                   std::vector<std::int32_t>& marks, std::vector<std::int64_t>& out) {
    const std::vector<std::int64_t> all = body_items(off, whole);
    fit(static_cast<std::int64_t>(all.size() + part.size()), out);
    std::merge(all.begin(), all.end(), part.begin(), part.end(), out.begin());
    for_each(HostExec{}, static_cast<std::int64_t>(out.size()),
             [&](std::int64_t j) { marks[out[j]] = static_cast<std::int32_t>(j); });
  };
  std::vector<std::int64_t>& tris = ids.triangle;
  std::vector<std::int32_t>& tri_l = ids.triangle_local;
  const std::vector<std::int64_t> cand_tris = body_items(ix.body_tri_off, some);
  clear(tri_l, static_cast<std::int64_t>(gc.tri_v.size()), tris, cand_tris);
  for_each(HostExec{}, npl, [&](std::int64_t j) {
    if (whole[gc.prim_body[prims[j]]]) return;
    for (std::int64_t q = gc.prim_tri_off[prims[j]]; q < gc.prim_tri_off[prims[j] + 1]; ++q)
      mark(tri_l[gc.prim_tri[q]]);
  });
  const std::vector<std::int64_t> part_tris = collect(tri_l, cand_tris);
  merge(ix.body_tri_off, part_tris, tri_l, tris);
  const auto ntl = static_cast<std::int64_t>(tris.size());
  std::vector<std::int64_t>& edges = ids.edge;
  std::vector<std::int32_t>& edge_l = ids.edge_local;
  const std::vector<std::int64_t> cand_edges = body_items(ix.body_edge_off, some);
  clear(edge_l, static_cast<std::int64_t>(gc.edges.size()), edges, cand_edges);
  for_each(HostExec{}, static_cast<std::int64_t>(part_tris.size()), [&](std::int64_t j) {
    for (int q = 0; q < 3; ++q) mark(edge_l[ix.tri_edges[part_tris[j]][q]]);
  });
  const std::vector<std::int64_t> part_edges = collect(edge_l, cand_edges);
  merge(ix.body_edge_off, part_edges, edge_l, edges);
  const auto nel = static_cast<std::int64_t>(edges.size());
  // The local lists, written in parallel (CSR offsets first).
  auto lv = [&](std::int64_t gid) {  // local index; a missing vertex is recorded
    const std::int32_t l = g2l[gid];
    if (l < 0) missing.store(gid, std::memory_order_relaxed);
    return l;
  };
  fit(ntl, c.tri_v, c.tri_body);
  offsets(ntl, c.own_v_off,
          [&](std::int64_t j) { return gc.own_v_off[tris[j] + 1] - gc.own_v_off[tris[j]]; });
  offsets(ntl, c.own_e_off,
          [&](std::int64_t j) { return gc.own_e_off[tris[j] + 1] - gc.own_e_off[tris[j]]; });
  fit(c.own_v_off[ntl], c.own_v);
  fit(c.own_e_off[ntl], c.own_e);
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
  fit(nel, c.edges, c.edge_tri);
  for_each(HostExec{}, nel, [&](std::int64_t j) {
    const std::int64_t e = edges[j];
    // Endpoints keep the global order (edge-edge geometry is evaluated a0 -> a1).
    c.edges[j] = {lv(gc.edges[e][0]), lv(gc.edges[e][1])};
    for (int k = 0; k < 2; ++k)
      c.edge_tri[j][k] = gc.edge_tri[e][k] >= 0 ? tri_l[gc.edge_tri[e][k]] : -1;
  });
  fit(npl, c.prim_v, c.prim_body);
  offsets(npl, c.prim_tri_off, [&](std::int64_t j) {
    return gc.prim_tri_off[prims[j] + 1] - gc.prim_tri_off[prims[j]];
  });
  fit(c.prim_tri_off[npl], c.prim_tri);
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
}

}  // namespace qdemsph
