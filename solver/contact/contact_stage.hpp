// The contact stage (METHOD.md section 3), written once over an execution space. Called from
// QdemBackend::compute_forces when the model needs contact; adds contact forces to f.
//
// Per step:
//  1. broad phase: centroid c and radius r (max centroid-vertex distance) of every primitive
//     (surface triangle, surface tet or tet: model/contact_model.hpp), a cell list of width
//     L = max(2 r) + D_DEM + skin (report eq. 9-10), candidate pairs (count, scan, fill) of
//     primitives of different bodies (or of one body with self-contact) whose spheres grown
//     by D_DEM + skin overlap, never two fixed bodies; the list is reused until a primitive
//     has moved by skin / 2 (Verlet skin, skin = D_DEM + max r / 4);
//  2. narrow phase over the triangles each primitive owns: point-face and edge-edge
//     (physics/contact_geometry.hpp) for the features each triangle owns, plus surface
//     vertices against analytic walls; records appended in one pass through an atomic
//     counter (cheap plane-distance and edge-midpoint tests skip features that cannot
//     touch), then sorted by key (unique per feature pair, so the order is deterministic);
//     of several point-face hits of one vertex on one body only the one with the largest
//     signed gap is kept (a vertex on a shared edge is one touch, not two);
//  3. force: the DEM law (physics/contact_law.hpp) between virtual particles of diameter
//     D_DEM at the two surface points, tangential history looked up by key (binary search
//     in the previous step's sorted keys), force distributed by weights (a gap below -D_DEM
//     counts only for a feature pair that was in contact the step before: the back face of
//     a thin body is not a penetration); a per-vertex gather (gather_local: count, scan,
//     fill, segment sort by record key, then slot) sums each vertex's entries in a fixed order
//     (deterministic), which the element forces' gather adds to f (sums());
//     on an MPI rank, which evaluates only the records anchored at its owned vertices
//     (Evaluator; all those of two bodies when one is whole there and leads, face_leads),
//     the shares of other ranks' vertices leave by shares() (keyed in global ids and
//     addressed to the owner's index: set_share_routes) and arrive at their owners'
//     add_forces, which merges them with the vertex's own entries by key: the one-rank order;
//  4. energy: the springs' stored energy and the step's dissipation per contact
//     (physics/contact_law.hpp, contact_energy; the non-potential force h is history like the
//     spring), plus, for touches that ended, their spring energy and the second half of their
//     last h's work (the previous step's records are kept for that), summed into the run's
//     contact_dissipated.
// Every phase is a for_each / reduce / scan / sort of the launch layer: on CUDA the data stays on
// the device (sorts and scans: neighbor/neighbor_cuda.cuh, contact/contact_sort_cuda.cuh); the
// host reads back only sizes (scan totals) and reduction results.
// Data: SoA views for topology and history; contact records are a transient AoS array.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include "contact/contact_record.hpp"
#include "contact/contact_sort_host.hpp"
#include "contact/contact_state.hpp"
#include "core/error.hpp"
#include "core/error_flag.hpp"
#include "core/exec_host.hpp"
#include "core/memory.hpp"
#include "core/radix_sort.hpp"
#include "core/timers.hpp"
#include "model/model.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/pair_list.hpp"
#include "neighbor/scan.hpp"
#include "physics/contact_geometry.hpp"
#include "physics/contact_law.hpp"

namespace qdemsph {

// Whether this process evaluates a record: it owns (index < n_free_vertices) the record's
// anchor vertex (contact_record.hpp, anchor_slot). Every record on one process; on MPI ranks
// exactly one rank evaluates a record (the narrow phase skips or drops the others').
// A model's vertices are [owned free | other ranks' free (ghosts) | fixed bodies'] (one
// process: no ghosts), so whether a vertex is free or owned is a comparison of its index, with
// no load of its body (a ghost vertex's test in the narrow phase waited for two dependent loads).
struct Evaluator {
  View<const std::uint64_t> vgid;
  View<const std::int32_t> vbody;
  View<const std::uint32_t> blead;  // per body, body_order << 2 | BodyWhole (with ghosts)
  std::int64_t nfv = 0, nfree = 0;  // owned free vertices; all free vertices held
  bool all = true;                  // one process (no ghosts): every record, no test needed
  QDEMSPH_HD bool free(int i) const { return i < nfree; }
  QDEMSPH_HD std::uint64_t gid(int i) const { return vgid[i]; }
  QDEMSPH_HD std::int32_t body(int i) const { return vbody[i]; }
  QDEMSPH_HD bool whole(std::int64_t b) const { return (blead[b] & 3) != kSplit; }
  QDEMSPH_HD bool whole_here(std::int64_t b) const { return (blead[b] & 3) == kWholeHere; }
  // A free vertex another rank owns.
  QDEMSPH_HD bool ghost(int i) const { return !all && i >= nfv && free(i); }
  // Of two bodies, the one whose faces lead (face_leads), -1 when neither does: from the table,
  // no hash in the narrow phase.
  QDEMSPH_HD int leading_body(int a, int b) const {
    const std::uint32_t ka = blead[a], kb = blead[b];
    if ((kb >> 2) < (ka >> 2)) return (kb & 3) != kSplit ? b : -1;
    if ((ka >> 2) < (kb >> 2)) return (ka & 3) != kSplit ? a : -1;
    return -1;
  }
  QDEMSPH_HD bool owns(int type, const std::int32_t* v) const {
    if (all) return true;
    // Owned vertices (index < nfv) are free: when every vertex is owned so is the anchor, when
    // none is the anchor is not. Only a record across the border reads bodies and global ids
    // (for a narrow-phase edge pair, dependent loads a GPU thread waits for).
    int owned = 0, used = 0;
    for (int k = 0; k < 4; ++k) {
      used += v[k] >= 0;
      owned += v[k] >= 0 && v[k] < nfv;
    }
    if (owned == 0) return false;
    if (owned == used) return true;
    const int k = anchor_slot(type, v, *this);
    return k >= 0 && v[k] < nfv;
  }
};
static_assert(std::is_trivially_copyable_v<Evaluator>);

// Read-only topology views used by the narrow phase (trivially copyable).
struct ContactTopology {
  View<const std::int32_t> tri_v;  // tri_v[k * ntri + s]
  View<const std::uint64_t> vgid;  // vertex global ids: keys survive renumbering (MPI ranks)
  std::int64_t ntri = 0;
  View<const std::int32_t> tri_body, edge_v, edge_tri;  // edge_v/edge_tri[k * ne + e]
  Vec3CView tri_n;  // unit outward normal of each surface triangle, this step
  std::int64_t ne = 0;
  View<const std::int64_t> own_v_off, own_e_off, prim_tri_off;
  View<const std::int32_t> own_v, own_e, prim_tri;
  View<const double> body_h;
  double d_dem = 0;
  bool self_contact = false;
  Evaluator eval;  // feature pairs another rank evaluates are skipped
  // On an MPI rank, per edge: body_order of its body << 41 | 2 gid + 1 of its free end with
  // the smallest global id when this rank owns that end, 2 gid when another rank does;
  // kNoFreeEnd when neither end is free (one process: empty). The smaller key of two edges is
  // their record's anchor (anchor_slot).
  View<const std::uint64_t> edge_anchor;
  static constexpr std::uint64_t kNoFreeEnd = ~std::uint64_t{1};

  // Whether this rank evaluates the edge pair (ea, eb): eval.owns for its record, read from two
  // keys before the pair's vertices are loaded (the pairs across a rank's border are found on
  // both ranks: each skips the other's half).
  QDEMSPH_HD bool evaluates_edges(int ea, int eb) const {
    const std::uint64_t ka = edge_anchor[ea], kb = edge_anchor[eb];
    return ((ka < kb ? ka : kb) & 1) != 0;
  }

  QDEMSPH_HD int tri_vertex(std::int64_t s, int k) const { return tri_v[k * ntri + s]; }
  QDEMSPH_HD Vec3 edge_normal(int e) const {
    const int t0 = edge_tri[e], t1 = edge_tri[ne + e];
    return (t0 >= 0 ? tri_n[t0] : Vec3{}) + (t1 >= 0 ? tri_n[t1] : Vec3{});
  }
  QDEMSPH_HD bool tri_has(std::int64_t s, int v) const {
    return tri_vertex(s, 0) == v || tri_vertex(s, 1) == v || tri_vertex(s, 2) == v;
  }

  // Contacts between the features owned by triangles a and b: emit(record) for each.
  // Three conservative early-outs skip the exact tests of features that cannot touch: a vertex
  // whose distance from the other triangle's plane (this step's unit normal) is outside the
  // accepted gaps by more than round-off; all edge pairs of two triangles one of which lies
  // wholly beyond the other's plane by more than D_DEM; and two edges whose midpoints are
  // farther apart than their half-lengths plus D_DEM (a valid edge-edge touch has |d| =
  // |p - q| < D_DEM). The exact tests decide every other case, so the records are those of
  // testing everything (Contact.NarrowPhaseFindsWhatTestingEveryFeaturePairFinds).
  // On an MPI rank, a free vertex's point-face tests run on its owner only, unless the faces'
  // body leads (face_leads: then on that body's rank), and an edge pair's on its anchor's owner
  // (anchor_slot); a fixed vertex's run wherever both sides are held (the duplicate filter
  // needs all of them), the narrow phase keeps the anchor owner's record.
  template <class Emit>
  QDEMSPH_HD void narrow_tris(Vec3CView x, std::int64_t a, std::int64_t b, Emit&& emit) const {
    const int ba = tri_body[a], bb = tri_body[b];
    const bool same = ba == bb;
    const double ha = body_h[ba], hb = body_h[bb];
    const double pen = d_dem + 0.5 * (ha < hb ? ha : hb);  // deepest gap still a contact
    Vec3 pa[3], pb[3];
    bool all_owned = true;  // then so is every edge pair's anchor
    for (int k = 0; k < 3; ++k) {
      const int ia = tri_vertex(a, k), ib = tri_vertex(b, k);
      all_owned = all_owned && ia < eval.nfv && ib < eval.nfv;
      pa[k] = x[ia];
      pb[k] = x[ib];
    }
    const bool test_anchor = !eval.all && !all_owned;
    const Vec3 na = tri_n[a], nb = tri_n[b];
    const double tol = 1e-9 * pen;  // >> the round-off of a plane distance, << any gap
    // Point-face: vertex A of side `side` on the other side's triangle s2 (points p2, normal n2).
    auto point_on_face = [&](int side, int A, std::int64_t s2, const Vec3* p2, const Vec3& n2) {
      const Vec3 xa = x[A];
      const double s_est = dot(xa - p2[0], n2);
      if (s_est > d_dem + tol || s_est < -pen - tol) return;
      const PointFace pf = point_face(xa, p2[0], p2[1], p2[2]);
      if (!pf.inside || !(pf.s < d_dem) || !(pf.s > -pen)) return;
      ContactRecord r;
      r.type = kPointFace;
      r.k1 = contact_key1(kPointFace, vgid[A]);
      r.k2 = static_cast<std::uint64_t>(s2);
      r.v[0] = A;
      r.w[0] = 1;
      for (int k = 0; k < 3; ++k) {
        r.v[k + 1] = tri_vertex(s2, k);
        r.w[k + 1] = pf.w[k];
      }
      r.n = pf.n;
      r.d = pf.s;
      r.n1 = 1;
      r.body1 = side == 0 ? ba : bb;
      r.body2 = side == 0 ? bb : ba;
      emit(r);
    };
    // Both ways; a free vertex's touches are tested on its owner.
    for (int side = 0; side < 2; ++side) {
      const std::int64_t s1 = side == 0 ? a : b, s2 = side == 0 ? b : a;
      const Vec3* p2 = side == 0 ? pb : pa;
      const Vec3 n2 = side == 0 ? nb : na;
      for (std::int64_t q = own_v_off[s1]; q < own_v_off[s1 + 1]; ++q) {
        const int A = own_v[q];
        if (same && tri_has(s2, A)) continue;
        if (eval.ghost(A)) continue;
        point_on_face(side, A, s2, p2, n2);
      }
    }
    // But other ranks' vertices on the faces of a body that leads (face_leads) are tested on the
    // rank holding that body whole (a pair of two free bodies whose leader another rank holds
    // is no candidate here). A loop of its own: a flag through the one above made the one-GPU
    // narrow phase 9 % slower on an H200.
    if (test_anchor && !same) {
      const int l = eval.leading_body(ba, bb);
      if (l >= 0 && eval.whole_here(l)) {
        const int side = l == bb ? 0 : 1;
        const std::int64_t s1 = side == 0 ? a : b, s2 = side == 0 ? b : a;
        const Vec3 n2 = side == 0 ? nb : na;
        for (std::int64_t q = own_v_off[s1]; q < own_v_off[s1 + 1]; ++q)
          if (eval.ghost(own_v[q])) point_on_face(side, own_v[q], s2, side == 0 ? pb : pa, n2);
      }
    }
    // Edge-edge. An edge lies in the plane of its triangle, and an edge-edge touch is two
    // points of the edges within D_DEM (|d| = |p - q|): when either triangle's vertices all lie
    // farther than that from the other's plane, on one side, none of their edge pairs touches
    // (3 in 4 candidate triangle pairs of the resting cube block, the side faces 1.5 D_DEM apart).
    if (beyond_plane(pa[0], na, pb, d_dem + tol) || beyond_plane(pb[0], nb, pa, d_dem + tol))
      return;
    for (std::int64_t qa = own_e_off[a]; qa < own_e_off[a + 1]; ++qa)
      for (std::int64_t qb = own_e_off[b]; qb < own_e_off[b + 1]; ++qb) {
        const int ea = own_e[qa], eb = own_e[qb];
        if (test_anchor && !evaluates_edges(ea, eb)) continue;
        const bool swap = eb < ea;
        const int e1 = swap ? eb : ea, e2 = swap ? ea : eb;
        const int a0 = edge_v[e1], a1 = edge_v[ne + e1], b0 = edge_v[e2], b1 = edge_v[ne + e2];
        if (same && (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1)) continue;
        const Vec3 xa0 = x[a0], xa1 = x[a1], xb0 = x[b0], xb1 = x[b1];
        const double reach = 0.5 * (norm(xa1 - xa0) + norm(xb1 - xb0)) + d_dem + tol;
        if (norm2(0.5 * ((xa0 + xa1) - (xb0 + xb1))) > reach * reach) continue;
        const EdgeEdge ee = edge_edge(xa0, xa1, xb0, xb1, edge_normal(e1), edge_normal(e2));
        // Edges have no face region to confirm a penetration: two skew edges merely passing
        // behind each other would read as a deep overlap. Accept |d| < D_DEM only.
        if (!ee.valid || !(ee.d < d_dem) || !(ee.d > -d_dem)) continue;
        ContactRecord r;
        r.type = kEdgeEdge;
        r.k1 = contact_key1(kEdgeEdge, static_cast<std::uint64_t>(e1));
        r.k2 = static_cast<std::uint64_t>(e2);
        r.v[0] = a0;
        r.v[1] = a1;
        r.v[2] = b0;
        r.v[3] = b1;
        r.w[0] = 1 - ee.s;
        r.w[1] = ee.s;
        r.w[2] = 1 - ee.t;
        r.w[3] = ee.t;
        r.n = ee.n;
        r.d = ee.d;
        r.n1 = 2;
        r.body1 = swap ? bb : ba;
        r.body2 = swap ? ba : bb;
        emit(r);
      }
  }
};
static_assert(std::is_trivially_copyable_v<ContactTopology>);

// ContactModel::body_whole for body_order on the host (empty: every body split).
struct WholeBodies {
  std::span<const std::uint8_t> w;
  QDEMSPH_HD bool whole(std::int64_t b) const { return !w.empty() && w[b] != kSplit; }
};

// Appends a record through an atomic counter (ContactStage::narrow_phase): slot k = count++,
// written when k < cap (the caller re-runs with a larger buffer when count ends above cap).
struct AppendRecord {
  ContactRecord* rec;
  int* count;
  std::int64_t cap;
  QDEMSPH_HD void operator()(const ContactRecord& r) const {
    const int k = atomic_inc(count);
    if (k < cap) rec[k] = r;
  }
};

// A contact entry (e: record e / 4, slot e % 4; keys k1, k2 in this model's ids) as a share's
// key: in global ids (`triangle`, `edge`: this model's, ShareRoutes), the slot. What a share
// carries, and what a vertex's own entries are compared with the shares sent for it.
struct ShareKeys {
  View<const std::uint64_t> k1, k2;
  View<const std::int64_t> triangle, edge;
  QDEMSPH_HD ContactShare operator()(std::int64_t e) const {
    ContactShare s;
    s.k1 = global_key1(k1[e / 4], edge.p);
    s.k2 = global_key2(k1[e / 4], k2[e / 4], triangle.p, edge.p);
    s.slot = static_cast<std::int32_t>(e % 4);
    return s;
  }
};
static_assert(std::is_trivially_copyable_v<ShareKeys>);

// The one-process order of a vertex's contact entries: by record key, then slot.
QDEMSPH_HD bool share_less(const ContactShare& a, const ContactShare& b) {
  if (a.k1 != b.k1) return a.k1 < b.k1;
  if (a.k2 != b.k2) return a.k2 < b.k2;
  return a.slot < b.slot;
}

// Whether shares[lo] is its vertex's first in shares grouped by vertex: the one thread of
// merge_shares' kernels that handles the vertex.
template <class Shares>
QDEMSPH_HD bool first_of_vertex(const Shares& shares, std::int64_t lo) {
  return lo == 0 || shares[lo - 1].vertex != shares[lo].vertex;
}

// A share target's entries are merged with its shares kMergeChunk at a time: their keys are
// read together (registers), so that the loads, a chain through vent_ to ekey_ an entry, are
// in flight at once.
inline constexpr int kMergeChunk = 8;

// The narrow phase's pass on a GPU: at most 128 registers a thread (512 threads an SM; with 143
// only 256 fitted: on an H100 the cube block's step 2.18 -> 1.75 ms, and 1.90 with 768), in
// blocks of 64 threads, since candidate pairs take unequal times and a block holds its place on
// the SM until its slowest warp ends (sph_stage.hpp, kSphPassLaunch): on an H200 the cube block
// 1.242 -> 1.223 ms a step and the dominoes 0.465 -> 0.458 ms against blocks of 256
// (references/benchmarks/scaling/2026-11-28_sph_blocks/).
inline constexpr MinBlocks<8, 64> kNarrowLaunch{};

// Room for n elements in an array that follows a count growing over a run (records, entries,
// shares): half as much again, so that the count's growth reallocates it a few times a run.
// Each growth is cheap on a GPU too (stream-ordered pool, core/memory.hpp); with cudaFree and
// cudaMalloc it had stalled the step ~0.25 ms an array, and on N ranks every rank's stall
// stalled them all.
constexpr std::int64_t count_room(std::int64_t n) { return n + n / 2 + 64; }

// At least n elements in b (a Buffer, or StagingBytes in bytes), grown with count_room's room;
// the contents are not kept. It grows only: no allocation per step.
template <class B>
void fit_count(B& b, std::int64_t n) {
  if (static_cast<std::int64_t>(b.size()) < n) b.resize(count_room(n));
}

template <class Exec>
class ContactStage {
  static constexpr Space S = Exec::space;

 public:
  ContactStage() : timers_([] { exec_sync(Exec{}); }) {}

  // Rows of K ids as K columns (entry k of row i at k * rows + i), built on the host threads.
  template <std::size_t K>
  void upload_columns(Buffer<std::int32_t>& b,
                      const std::vector<std::array<std::int32_t, K>>& rows) {
    const auto n = static_cast<std::int64_t>(rows.size());
    write_on_host(b, static_cast<std::int64_t>(K) * n, stage_, [&](std::int32_t* out) {
      for_each(HostExec{}, n, [&](std::int64_t i) {
        for (std::size_t k = 0; k < K; ++k) out[static_cast<std::int64_t>(k) * n + i] = rows[i][k];
      });
    });
  }

  // ContactTopology::edge_anchor for a model with ghosts (else empty).
  void upload_edge_anchors(const Model& m) {
    const std::int64_t ne = ghosts_ ? ne_ : 0, nfv = nfv_, nfree = nfree_, nv = nv_;
    const bool ids = static_cast<std::int64_t>(m.gid.size()) == nv;
    const auto& edges = m.contact.edges;
    const WholeBodies whole{m.contact.body_whole};
    write_on_host(edge_anchor_, ne, stage_, [&](std::uint64_t* key) {
      for_each(HostExec{}, ne, [&](std::int64_t e) {
        std::uint64_t k = ContactTopology::kNoFreeEnd;
        for (const std::int32_t i : edges[e]) {  // both ends are of one body
          if (i >= nfree) continue;
          const std::uint64_t g = ids ? m.gid[i] : static_cast<std::uint64_t>(i);  // < 2^31
          k = std::min(k, body_order(whole, m.body[i]) << 41 | (2 * g + (i < nfv ? 1 : 0)));
        }
        key[e] = k;
      });
    });
  }

  // The model's contact topology, and a fresh start (no history, pair list or counters); a
  // stage uploaded again keeps its storage (a distributed rank's rebuilt model).
  void upload(const Model& m) {
    const ContactModel& c = m.contact;
    nv_ = m.n_vertices();
    nfv_ = m.n_free_vertices;
    ntri_ = static_cast<std::int64_t>(c.tri_v.size());
    ne_ = static_cast<std::int64_t>(c.edges.size());
    np_ = static_cast<std::int64_t>(c.prim_v.size());
    npf_ = c.n_free_prims;
    nwv_ = static_cast<std::int64_t>(c.wall_vertices.size());
    nw_ = static_cast<std::int64_t>(c.walls.size());
    d_dem_ = c.d_dem;
    max_pen_ = c.max_penetration;
    pen_flag_.resize(1);
    pen_rec_.resize(1);
    pen_val_.resize(2);
    self_ = c.self_contact;
    kn_factor_ = c.kn_factor;
    kt_ratio_ = c.kt_ratio;
    skin_setting_ = c.skin;
    nm_ = c.n_mat;
    const std::int64_t nw = nw_;
    upload_columns(tri_v_, c.tri_v);
    upload_columns(edge_v_, c.edges);
    upload_columns(edge_tri_, c.edge_tri);
    upload_columns(prim_v_, c.prim_v);
    tri_n_.resize(ntri_);
    // The per-feature lists on the threads (through the page-locked staging for a device).
    assign_on_threads(tri_body_, c.tri_body, stage_);
    assign_on_threads(prim_body_, c.prim_body, stage_);
    assign_on_threads(own_v_off_, c.own_v_off, stage_);
    assign_on_threads(own_e_off_, c.own_e_off, stage_);
    assign_on_threads(own_v_, c.own_v, stage_);
    assign_on_threads(own_e_, c.own_e, stage_);
    assign_on_threads(prim_tri_off_, c.prim_tri_off, stage_);
    assign_on_threads(prim_tri_, c.prim_tri, stage_);
    assign_on_threads(wall_v_, c.wall_vertices, stage_);
    body_h_.assign(c.body_h);
    body_fixed_.assign(std::vector<std::int32_t>(c.body_fixed.begin(), c.body_fixed.end()));
    body_mat_.assign(c.body_mat);
    pair_mu_.assign(c.pair_mu);
    pair_zeta_.assign(c.pair_zeta);
    pair_kn_.assign(c.pair_kn);
    pair_E_.assign(c.pair_E);
    write_on_host(wall_, 8 * nw, stage_, [&](double* wall) {
      for (std::int64_t w = 0; w < nw; ++w) {
        const ContactWall& cw = c.walls[w];
        const double vals[8] = {cw.point.x,  cw.point.y,  cw.point.z, cw.normal.x,
                                cw.normal.y, cw.normal.z, cw.mu,      cw.zeta};
        for (int k = 0; k < 8; ++k) wall[8 * w + k] = vals[k];
      }
    });
    write_on_host(wall_kn_, nw, stage_, [&](double* wk) {
      for (std::int64_t w = 0; w < nw; ++w) wk[w] = c.walls[w].stiffness;
    });
    assign_on_threads(vertex_body_, m.body, stage_);
    const std::int64_t nv = nv_;
    const bool ids = static_cast<std::int64_t>(m.gid.size()) == nv;  // else numbered by index
    write_on_host(vgid_, nv, stage_, [&](std::uint64_t* g) {
      for_each(HostExec{}, nv, [&](std::int64_t i) { g[i] = ids ? m.gid[i] : i; });
    });
    // The sort key's fields (sort_key): id1 a vertex's place by global id (vrank_) or an edge
    // (numbered in global order), k2 a triangle, an edge or a wall. A distributed run's global
    // ids need more bits as the ranks grow (one radix pass more from 1 to 4 GPUs of the cube
    // block); these do not.
    write_on_host(vrank_, nv, stage_, [&](std::int32_t* rank) {
      std::vector<std::pair<std::uint64_t, std::int32_t>> by_gid(nv), tmp;
      for_each(HostExec{}, nv, [&](std::int64_t i) {
        by_gid[i] = {ids ? m.gid[i] : static_cast<std::uint64_t>(i), static_cast<std::int32_t>(i)};
      });
      merge_runs(by_gid, tmp);  // a rank's vertices come in a few runs by global id
      for_each(HostExec{}, nv,
               [&](std::int64_t k) { rank[by_gid[k].second] = static_cast<std::int32_t>(k); });
    });
    key_b2_ = std::bit_width(static_cast<std::uint64_t>(std::max({ntri_, ne_, nw_})));
    key_b12_ = key_b2_ + std::bit_width(static_cast<std::uint64_t>(std::max(nv, ne_)));
    if (key_b12_ > 62)
      throw std::logic_error("contact stage: feature ids of " + std::to_string(key_b12_) +
                             " bits do not fit a 64-bit sort key");
    assign_on_threads(inv_mass_, m.inv_mass, stage_);
    // Free vertices first (Evaluator): [0, nfv) owned, [nfv, nfree) other ranks' (ghosts).
    nfree_ = nfv_;
    while (nfree_ < nv_ && !c.body_fixed[m.body[nfree_]]) ++nfree_;
    for (std::int64_t i = nfree_; i < nv_; ++i)
      if (!c.body_fixed[m.body[i]])
        throw std::logic_error("contact stage: free vertex " + std::to_string(i) +
                               " after a fixed body's vertex");
    ghosts_ = nfree_ > nfv_;     // free vertices other ranks own (a distributed run's rank)
    fixed_held_ = nfree_ < nv_;  // fixed bodies' vertices (their point-face hits: keep_evaluated)
    const std::size_t nb = ghosts_ ? c.body_fixed.size() : 0;
    if (!c.body_whole.empty() && c.body_whole.size() != c.body_fixed.size())
      throw std::logic_error("contact stage: body_whole has " +
                             std::to_string(c.body_whole.size()) + " entries for " +
                             std::to_string(c.body_fixed.size()) + " bodies");
    const WholeBodies whole{c.body_whole};
    write_on_host(body_lead_, static_cast<std::int64_t>(nb), stage_, [&](std::uint32_t* k) {
      for (std::size_t b = 0; b < nb; ++b)
        k[b] = static_cast<std::uint32_t>(body_order(whole, static_cast<std::int64_t>(b)) << 2) |
               (c.body_whole.empty() ? std::uint8_t{kSplit} : c.body_whole[b]);
    });
    upload_edge_anchors(m);
    std::vector<std::int64_t> every(ghosts_ ? nfv_ : 0);
    std::iota(every.begin(), every.end(), std::int64_t{0});
    set_share_targets(every);  // until the rank's halo narrows them (set_share_targets)
    route_rank_.resize(0);     // the routes of an earlier layout (set_share_routes)
    pc_.resize(np_);
    pr_.resize(np_);
    pc_ref_.resize(np_);
    pr_ref_.resize(np_);
    count_.resize(1);
    vcnt_.resize(nv_ + 1);
    vcur_.resize(nv_);
    // A fresh start: no pair list, history or counters of an earlier model.
    pairs_.clear();
    n_prev_ = 0;
    built_ = false;
    timed_ = false;
    skin_ = 0;
    rebuilds_ = 0;
    steps_ = 0;
    stats_ = {};
    stats_current_ = true;
    acc_.resize(2);
    acc_.zero();
    timers_.clear();
  }

  // The contact records at positions x and velocities v: pairs, records, the force law, the
  // history and energies; add_forces then adds the forces. dt > 0 advances the tangential
  // springs (dynamics); dt = 0 leaves them (relaxation, the first evaluation). Timers
  // accumulate for dynamic steps only (dt > 0: inside the stepper's "elements" phase), so
  // run_scene can report "elements" without contact.
  void evaluate(Vec3CView x, Vec3CView v, double dt) {
    timed_ = dt > 0;
    PhaseTimers scratch;
    PhaseTimers& tm = timed_ ? timers_ : scratch;
    std::int64_t npairs = 0;
    {
      auto scope = tm.scope("contact.broad");
      npairs = broad_phase(x);
    }
    std::int64_t nc = 0;
    {
      auto scope = tm.scope("contact.narrow");
      nc = narrow_phase(x);
    }
    // The per-vertex sums are queued behind the force law, and the host waits for the force law
    // only (forced_), not for them: queued after the wait, their short kernels had left the
    // device idle between the host's launches (one H200: the step 25-60 us longer); a wait for
    // them too would hold an MPI rank's shares back (they leave once the force law is done).
    {
      auto scope = tm.launch("contact.force");
      forces(v, dt, nc);
      if constexpr (S == Space::Cuda) forced_.record();
      gather_local();
      forced_.wait();
    }
    stats_.pairs = npairs;
    stats_.contacts = nc;
    ++steps_;
  }

  // The last evaluation's force shares of free vertices held but not owned (an MPI rank's
  // ghosts; none on one process), as they travel (ContactShare: the owner's rank and index,
  // global keys), in no fixed order; valid until the next call. The force law compacted them
  // and queued their copy to page-locked memory (queue_shares); the host waits for it while the
  // device runs the element gather queued before.
  std::span<const ContactShare> shares() {
    if (!ghosts_) return {};
    int count = 0;
    if constexpr (S == Space::Cuda) {
      shares_mark_.wait();
      std::memcpy(&count, share_read_.data(), sizeof(int));
    } else {
      count = count_.cview()[0];
    }
    const std::int64_t n = count;
    if (n > out_.size()) {  // as narrow_phase: again with room for all (the count is exact)
      out_.resize(count_room(n));
      queue_shares(4 * n_prev_, pk1_.cview(), pk2_.cview());
      if constexpr (S == Space::Cuda) shares_mark_.wait();
    }
    if constexpr (S == Space::Cuda)
      return {reinterpret_cast<const ContactShare*>(share_read_.data() + kShareHead),
              static_cast<std::size_t>(n)};
    else
      return {out_.cview().p, static_cast<std::size_t>(n)};
  }

  // What the element forces' gather adds to each free vertex's force f_i (computed before it):
  // the sum of its contact entries of the last evaluation, in key order (-0, which adds
  // nothing, where it has none), f_i + sum[i]; on an MPI rank a share target's f_i is kept in
  // base (target[i] != 0; keep_base false without ghosts), from which add_forces sums it again
  // with the shares other ranks send.
  struct Sums {
    Vec3CView sum;
    View<const std::uint8_t> target;
    Vec3View base;
    bool keep_base = false;
  };
  Sums sums() { return {sum_.cview(), share_flag_.cview(), base_.view(), ghosts_}; }

  // On an MPI rank, the shares other ranks evaluated for this rank's vertices, as they arrive
  // (`in`, only for share targets), after the element gather added sums(): each target that got
  // some has f = base + its entries and shares merged in key order (the one-rank order: no
  // atomics in the sums). On a GPU the merge runs on the side stream from the end of
  // gather_local, beside the element gather; the last kernel adds its sums. Nothing to add on
  // one process.
  void add_forces(Vec3View f, std::span<const ContactShare> in = {}) {
    PhaseTimers scratch;
    auto scope = (timed_ ? timers_ : scratch).scope("contact.force");
    if (!ghosts_ && !in.empty())
      throw std::logic_error("contact shares for a model without ghosts");
    if (ghosts_) merge_shares(f, in);
  }

  // The owned vertices other ranks may send shares for: those they hold (an MPI rank's halo
  // sends them; duplicates and ghosts ignored). The element gather keeps their force without
  // contact (Sums::base), so that merge_shares can sum a vertex's entries and shares in the
  // one-process order. upload() makes every owned vertex a target.
  void set_share_targets(const std::vector<std::int64_t>& held_elsewhere) {
    std::vector<std::uint8_t> flag(nfv_, 0);
    for (const std::int64_t i : held_elsewhere)
      if (i >= 0 && i < nfv_) flag[i] = 1;
    share_flag_.assign(flag);
    share_host_ = std::move(flag);
    share_head_.assign(static_cast<std::size_t>(nfv_), -1);
  }

  // Where this rank's shares go (ShareRoutes, from its layout): the owners of the free vertices
  // it holds but does not own, and its triangles' and edges' global ids, which key the shares.
  // upload() drops them: a model with such vertices needs them before its first shares().
  void set_share_routes(const ShareRoutes& r) {
    const auto nghost = static_cast<std::size_t>(nfree_ - nfv_);
    if (r.rank.size() != nghost || r.index.size() != nghost ||
        r.triangle.size() != static_cast<std::size_t>(ntri_) ||
        r.edge.size() != static_cast<std::size_t>(ne_))
      throw std::logic_error("contact stage: share routes for " + std::to_string(r.rank.size()) +
                             " vertices, " + std::to_string(r.triangle.size()) + " triangles, " +
                             std::to_string(r.edge.size()) + " edges; the model holds " +
                             std::to_string(nghost) + ", " + std::to_string(ntri_) + ", " +
                             std::to_string(ne_));
    route_rank_.assign(r.rank);
    route_index_.assign(r.index);
    tri_gid_.assign(r.triangle);
    edge_gid_.assign(r.edge);
  }

  // The state between steps (contact_state.hpp): the whole history of the last force
  // evaluation, the pair list's reference and the counters. load_state (after upload)
  // restores them, so the next step is bit-identical; a state without a pair-list reference
  // (e.g. migrated to another rank layout) rebuilds the list at the next step.
  ContactState save_state() const {
    ContactState s = save_history();
    if (built_) {
      s.ref_centroid = pc_ref_.to_host();
      s.ref_radius = pr_ref_.to_host();
    }
    s.skin = skin_;
    s.rebuilds = rebuilds_;
    s.steps = steps_;
    s.stats = stats();
    return s;
  }

  // The history alone (its n_prev_ entries of the longer buffers), the dissipation and the
  // deepest overlap: what a distributed rank's export carries (Backend::save_owned).
  ContactState save_history() const {
    ContactState s;
    s.k1 = pk1_.to_host(n_prev_);
    s.k2 = pk2_.to_host(n_prev_);
    s.xi = pxi_.to_host(n_prev_);
    s.h = ph_.to_host(n_prev_);
    s.energy = pen_.to_host(n_prev_);
    s.energy_t = pet_.to_host(n_prev_);
    const std::vector<int> act = pact_.to_host(n_prev_);
    const std::vector<ContactRecord> rec = rec_.to_host(n_prev_);
    s.resize(n_prev_);
    for_each(HostExec{}, n_prev_, [&](std::int64_t c) {
      s.active[c] = act[c] ? 1 : 0;
      s.n1[c] = rec[c].n1;
      for (int k = 0; k < 4; ++k) {
        s.v[c][k] = rec[c].v[k];
        s.w[c][k] = rec[c].w[k];
      }
    });
    const std::vector<double> acc = acc_.to_host();  // one read-back for both
    s.dissipated = acc[0];
    s.max_overlap_ever = acc[1];
    return s;
  }

  // `s`'s keys sorted and its vertices in this model's indices.
  void load_state(const ContactState& s) {
    const auto n = static_cast<std::int64_t>(s.size());
    const auto nref = static_cast<std::int64_t>(s.ref_centroid.size());
    const auto fits = [n](const auto& a) { return static_cast<std::int64_t>(a.size()) == n; };
    if (!fits(s.k2) || !fits(s.active) || !fits(s.xi) || !fits(s.h) || !fits(s.energy) ||
        !fits(s.energy_t) || !fits(s.v) || !fits(s.w) || !fits(s.n1) ||
        (nref != 0 && nref != np_) || static_cast<std::int64_t>(s.ref_radius.size()) != nref)
      throw InputError("contact state does not fit the model (history or primitive count)");
    std::vector<ContactRecord> rec(n);
    std::vector<int> act(n);
    for (std::int64_t c = 0; c < n; ++c) {
      ContactRecord& r = rec[c];
      r.k1 = s.k1[c];
      r.k2 = s.k2[c];
      r.type = static_cast<std::int32_t>(s.k1[c] >> 60);
      r.n1 = s.n1[c];
      r.active = act[c] = s.active[c];
      for (int k = 0; k < 4; ++k) {
        if (s.v[c][k] >= nv_) throw InputError("contact state names a vertex the model lacks");
        r.v[k] = static_cast<std::int32_t>(s.v[c][k]);
        r.w[k] = s.w[c][k];
      }
    }
    pk1_.assign(s.k1);
    pk2_.assign(s.k2);
    pxi_.assign(s.xi);
    ph_.assign(s.h);
    pen_.assign(s.energy);
    pet_.assign(s.energy_t);
    pact_.assign(act);
    rec_.assign(rec);
    n_prev_ = n;
    skin_ = s.skin;
    built_ = nref > 0;
    if (built_) {
      pc_ref_.assign(s.ref_centroid);
      pr_ref_.assign(s.ref_radius);
      build_pairs();
    }
    rebuilds_ = s.rebuilds;
    steps_ = s.steps;
    stats_ = s.stats;
    stats_current_ = true;
    acc_.assign(std::vector<double>{s.dissipated, s.max_overlap_ever});
  }

  const std::map<std::string, double>& seconds() const { return timers_.seconds(); }
  // Elastic energy in the contact springs now (normal + tangential, last force evaluation).
  double stored_energy() const {
    const auto en = pen_.cview();
    return reduce_sum(
        Exec{}, n_prev_, QDEMSPH_LAMBDA(std::int64_t c) { return en[c]; });
  }
  Evaluator evaluator() const {
    return {vgid_.cview(), vertex_body_.cview(), body_lead_.cview(), nfv_, nfree_, !ghosts_};
  }
  // Energy dissipated by the contact dashpots and Coulomb slip since the start [J] (accumulated
  // where the stage runs: on a GPU, read back here, not every step).
  double dissipated_energy() const { return read_back(acc_, 0); }
  // The last evaluation's counters. The active contacts and the largest overlap are counted here
  // from its records, when asked (not every step: on a GPU two read-backs a step).
  const ContactStepStats& stats() const {
    if (!stats_current_) {
      const auto act = pact_.cview();
      const auto rec = rec_.cview();
      const double d_dem = d_dem_;
      stats_.active = static_cast<std::int64_t>(reduce_sum(
          Exec{}, n_prev_, QDEMSPH_LAMBDA(std::int64_t c) { return static_cast<double>(act[c]); }));
      stats_.max_overlap = reduce_max(
          Exec{}, n_prev_,
          QDEMSPH_LAMBDA(std::int64_t c) { return act[c] ? d_dem - rec[c].d : 0.0; }, 0.0);
      stats_current_ = true;
    }
    return stats_;
  }
  // The largest overlap of any evaluation since the start (the penetration guard's kernel keeps
  // it where the stage runs).
  double max_overlap_ever() const { return read_back(acc_, 1); }
  std::int64_t steps() const { return steps_; }
  std::int64_t pair_rebuilds() const { return rebuilds_; }
  std::size_t bytes() const {
    return tri_v_.bytes() + edge_v_.bytes() + edge_tri_.bytes() + tri_n_.bytes() + prim_v_.bytes() +
           tri_body_.bytes() + prim_body_.bytes() + own_v_off_.bytes() + own_e_off_.bytes() +
           own_v_.bytes() + own_e_.bytes() + prim_tri_off_.bytes() + prim_tri_.bytes() +
           pc_.bytes() + pr_.bytes() + rec_.bytes() + ent_f_.bytes() + ent_v_.bytes() +
           vcnt_.bytes() + vcur_.bytes() + vent_.bytes() + pact_.bytes() + nact_.bytes() +
           pk1_.bytes() + pk2_.bytes() + pxi_.bytes() + nk1_.bytes() + nk2_.bytes() + nxi_.bytes() +
           pen_.bytes() + pet_.bytes() + nen_.bytes() + net_.bytes() + ediss_.bytes() +
           ph_.bytes() + nh_.bytes() + prec_.bytes() + pc_ref_.bytes() + pr_ref_.bytes() +
           cells_.bytes() + pairs_.bytes() + vgid_.bytes() + edge_anchor_.bytes() +
           rec_tmp_.bytes() + skey_.bytes() + vrank_.bytes() + sorder_.bytes() + in_.bytes() +
           sum_.bytes() + base_.bytes() + msum_.bytes() + ekey_.bytes() + share_flag_.bytes() +
           out_.bytes() + keep_.bytes() + tfirst_.bytes() + tsecond_.bytes() + route_rank_.bytes() +
           route_index_.bytes() + tri_gid_.bytes() + edge_gid_.bytes();
  }

  ContactTopology topology() const {
    ContactTopology t;
    t.tri_v = tri_v_.cview();
    t.ntri = ntri_;
    t.tri_body = tri_body_.cview();
    t.edge_v = edge_v_.cview();
    t.edge_tri = edge_tri_.cview();
    t.tri_n = tri_n_.cview();
    t.ne = ne_;
    t.own_v_off = own_v_off_.cview();
    t.own_e_off = own_e_off_.cview();
    t.prim_tri_off = prim_tri_off_.cview();
    t.own_v = own_v_.cview();
    t.own_e = own_e_.cview();
    t.prim_tri = prim_tri_.cview();
    t.body_h = body_h_.cview();
    t.vgid = vgid_.cview();
    t.d_dem = d_dem_;
    t.self_contact = self_;
    t.eval = evaluator();
    t.edge_anchor = edge_anchor_.cview();
    return t;
  }

  // Candidate pairs of the last broad phase (tests compare them with brute force).
  const CandidatePairs<Exec>& pairs() const { return pairs_; }
  Vec3CView centroids() const { return pc_.cview(); }
  View<const double> radii() const { return pr_.cview(); }
  std::int64_t n_primitives() const { return np_; }
  // The last step's records, sorted by key (host copy; tests and diagnostics).
  std::vector<ContactRecord> records() const {
    std::vector<ContactRecord> r = rec_.to_host();
    r.resize(stats_.contacts);
    return r;
  }

  // The phases are public only because nvcc requires the enclosing function of an extended
  // __host__ __device__ lambda to be public (the CUDA build fails otherwise).
  std::int64_t broad_phase(Vec3CView x) {
    if (np_ == 0) return 0;
    const std::int64_t np = np_;
    const auto pv = prim_v_.cview();
    const auto pc = pc_.view();
    const auto pr = pr_.view();
    for_each(
        Exec{}, np, QDEMSPH_LAMBDA(std::int64_t p) {
          Vec3 q[4];
          int k = 0;
          Vec3 c{};
          for (; k < 4; ++k) {
            const int i = pv[k * np + p];
            if (i < 0) break;
            q[k] = x[i];
            c += q[k];
          }
          c = c / static_cast<double>(k);
          double r2 = 0;
          for (int j = 0; j < k; ++j) {
            const double d2 = norm2(q[j] - c);
            r2 = d2 > r2 ? d2 : r2;
          }
          pc.set(p, c);
          pr[p] = sqrt(r2);
        });
    const auto cc = pc_.cview();
    const auto rr = pr_.cview();
    // Verlet skin: the pair list built with gap D_DEM + skin stays a superset of the pairs
    // within D_DEM until some primitive's centroid has moved, plus its radius changed, by
    // skin / 2. Checked every step (one device reduction); the list is rebuilt only then.
    if (built_) {
      const auto c0 = pc_ref_.cview();
      const auto r0 = pr_ref_.cview();
      const double moved = reduce_max(
          Exec{}, np,
          QDEMSPH_LAMBDA(std::int64_t p) {
            const double dr = rr[p] - r0[p];
            return norm(cc[p] - c0[p]) + (dr > 0 ? dr : -dr);
          },
          0.0);
      if (skin_ > 0 && moved <= 0.5 * skin_) return pairs_.size();
    }
    {
      const auto c0 = pc_ref_.view();
      const auto r0 = pr_ref_.view();
      for_each(
          Exec{}, np, QDEMSPH_LAMBDA(std::int64_t p) {
            c0.set(p, cc[p]);
            r0[p] = rr[p];
          });
    }
    const double rmax = reduce_max(
        Exec{}, np, QDEMSPH_LAMBDA(std::int64_t p) { return rr[p]; }, 0.0);
    skin_ = skin_setting_ >= 0 ? skin_setting_ : d_dem_ + 0.25 * rmax;
    built_ = true;
    ++rebuilds_;
    return build_pairs();
  }

  // The candidate pairs of the centroids and radii of the last rebuild (pc_ref_, pr_ref_) with
  // gap D_DEM + skin: a function of those arrays only, so load_state rebuilds the same list.
  std::int64_t build_pairs() {
    const std::int64_t np = np_;
    const auto pv = prim_v_.cview();
    const auto cc = pc_ref_.cview();
    const auto rr = pr_ref_.cview();
    Vec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      const double* ca = a == 0 ? cc.x : (a == 1 ? cc.y : cc.z);
      hi[a] = reduce_max(
          Exec{}, np, QDEMSPH_LAMBDA(std::int64_t p) { return ca[p]; }, -1e300);
      lo[a] = -reduce_max(
          Exec{}, np, QDEMSPH_LAMBDA(std::int64_t p) { return -ca[p]; }, -1e300);
    }
    const double rmax = reduce_max(
        Exec{}, np, QDEMSPH_LAMBDA(std::int64_t p) { return rr[p]; }, 0.0);
    const double gap = d_dem_ + skin_;
    // Report eq. 9-10: L_cell >= D_max + D_DEM with D_max = 2 max r (+ the skin).
    const double L = (2 * rmax + gap) * (1 + 1e-9) + 1e-300;
    cells_.set_grid(cover_capped(lo, hi, L, 4 * np + 64));
    cells_.build(cc);
    const auto pb = prim_body_.cview();
    const auto fixed = body_fixed_.cview();
    const bool self = self_;
    const auto pvv = pv;
    const std::int64_t nfv = nfv_;
    const bool ghosts = ghosts_;
    const Evaluator ev = evaluator();
    // Only primitives of free bodies start a pair (they come first): a fixed-fixed pair is
    // never needed, and a free-fixed pair (i < npf <= j) is found from its free side. On an
    // MPI rank a pair of two free primitives without an owned vertex is another rank's
    // (every record it could give is anchored elsewhere, Evaluator), and so is a pair of two
    // bodies of which one leads on another rank (face_leads: all their records are its).
    const std::int64_t n = pairs_.build(
        cells_, cc, rr, gap, npf_, QDEMSPH_LAMBDA(std::int64_t i, std::int64_t j)->bool {
          const int bi = pb[i], bj = pb[j];
          if (fixed[bi] && fixed[bj]) return false;
          if (ghosts && !fixed[bj]) {
            const int lead = bi != bj ? ev.leading_body(bi, bj) : -1;
            if (lead >= 0) return ev.whole_here(lead);
            bool owned = false;
            for (int a = 0; a < 8 && !owned; ++a) {
              const int va = pvv[(a & 3) * np + (a < 4 ? i : j)];
              owned = va >= 0 && va < nfv;
            }
            if (!owned) return false;
          }
          if (bi != bj) return true;
          if (!self) return false;
          // Self-contact: primitives sharing a vertex are neighbours in the mesh, not a touch.
          for (int a = 0; a < 4; ++a) {
            const int va = pvv[a * np + i];
            if (va < 0) break;
            for (int b = 0; b < 4; ++b)
              if (pvv[b * np + j] == va) return false;
          }
          return true;
        });
    if (ghosts) order_border_last(n);
    return n;
  }

  // On a rank with ghosts, the candidate pairs in the narrow phase's thread order (tfirst_,
  // tsecond_): those whose primitives' vertices are all owned first, the pairs across the
  // border (another rank's or a fixed body's vertex) last, each group in the list's order. A
  // border pair runs the anchor and leading-body tests that the others skip, and spread
  // through the list it held up the warps it fell in.
  void order_border_last(std::int64_t n) {
    fit_count(tfirst_, n);
    fit_count(tsecond_, n);
    fit_count(keep_, n + 1);
    const std::int64_t np = np_, nfv = nfv_;
    const auto pv = prim_v_.cview();
    const auto fst = pairs_.first(), sec = pairs_.second();
    const auto inner = keep_.view();
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t q) {
          bool owned = true;
          for (int a = 0; a < 8 && owned; ++a) {
            const int v = pv[(a & 3) * np + (a < 4 ? fst[q] : sec[q])];
            owned = v < nfv;  // padding (-1) included
          }
          inner[q] = owned ? 1 : 0;
        });
    const std::int64_t ninner = exclusive_scan(Exec{}, inner, n);
    const auto tf = tfirst_.view(), ts = tsecond_.view();
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t q) {
          const std::int64_t k = inner[q + 1] > inner[q] ? inner[q] : ninner + q - inner[q];
          tf[k] = fst[q];
          ts[k] = sec[q];
        });
  }

  // Records of all contacts, sorted by key, duplicates of one touch deactivated; on an MPI rank
  // only those it evaluates (Evaluator). The previous step's records move to prec_ (the energy
  // of touches that ended needs them).
  std::int64_t narrow_phase(Vec3CView x) {
    std::swap(rec_, prec_);
    // Room for a quarter more records than the last step's: a count that grows reallocates here
    // rather than through the pass's second run below.
    fit_count(rec_, n_prev_ + n_prev_ / 4);
    {
      const std::int64_t ntri = ntri_;
      const auto tv = tri_v_.cview();
      const auto tn = tri_n_.view();
      for_each(
          Exec{}, ntri, QDEMSPH_LAMBDA(std::int64_t s) {
            const Vec3 p0 = x[tv[s]], p1 = x[tv[ntri + s]], p2 = x[tv[2 * ntri + s]];
            const Vec3 m = cross(p1 - p0, p2 - p0);
            const double l = norm(m);
            tn.set(s, l > 0 ? m / l : Vec3{});
          });
    }
    const ContactTopology topo = topology();
    const std::int64_t npair = pairs_.size(), nwv = nwv_, nw = nw_;
    const auto fst = ghosts_ ? tfirst_.cview() : pairs_.first();
    const auto sec = ghosts_ ? tsecond_.cview() : pairs_.second();
    const auto pto = prim_tri_off_.cview();
    const auto pt = prim_tri_.cview();
    const auto wv = wall_v_.cview();
    const auto wall = wall_.cview();
    const auto vb = vertex_body_.cview();
    const auto vg = vgid_.cview();
    const double d_dem = d_dem_;
    // One pass over the candidate pairs (a thread per pair: primitives' pair counts are uneven)
    // and the wall vertices appends every contact through one atomic counter; the order of the
    // appends does not matter, the records are sorted by their keys (unique per feature pair)
    // next. Should the buffer be too small, the pass runs again with room for all (the count
    // is exact: every contact was counted).
    std::int64_t nc = 0;
    for (int pass = 0; pass < 2; ++pass) {
      count_.zero();
      const AppendRecord app{rec_.view().p, count_.view().p, rec_.size()};
      for_each(
          Exec{}, npair + nwv,
          QDEMSPH_LAMBDA(std::int64_t i) {
            if (i < npair) {
              const int a = fst[i], b = sec[i];
              for (std::int64_t ta = pto[a]; ta < pto[a + 1]; ++ta)
                for (std::int64_t tb = pto[b]; tb < pto[b + 1]; ++tb)
                  topo.narrow_tris(x, pt[ta], pt[tb], app);
              return;
            }
            const int A = wv[i - npair];
            const Vec3 xa = x[A];
            for (std::int64_t w = 0; w < nw; ++w) {
              const Vec3 p{wall[8 * w], wall[8 * w + 1], wall[8 * w + 2]};
              const Vec3 nn{wall[8 * w + 3], wall[8 * w + 4], wall[8 * w + 5]};
              const double s = dot(xa - p, nn);
              if (!(s < d_dem)) continue;
              ContactRecord r;
              r.type = kWall;
              r.k1 = contact_key1(kWall, vg[A]);
              r.k2 = static_cast<std::uint64_t>(w);
              r.v[0] = A;
              r.w[0] = 1;
              r.n = nn;
              r.d = s;
              r.n1 = 1;
              r.body1 = vb[A];
              r.body2 = -1;
              r.wall = static_cast<std::int32_t>(w);
              app(r);
            }
          },
          kNarrowLaunch);
      nc = read_back(count_, 0);
      if (nc <= rec_.size()) break;
      rec_.resize(count_room(nc));
    }
    sort_records(nc);
    const auto rec = rec_.view();
    // One vertex touching one body: keep the point-face hit with the largest gap.
    for_each(
        Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) {
          ContactRecord& r = rec[c];
          if (r.type != kPointFace) return;
          bool keep = true;
          for (std::int64_t o = c - 1; o >= 0 && rec[o].k1 == r.k1 && keep; --o)
            if (rec[o].body2 == r.body2 && rec[o].d >= r.d) keep = false;  // lower key wins ties
          for (std::int64_t o = c + 1; o < nc && rec[o].k1 == r.k1 && keep; ++o)
            if (rec[o].body2 == r.body2 && rec[o].d > r.d) keep = false;
          r.active = keep ? 1 : 0;
        });
    // Only a fixed vertex's point-face records can be another rank's (a free vertex's are tested
    // on its owner, an edge pair's on its anchor's, wall vertices are owned ones): without fixed
    // vertices there is nothing to drop (cube block, 2 ranks: 25 us of kernels and a read-back
    // a step on an H100).
    return ghosts_ && fixed_held_ ? keep_evaluated(nc) : nc;
  }

  // rec_[0, nc) in key order: their packed keys sorted with their indices, then the records
  // gathered once. Sorting the records themselves (~130 bytes each, a merge sort) took 335 us
  // of the cube block's 1.42 ms step on an H200 (106 k records).
  void sort_records(std::int64_t nc) {
    fit_count(skey_, 2 * nc);
    fit_count(sorder_, 2 * nc);
    fit_count(rec_tmp_, nc);
    const auto rec = rec_.cview();
    const auto key = skey_.view();
    const auto order = sorder_.view();
    const auto vrank = vrank_.cview();
    const int b2 = key_b2_, b12 = key_b12_;
    for_each(
        Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) {
          const ContactRecord& r = rec[c];  // point-face and wall: id1 is v[0]'s global id
          const std::uint64_t rank1 = r.type == kEdgeEdge ? r.k1 & kIdMask : vrank[r.v[0]];
          key[c] = sort_key(r, rank1, b2, b12);
          order[c] = static_cast<std::int32_t>(c);
        });
    const std::int32_t* sorted = sorted_order(Exec{}, key, order, nc, b12 + 2);
    const auto out = rec_tmp_.view();
    for_each(
        Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) { out[c] = rec[sorted[c]]; });
    std::swap(rec_, rec_tmp_);
  }

  void forces(Vec3CView v, double dt, std::int64_t nc) {
    if (ent_v_.size() < 4 * nc) {
      ent_v_.resize(count_room(4 * nc));
      ent_f_.resize(count_room(4 * nc));
    }
    if (nk1_.size() < nc) {
      nact_.resize(count_room(nc));
      nk1_.resize(count_room(nc));
      nk2_.resize(count_room(nc));
      nxi_.resize(count_room(nc));
      nen_.resize(count_room(nc));
      net_.resize(count_room(nc));
      nh_.resize(count_room(nc));
    }
    fit_count(ediss_, nc);
    const auto rec = rec_.cview();
    const auto im = inv_mass_.cview();
    const auto bmat = body_mat_.cview();
    const auto bh = body_h_.cview();
    const auto pmu = pair_mu_.cview(), pzeta = pair_zeta_.cview(), pkn = pair_kn_.cview(),
               pE = pair_E_.cview();
    const auto wall = wall_.cview();
    const auto wkn = wall_kn_.cview();
    const auto pk1 = pk1_.cview(), pk2 = pk2_.cview();
    const auto pxi = pxi_.cview();
    const auto ph = ph_.cview();
    const auto pact = pact_.cview();
    const std::int64_t nprev = n_prev_;
    const auto nk1 = nk1_.view(), nk2 = nk2_.view();
    const auto nxi = nxi_.view();
    const auto nact = nact_.view();
    const auto nen = nen_.view(), net = net_.view(), ediss = ediss_.view();
    const auto nh = nh_.view();
    const auto ev = ent_v_.view();
    const auto ef = ent_f_.view();
    const int nm = nm_;
    const double d_dem = d_dem_, knf = kn_factor_, ktr = kt_ratio_;
    for_each(
        Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) {
          const ContactRecord& r = rec[c];
          nk1[c] = r.k1;
          nk2[c] = r.k2;
          nxi.set(c, Vec3{});
          nact[c] = 0;
          nen[c] = 0;
          net[c] = 0;
          ediss[c] = 0;
          nh.set(c, Vec3{});
          for (int k = 0; k < 4; ++k) ev[4 * c + k] = -1;
          if (!r.active) return;
          Vec3 v1{}, v2{};
          double im1 = 0, im2 = 0;
          for (int k = 0; k < 4; ++k) {
            const int i = r.v[k];
            if (i < 0) continue;
            if (k < r.n1) {
              v1 += r.w[k] * v[i];
              im1 += r.w[k] * im[i];
            } else {
              v2 += r.w[k] * v[i];
              im2 += r.w[k] * im[i];
            }
          }
          const double inv_eff = im1 + im2;
          if (!(inv_eff > 0)) return;  // both sides immobile
          ContactLaw law;
          const int m1 = bmat[r.body1];
          if (r.body2 < 0) {
            const std::int64_t w = r.wall;
            law.mu = wall[8 * w + 6];
            law.zeta = wall[8 * w + 7];
            law.kn = wkn[w] > 0 ? wkn[w] : knf * pE[m1 * nm + m1] * bh[r.body1];
          } else {
            const int mp = m1 * nm + bmat[r.body2];
            const double h1 = bh[r.body1], h2 = bh[r.body2];
            law.mu = pmu[mp];
            law.zeta = pzeta[mp];
            law.kn = pkn[mp] > 0 ? pkn[mp] : knf * pE[mp] * (h1 < h2 ? h1 : h2);
          }
          law.kt = ktr * law.kn;
          // Tangential history of this feature pair from the previous step (sorted keys).
          Vec3 xi{}, h_old{};
          const std::int64_t lo = lower_bound_index(nprev, [&](std::int64_t m) {
            return pk1[m] < r.k1 || (pk1[m] == r.k1 && pk2[m] < r.k2);
          });
          const bool known = lo < nprev && pk1[lo] == r.k1 && pk2[lo] == r.k2 && pact[lo];
          if (known) {
            xi = pxi[lo];
            h_old = ph[lo];
          }
          // A touch starts with a gap above -D_DEM; a deeper one must have been a contact the
          // step before (continuity). Otherwise it is the back face of a thin body seen through
          // it, not a penetration.
          if (r.d < -d_dem && !known) return;
          nact[c] = 1;
          const ContactForce cf =
              contact_force(law, r.n, d_dem - r.d, v1 - v2, xi, dt, 1.0 / inv_eff);
          const Vec3 xi_kept = dt > 0 ? cf.xi : xi;
          nxi.set(c, xi_kept);
          const ContactEnergy en =
              contact_energy(law, r.n, d_dem - r.d, v1 - v2, xi, xi_kept, h_old, cf, dt);
          nen[c] = en.stored;
          net[c] = en.stored_t;
          ediss[c] = en.dissipated;
          nh.set(c, en.h);
          for (int k = 0; k < 4; ++k) {
            ev[4 * c + k] = r.v[k];
            ef.set(4 * c + k, (k < r.n1 ? r.w[k] : -r.w[k]) * cf.f);
          }
        });
    if (ghosts_) queue_shares(4 * nc, nk1_.cview(), nk2_.cview());
    // Dissipation of this step: per contact, plus for each of the previous step's touches with
    // no active successor (binary search in this step's sorted keys) its spring energy and the
    // second half of its last h's work, -h/2 . v_rel dt at this step's velocities.
    if (dt > 0) {
      const auto nk1c = nk1_.cview(), nk2c = nk2_.cview();
      const auto nactc = nact_.cview();
      const auto pet = pet_.cview();
      const auto ed = ediss_.cview();
      const auto prec = prec_.cview();
      const std::int64_t ncur = nc;
      reduce_sum_into(
          Exec{}, nc > nprev ? nc : nprev,
          QDEMSPH_LAMBDA(std::int64_t i) {
            double s = i < ncur ? ed[i] : 0.0;
            if (i < nprev && pact[i]) {
              const std::int64_t lo = lower_bound_index(ncur, [&](std::int64_t m) {
                return nk1c[m] < pk1[i] || (nk1c[m] == pk1[i] && nk2c[m] < pk2[i]);
              });
              const bool kept = lo < ncur && nk1c[lo] == pk1[i] && nk2c[lo] == pk2[i] && nactc[lo];
              if (!kept) {
                const ContactRecord& r = prec[i];
                Vec3 vr{};
                for (int k = 0; k < 4; ++k)
                  if (r.v[k] >= 0) vr += (k < r.n1 ? r.w[k] : -r.w[k]) * v[r.v[k]];
                s += pet[i] - 0.5 * dot(ph[i], vr) * dt;
              }
            }
            return s;
          },
          acc_.view().p);
    }
    // The keys and springs become the next step's history (already sorted).
    std::swap(pk1_, nk1_);
    std::swap(pk2_, nk2_);
    std::swap(pxi_, nxi_);
    std::swap(pact_, nact_);
    std::swap(pen_, nen_);
    std::swap(pet_, net_);
    std::swap(ph_, nh_);
    n_prev_ = nc;

    const auto pxc = rec_.cview();
    const auto act = pact_.cview();  // this step's, after the swap
    stats_current_ = false;          // stats() counts the active contacts when asked
    // Penetration guard: surfaces crossed deeper than the bound (contact.max_penetration, or
    // half the pair's smaller mean surface edge) flag the first such contact found. The same
    // pass keeps the largest overlap ever (max_overlap_ever).
    {
      const auto bh = body_h_.cview();
      const double mp = max_pen_;
      unsigned long long* flag = pen_flag_.view().p;
      ContactRecord* info = pen_rec_.view().p;
      double* val = pen_val_.view().p;
      double* ever = acc_.view().p + 1;
      for_each(
          Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) {
            if (!act[c]) return;
            const ContactRecord& r = pxc[c];
            atomic_max_positive(ever, d_dem - r.d);
            const double h1 = bh[r.body1];
            const double h = r.body2 >= 0 && bh[r.body2] < h1 ? bh[r.body2] : h1;
            const double bound = mp > 0 ? mp : 0.5 * h;
            if (-r.d > bound && raise_flag(flag, c)) {
              info[0] = r;
              val[0] = -r.d;
              val[1] = bound;
            }
          });
    }
  }

  // Each vertex's entries of the last evaluation sorted by record key, then slot (count, scan,
  // fill, sort) and summed into sum_ (sums()). On an MPI rank its end is marked (summed_): the
  // merge of the shares starts there (merge_shares), beside the element gather.
  void gather_local() {
    const std::int64_t ne = 4 * n_prev_;
    fit_count(vent_, ne);
    if (sum_.size() != nfv_) sum_.resize(nfv_);  // every entry is written below
    if (ghosts_) {
      if (base_.size() < nfv_) base_.resize(nfv_);
      fit_count(ekey_, ne);  // merge_shares fills it, on the side stream
    }
    const auto ev = ent_v_.cview();
    const auto ef = ent_f_.cview();
    const auto vcnt = vcnt_.view();
    const auto vcur = vcur_.view();
    const auto vent = vent_.view();
    const auto sum = sum_.view();
    vcnt_.zero();  // memset: no parallel region for a loop without work
    vcur_.zero();
    for_each(
        Exec{}, ne, QDEMSPH_LAMBDA(std::int64_t e) {
          const int i = ev[e];
          if (i >= 0) atomic_inc(&vcnt[i]);
        });
    queue_exclusive_scan(Exec{}, vcnt, nv_);  // no total needed: on a GPU nothing waits here
    for_each(
        Exec{}, ne, QDEMSPH_LAMBDA(std::int64_t e) {
          const int i = ev[e];
          if (i >= 0) vent[vcnt[i] + atomic_inc(&vcur[i])] = static_cast<int>(e);
        });
    // Local entries are in key order by index (the records are sorted by key, e = 4 record +
    // slot); insertion sort: a vertex has few entries.
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          const int b = vcnt[i], e = vcnt[i + 1];
          for (int k = b + 1; k < e; ++k) {
            const int val = vent[k];
            int j = k - 1;
            while (j >= b && val < vent[j]) {
              vent[j + 1] = vent[j];
              --j;
            }
            vent[j + 1] = val;
          }
          Vec3 s{};
          for (int k = b; k < e; ++k) s += ef[vent[k]];
          sum.set(i, b < e ? s : Vec3{-0.0, -0.0, -0.0});  // x + -0 is x, bit for bit
        });
    if constexpr (S == Space::Cuda)
      if (ghosts_) summed_.record();
  }

  // The entries [0, ne) of free vertices held but not owned, as shares (keys k1, k2 of record
  // e / 4, in global ids; the owner's rank and index from the routes), into out_; their count
  // into count_, exact even when out_ is too small.
  void compact_shares(std::int64_t ne, View<const std::uint64_t> k1, View<const std::uint64_t> k2) {
    if (route_rank_.size() != nfree_ - nfv_)
      throw std::logic_error("contact stage: shares without their routes (set_share_routes)");
    count_.zero();
    const auto evc = ent_v_.cview();
    const auto efc = ent_f_.cview();
    const Evaluator ev = evaluator();
    ContactShare* out = out_.view().p;
    int* count = count_.view().p;
    const std::int64_t cap = out_.size();
    const auto rank = route_rank_.cview(), index = route_index_.cview();
    const ShareKeys key{k1, k2, tri_gid_.cview(), edge_gid_.cview()};
    for_each(
        Exec{}, ne, QDEMSPH_LAMBDA(std::int64_t e) {
          const int i = evc[e];
          if (i < ev.nfv || !ev.free(i)) return;
          const int k = atomic_inc(count);
          if (k >= cap) return;
          ContactShare s = key(e);
          s.vertex = index[i - ev.nfv];
          s.rank = rank[i - ev.nfv];
          s.f = efc[e];
          out[k] = s;
        });
  }

  // compact_shares and, on a GPU, the shares copied to page-locked memory (share_read_: their
  // count, then as many as out_ holds, the count known only after), on the side stream: the
  // default stream's dissipation, sums and gathers go on meanwhile (none reads the shares), and
  // shares() waits for shares_mark_.
  void queue_shares(std::int64_t ne, View<const std::uint64_t> k1, View<const std::uint64_t> k2) {
    SideQueue side(S == Space::Cuda);
    compact_shares(ne, k1, k2);
    if constexpr (S == Space::Cuda) {
      const std::size_t bytes = sizeof(ContactShare) * out_.size();
      share_read_.resize(kShareHead + bytes);
      cuda_copy_queued(share_read_.data(), count_.cview().p, sizeof(int));
      if (bytes > 0) cuda_copy_queued(share_read_.data() + kShareHead, out_.cview().p, bytes);
      shares_mark_.record();
    }
  }

  // Each vertex that other ranks sent shares for: f = its force before contact (base_) + its
  // entries and those shares merged in key order and summed (the one-rank order); every other
  // vertex has its sum from the element gather. The host groups the shares by vertex (linked
  // through share_head_, O(n)), sorts each vertex's few by key and queues their copy; on the
  // device a thread a vertex walks its entries (in key order, with their keys in ekey_) and its
  // shares side by side into msum_, on the side stream from gather_local's end (summed_), beside
  // the element gather (cube block, 4 x H200: the merge had followed it, ~20 us on the step's
  // path); the default stream then adds base_ + msum_.
  void merge_shares(Vec3View f, std::span<const ContactShare> in) {
    const auto nin = static_cast<std::int64_t>(in.size());
    for (const ContactShare& c : in)
      if (c.vertex < 0 || c.vertex >= nfv_ || !share_host_[c.vertex])
        throw std::logic_error("contact share for vertex " + std::to_string(c.vertex) +
                               ", which is not a share target of this rank");
    if (nin == 0) return;
    share_next_.resize(static_cast<std::size_t>(nin));
    share_first_.clear();
    for (std::int64_t m = 0; m < nin; ++m) {
      std::int32_t& h = share_head_[in[m].vertex];
      if (h < 0) share_first_.push_back(static_cast<std::int32_t>(in[m].vertex));
      share_next_[m] = h;
      h = static_cast<std::int32_t>(m);
    }
    // Grown arrays are new memory from the default stream's pool: the side stream may use them
    // only from a point the default stream reached after their allocation (now, not summed_).
    const bool grows = in_.size() < nin || msum_.size() < nin;
    fit_count(in_, nin);
    fit_count(msum_, nin);
    ContactShare* grouped = in_.view().p;
    if constexpr (S == Space::Cuda) {
      fit_count(share_write_, static_cast<std::int64_t>(sizeof(ContactShare)) * nin);
      grouped = reinterpret_cast<ContactShare*>(share_write_.data());
    }
    std::int64_t j = 0;
    for (const std::int32_t v : share_first_) {
      const std::int64_t first = j;
      for (std::int32_t m = share_head_[v]; m >= 0; m = share_next_[m]) grouped[j++] = in[m];
      share_head_[v] = -1;
      std::sort(grouped + first, grouped + j,
                [](const ContactShare& a, const ContactShare& b) { return share_less(a, b); });
    }
    const auto shares = in_.cview();
    const auto msum = msum_.view();
    const auto ev = ent_v_.cview();
    const auto ef = ent_f_.cview();
    const auto vcnt = vcnt_.cview();
    const auto vent = vent_.cview();
    const auto base = base_.cview();
    const auto target = share_flag_.cview();
    {
      SideQueue side(S == Space::Cuda, grows ? nullptr : &summed_);
      if constexpr (S == Space::Cuda)
        cuda_copy_queued(in_.view().p, grouped, sizeof(ContactShare) * nin);
      // A share target's entries' keys in global ids, which the merge compares with the shares:
      // a thread an entry here, where each vertex's merge had waited for a chain of dependent
      // loads a key (that kernel: 39 us of a 4-GPU step on an H200, on the step's critical path).
      const auto ekey = ekey_.view();
      const ShareKeys key{pk1_.cview(), pk2_.cview(), tri_gid_.cview(), edge_gid_.cview()};
      const std::int64_t nfv = nfv_;
      for_each(
          Exec{}, 4 * n_prev_, QDEMSPH_LAMBDA(std::int64_t e) {
            const int i = ev[e];
            if (i >= 0 && i < nfv && target[i]) ekey[e] = key(e);
          });
      const auto ekc = ekey_.cview();
      for_each(
          Exec{}, nin, QDEMSPH_LAMBDA(std::int64_t lo) {
            if (!first_of_vertex(shares, lo)) return;
            const int i = shares[lo].vertex;
            std::int64_t c = lo;
            Vec3 s{};
            const int e = vcnt[i + 1];
            for (int a = vcnt[i]; a < e; a += kMergeChunk) {
              ContactShare k8[kMergeChunk];
              QDEMSPH_UNROLL
              for (int k = 0; k < kMergeChunk; ++k)
                if (a + k < e) {
                  const ContactShare& ek = ekc[vent[a + k]];
                  k8[k].k1 = ek.k1, k8[k].k2 = ek.k2, k8[k].slot = ek.slot;
                }
              QDEMSPH_UNROLL
              for (int k = 0; k < kMergeChunk; ++k)
                if (a + k < e) {
                  for (; c < nin && shares[c].vertex == i && !share_less(k8[k], shares[c]); ++c)
                    s += shares[c].f;
                  s += ef[vent[a + k]];
                }
            }
            for (; c < nin && shares[c].vertex == i; ++c) s += shares[c].f;
            msum.set(lo, s);
          });
      if constexpr (S == Space::Cuda) merged_.record();
    }
    merged_.follow();
    const auto msc = msum_.cview();
    for_each(
        Exec{}, nin, QDEMSPH_LAMBDA(std::int64_t lo) {
          if (first_of_vertex(shares, lo)) {
            const int i = shares[lo].vertex;
            f.set(i, base[i] + msc[lo]);
          }
        });
  }

  // Drops the records another rank evaluates (a fixed vertex's point-face hits: tested wherever
  // both sides are held, so that the duplicate filter sees them all); the key order stays.
  std::int64_t keep_evaluated(std::int64_t nc) {
    fit_count(keep_, nc + 1);
    fit_count(rec_tmp_, nc);
    const auto rec = rec_.cview();
    const auto keep = keep_.view();
    const Evaluator ev = evaluator();
    for_each(
        Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) { keep[c] = ev.owns(rec[c].type, rec[c].v); });
    const std::int64_t n = exclusive_scan(Exec{}, keep, nc);
    const auto out = rec_tmp_.view();
    for_each(
        Exec{}, nc, QDEMSPH_LAMBDA(std::int64_t c) {
          if (keep[c + 1] > keep[c]) out[keep[c]] = rec[c];
        });
    std::swap(rec_, rec_tmp_);
    return n;
  }

  // The contact flagged by the penetration guard since the last call, if any (clears it).
  // Vertex and body indices are the uploaded model's.
  std::optional<DeepContact> take_deep_contact() {
    if (read_back(pen_flag_, 0) == 0) return std::nullopt;
    const ContactRecord r = pen_rec_.to_host()[0];
    const std::vector<double> val = pen_val_.to_host();
    pen_flag_.zero();
    return DeepContact{r.v[0], r.body1, r.body2, r.wall, val[0], val[1]};
  }

 private:
  std::int64_t nv_ = 0, nfv_ = 0, nfree_ = 0, ntri_ = 0, ne_ = 0, np_ = 0, npf_ = 0, nwv_ = 0,
               nw_ = 0, n_prev_ = 0;
  double d_dem_ = 0, kn_factor_ = 0.1, kt_ratio_ = 2.0 / 7.0;
  bool self_ = false, ghosts_ = false, fixed_held_ = false;
  int nm_ = 0;
  int key_b2_ = 0, key_b12_ = 0;  // sort_key's field widths (upload)
  Vec3Buffer tri_n_{S};
  Buffer<std::int32_t> edge_tri_{S};
  Buffer<std::int32_t> tri_v_{S}, edge_v_{S}, prim_v_{S}, tri_body_{S}, prim_body_{S}, own_v_{S},
      own_e_{S}, prim_tri_{S}, wall_v_{S}, body_fixed_{S}, body_mat_{S}, vertex_body_{S};
  Buffer<std::uint32_t> body_lead_{S};  // Evaluator::blead (kSplit where body_whole is empty)
  Buffer<std::uint64_t> vgid_{S}, edge_anchor_{S};
  Buffer<std::int64_t> own_v_off_{S}, own_e_off_{S}, prim_tri_off_{S};
  Buffer<double> body_h_{S}, pair_mu_{S}, pair_zeta_{S}, pair_kn_{S}, pair_E_{S}, wall_{S},
      wall_kn_{S}, inv_mass_{S}, pr_{S};
  Vec3Buffer pc_{S};
  CellList<Exec> cells_;
  CandidatePairs<Exec> pairs_;
  Buffer<ContactRecord> rec_{S}, rec_tmp_{S};
  Buffer<std::uint64_t> skey_{S};  // sort_records: keys and the order, twice n (scratch)
  Buffer<std::int32_t> vrank_{S};  // per vertex its place by global id (sort_key's id1)
  Buffer<std::int32_t> sorder_{S};
  Buffer<ContactShare> in_{S}, out_{S};          // shares received and to send (add_forces, shares)
  StagingBytes share_read_, share_write_;        // a GPU's shares on the host: out_'s, in_'s
  static constexpr std::size_t kShareHead = 64;  // share_read_: the count, then the shares
  Buffer<std::int32_t> route_rank_{S}, route_index_{S};  // ShareRoutes (set_share_routes)
  Buffer<std::int64_t> tri_gid_{S}, edge_gid_{S};
  Vec3Buffer sum_{S};   // each free vertex's contact entries summed (gather_local, sums())
  Vec3Buffer base_{S};  // an MPI rank's share targets' force before contact (sums())
  Vec3Buffer msum_{S};  // per vertex with shares, at its first: the merged sum (merge_shares)
  Buffer<std::uint8_t> share_flag_{S};  // per owned vertex: a share target (set_share_targets)
  Buffer<ContactShare> ekey_{S};  // a share target's entries' keys, in global ids (merge_shares)
  // merge_shares' grouping: per owned vertex its last share (-1: none), per share the vertex's
  // one before, the vertices with shares.
  std::vector<std::int32_t> share_head_, share_next_, share_first_;
  std::vector<std::uint8_t> share_host_;  // share_flag_ on the host (merge_shares checks)
  DeviceMark shares_mark_;                // after the shares' compaction and copy (queue_shares)
  DeviceMark forced_;                     // after the force law (evaluate)
  DeviceMark summed_, merged_;          // after gather_local; after merge_shares' side stream work
  Buffer<int> keep_{S};                 // flags and their scan (keep_evaluated, order_border_last)
  Buffer<int> tfirst_{S}, tsecond_{S};  // the narrow phase's pair order on a rank with ghosts
  bool timed_ = false;                  // the last evaluation was a dynamic step
  Buffer<int> ent_v_{S}, vcnt_{S}, vcur_{S}, vent_{S}, count_{S};
  Vec3Buffer ent_f_{S};
  Buffer<std::uint64_t> pk1_{S}, pk2_{S}, nk1_{S}, nk2_{S};
  Buffer<int> pact_{S}, nact_{S};
  Vec3Buffer pxi_{S}, nxi_{S};
  Buffer<double> pen_{S}, nen_{S}, pet_{S}, net_{S}, ediss_{S};  // per-contact energy [J]
  Vec3Buffer ph_{S}, nh_{S};       // per-contact non-potential force h (contact_energy) [N]
  Buffer<ContactRecord> prec_{S};  // the previous step's records
  // Where the stage runs: [0] the dissipated energy since the start, [1] the largest overlap.
  Buffer<double> acc_{S};
  Vec3Buffer pc_ref_{S};
  Buffer<double> pr_ref_{S};
  bool built_ = false;
  double skin_ = 0, skin_setting_ = -1;
  std::int64_t rebuilds_ = 0;
  mutable ContactStepStats stats_;     // active, max_overlap: counted by stats()
  mutable bool stats_current_ = true;  // stats_ has the last evaluation's active and overlap
  double max_pen_ = 0;  // contact.max_penetration [m]; 0: half the pair's mean surface edge
  Buffer<unsigned long long> pen_flag_{S};
  Buffer<ContactRecord> pen_rec_{S};
  Buffer<double> pen_val_{S};
  std::int64_t steps_ = 0;
  PhaseTimers timers_;
  StagingBytes stage_;  // host side of the upload (write_on_host)
};

}  // namespace qdemsph
