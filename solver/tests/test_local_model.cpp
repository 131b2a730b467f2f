// A rank's part of a distributed model (parallel/local_model.hpp), without MPI: the free
// vertices of a model are split in two "ranks" by a plane; each part holds its owned vertices,
// the tets touching them and their other vertices as ghosts (values copied from the whole
// model, as the halo exchange would). Each part evaluates the contacts anchored at its owned
// vertices (each once over the two) and hands the other the force shares of its vertices; the
// owned vertices' forces equal the whole model's bit for bit, the home tets' strain energies
// add up to the whole model's, and contact keys translate to global ids and back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "contact/contact_record.hpp"
#include "contact/contact_stage.hpp"
#include "core/exec_host.hpp"
#include "core/memory.hpp"
#include "integrate/backend.hpp"
#include "parallel/local_model.hpp"
#include "scene_fixture.hpp"

namespace qdemsph {
namespace {

using testing::make_problem;

const char* kScene = R"(
run: {mode: dynamic, end_time: 1.0}
gravity: [0, 0, -9.81]
damping: {mass: 0.3}
materials: {m: {law: svk, E: 1.0e6, nu: 0.3, density: 1000, viscosity: 20}}
contact: {d_dem: 0.01, max_penetration: 0.05}
walls: [{point: [0, 0, -0.5], normal: [0, 0, 1]}]
bodies:
  - {name: a, material: m, mesh: {type: box, size: [0.6, 0.2, 0.2], cells: [6, 2, 2]},
     velocity: [0, 0, -1], angular_velocity: [1, 2, 3]}
  - {name: floor, material: m, fixed: true, mesh: {type: box, origin: [-0.2, -0.2, -0.2], size: [1, 0.6, 0.1], cells: [2, 2, 1]}}
loads: [{type: point, body: a, at: [0.6, 0.2, 0.2], force: [1, 2, 3]}]
)";

// Two free boxes side by side along x (0.1 m cells), cut through
// the second (EdgeKeys) or in the gap (TwoParts).
const char* kTwoBodies = R"(
run: {mode: dynamic, end_time: 1.0}
materials: {m: {law: svk, E: 1.0e6, nu: 0.3, density: 1000}}
contact: {d_dem: 0.01}
bodies:
  - {name: a, material: m, mesh: {type: box, size: [0.3, 0.2, 0.2], cells: [3, 2, 2]}}
  - {name: b, material: m, mesh: {type: box, origin: [0.305, 0, 0], size: [0.3, 0.2, 0.2],
     cells: [3, 2, 2]}}
)";

// The layout of "rank" `side` (0: x < cut, 1: x >= cut), as the distributed backend builds it;
// the other side's free vertices within `band` of an owned one are held too (the contact band).
LocalLayout layout_of(const Model& g, const ModelIndex& ix, int side, double cut, double band = 0) {
  auto owner = [&](std::int64_t v) { return g.X[v].x < cut ? 0 : 1; };
  LocalLayout L;
  for (std::int64_t v = 0; v < g.n_free_vertices; ++v)
    if (owner(v) == side) L.vertices.push_back(v);
  L.n_owned = static_cast<std::int64_t>(L.vertices.size());
  std::set<std::int64_t> held, ghosts;
  for (std::int64_t u = 0; u < g.n_free_vertices; ++u)
    for (std::int64_t i = 0; i < L.n_owned && owner(u) != side; ++i)
      if (norm(g.X[u] - g.X[L.vertices[i]]) < band) ghosts.insert(u);
  for (const BodyRange& b : g.bodies) {
    int sides = 0;
    for (std::int64_t v = b.v_begin; v < b.v_end; ++v) sides |= 1 << owner(v);
    L.body_whole.push_back(b.fixed || sides == 3 ? kSplit
                           : sides == 1 << side  ? kWholeHere
                                                 : kWholeElsewhere);
  }
  for (std::int64_t i = 0; i < L.n_owned; ++i)
    for (auto q = ix.corner_off[4 * L.vertices[i]]; q < ix.corner_off[4 * L.vertices[i] + 4]; ++q)
      held.insert(ix.corner_tet[q]);
  std::vector<std::int64_t> interior, boundary, halo;
  for (std::int64_t t : held) {
    const auto& tv = g.tets[t];
    bool all = true;
    for (auto u : tv) {
      all = all && owner(u) == side;
      if (owner(u) != side) ghosts.insert(u);
    }
    (all                                                      ? interior
     : owner(*std::min_element(tv.begin(), tv.end())) == side ? boundary
                                                              : halo)
        .push_back(t);
  }
  L.vertices.insert(L.vertices.end(), ghosts.begin(), ghosts.end());
  L.n_free = static_cast<std::int64_t>(L.vertices.size());
  for (std::int64_t v = g.n_free_vertices; v < g.n_vertices(); ++v) L.vertices.push_back(v);
  L.tets = interior;
  L.n_interior = static_cast<std::int64_t>(interior.size());
  L.tets.insert(L.tets.end(), boundary.begin(), boundary.end());
  L.n_home = static_cast<std::int64_t>(L.tets.size());
  L.tets.insert(L.tets.end(), halo.begin(), halo.end());
  return L;
}

// The parts on `backend` against the whole model on the same backend: the body on the fixed
// floor cut through (kScene, 0.3), or two free bodies cut in the gap between them (kTwoBodies,
// 0.3025), whose every record the body that leads (face_leads, here b) evaluates.
void two_parts_give_the_whole_models_forces(const std::string& backend, const char* scene,
                                            double cut) {
  auto pb = make_problem(scene, "test.yaml", backend);
  const Model& g = pb.model;
  ASSERT_TRUE(g.contact.enabled);
  const ModelIndex ix = index_model(g);
  // Deform the body and lower it to within D_DEM of the floor, so that elements and contact
  // both give forces.
  Model moved = g;
  for (std::int64_t i = 0; i < g.n_free_vertices; ++i)
    moved.x[i] =
        g.X[i] + Vec3{0.01 * g.X[i].y * g.X[i].z, -0.02 * g.X[i].x, 0.015 * g.X[i].x - 0.097};
  pb.backend->upload(moved);
  pb.backend->compute_forces(1e-4, g.mass_damping);
  EXPECT_GT(pb.backend->contact_stats().at("active"), 0);
  const HostFields whole = pb.backend->download(true);
  const BackendState whole_state = pb.backend->save_state();
  const Energies whole_e = pb.backend->energies();
  // Forces are seen through a kick of dt = 1: v + f / m.
  pb.backend->kick(1.0);
  const HostFields whole_kicked = pb.backend->download(false);

  // Each part evaluates the contacts anchored at its owned vertices; the force shares of the
  // other part's vertices cross over as written (routes: the owner's index, global keys), as
  // the distributed backend sends them.
  std::vector<LocalLayout> layouts;
  std::vector<LocalModel> parts;
  std::vector<std::unique_ptr<Backend>> backends;
  std::vector<ContactShare> crossing[2];
  std::set<std::pair<std::uint64_t, std::uint64_t>> whole_keys;  // the one-process records'
  for (std::size_t e = 0; e < whole_state.contact->size(); ++e)
    whole_keys.insert({whole_state.contact->k1[e], whole_state.contact->k2[e]});
  std::int64_t records = 0, led = 0;  // led: point-face records of another part's vertex
  const double band = 0.25;
  for (int side = 0; side < 2; ++side) {
    const LocalLayout& L = layouts.emplace_back(layout_of(g, ix, side, cut, band));
    std::vector<Vec3> x, v;
    for (auto gv : L.vertices) {
      x.push_back(moved.x[gv]);
      v.push_back(moved.v[gv]);
    }
    const LocalModel& lm = parts.emplace_back(build_local_model(g, ix, L, x, v));
    EXPECT_EQ(lm.model.n_free_vertices, L.n_owned);
    EXPECT_EQ(lm.model.n_counted_tets, L.n_home);
    EXPECT_EQ(lm.model.contact.max_penetration, g.contact.max_penetration);  // settings carry over
    auto& be = backends.emplace_back(make_backend(backend));
    be->upload(lm.model);
    // The owned vertices the other part holds, as the halo sends them: only they get shares,
    // every other vertex's contact sum goes straight into f.
    const LocalLayout other = layout_of(g, ix, 1 - side, cut, band);
    const std::set<std::int64_t> held(other.vertices.begin() + other.n_owned,
                                      other.vertices.begin() + other.n_free);
    std::vector<std::int64_t> send;
    for (std::int64_t i = 0; i < L.n_owned; ++i)
      if (held.count(L.vertices[i])) send.push_back(i);
    EXPECT_GT(send.size(), 0u);
    EXPECT_LT(send.size(), static_cast<std::size_t>(L.n_owned));
    be->set_halo(send, L.n_owned, 0);
    ShareRoutes routes{{}, {}, lm.ids.triangle, lm.ids.edge};
    for (std::int64_t i = L.n_owned; i < L.n_free; ++i) {
      const auto at = std::find(other.vertices.begin(), other.vertices.end(), L.vertices[i]);
      ASSERT_LT(at - other.vertices.begin(), other.n_owned);  // the other part owns it
      routes.rank.push_back(1 - side);
      routes.index.push_back(static_cast<std::int32_t>(at - other.vertices.begin()));
    }
    be->set_share_routes(routes);
    be->element_forces(0, lm.model.n_free_tets, 1e-4, false);
    be->assemble_forces(1e-4, g.mass_damping);
    for (const ContactShare& c : be->contact_shares()) {
      EXPECT_EQ(c.rank, 1 - side);
      EXPECT_TRUE(whole_keys.count({c.k1, c.k2})) << "a share keyed as no one-process record";
      crossing[1 - side].push_back(c);
    }
    records += static_cast<std::int64_t>(be->contact_stats().at("contacts"));
    const BackendState st = be->save_state();
    // In key order (global ids), which a part's vertex indices are not.
    for (std::size_t e = 1; e < st.contact->size(); ++e)
      EXPECT_LT(std::pair(st.contact->k1[e - 1], st.contact->k2[e - 1]),
                std::pair(st.contact->k1[e], st.contact->k2[e]))
          << "record " << e;
    for (std::size_t e = 0; e < st.contact->size(); ++e)
      led += (st.contact->k1[e] >> 60) == kPointFace && st.contact->v[e][0] >= L.n_owned &&
             st.contact->v[e][0] < L.n_free;
  }
  EXPECT_EQ(led > 0, std::string(scene) == kTwoBodies);
  EXPECT_GT(crossing[0].size() + crossing[1].size(), 0u);
  EXPECT_EQ(records, static_cast<std::int64_t>(whole_state.contact->size()));  // each once

  std::map<std::pair<int, std::int64_t>, int> per_vertex;  // some vertex gets several shares
  for (int side = 0; side < 2; ++side)
    for (const ContactShare& c : crossing[side]) ++per_vertex[{side, c.vertex}];
  EXPECT_TRUE(std::any_of(per_vertex.begin(), per_vertex.end(),
                          [](const auto& kv) { return kv.second > 1; }));

  Energies sum;
  std::int64_t owned = 0, home = 0;
  for (int side = 0; side < 2; ++side) {
    const LocalLayout& L = layouts[side];
    const LocalModel& lm = parts[side];
    auto& be = backends[side];
    // Shares arrive in no fixed order: shuffled, a vertex's come out of their key order.
    std::shuffle(crossing[side].begin(), crossing[side].end(), std::mt19937(7 + side));
    be->add_contact_forces(crossing[side]);
    const BackendState st = be->save_state();
    const HostFields h = be->download(true);
    const Energies e = be->energies();
    be->kick(1.0);
    const HostFields k = be->download(false);
    std::int64_t bad = 0;
    for (std::int64_t i = 0; i < L.n_owned; ++i) {
      const std::int64_t gv = L.vertices[i];
      bad += k.v[i].x != whole_kicked.v[gv].x || k.v[i].y != whole_kicked.v[gv].y ||
             k.v[i].z != whole_kicked.v[gv].z || st.diss_v[i] != whole_state.diss_v[gv];
    }
    EXPECT_EQ(bad, 0) << "side " << side;
    // Contact keys: edges and triangles translate to global ids and back; vertices are
    // global already.
    const FeatureIds& ids = lm.ids;
    ASSERT_FALSE(ids.edge.empty());
    for (std::size_t e = 0; e < ids.edge.size(); ++e) {
      const std::uint64_t k1 = contact_key1(kEdgeEdge, e);
      EXPECT_EQ(ids.k1_to_global(k1), contact_key1(kEdgeEdge, ids.edge[e]));
      EXPECT_EQ(ids.k1_to_local(ids.k1_to_global(k1)), k1);
      EXPECT_EQ(ids.k2_to_local(k1, ids.k2_to_global(k1, e)), e);
    }
    const std::uint64_t pf = contact_key1(kPointFace, static_cast<std::uint64_t>(L.vertices[0]));
    EXPECT_EQ(ids.k1_to_global(pf), pf);
    for (std::size_t t = 0; t < ids.triangle.size(); ++t)
      EXPECT_EQ(ids.k2_to_local(pf, ids.k2_to_global(pf, t)), t);
    EXPECT_EQ(ids.k1_to_local(contact_key1(kPointFace, 1u << 30)), FeatureIds::kNone);
    for (std::int64_t j = 0; j < L.n_home; ++j) {
      EXPECT_EQ(st.diss_t[j], whole_state.diss_t[L.tets[j]]);
      EXPECT_EQ(h.von_mises[j], whole.von_mises[L.tets[j]]);
    }
    sum.kinetic += e.kinetic;
    sum.strain += e.strain;
    sum.potential += e.potential;
    sum.dissipated += e.dissipated;
    owned += L.n_owned;
    home += L.n_home;
  }
  EXPECT_EQ(owned, g.n_free_vertices);
  EXPECT_EQ(home, g.n_free_tets);
  EXPECT_NEAR(sum.strain, whole_e.strain, 1e-12 * std::abs(whole_e.strain));
  EXPECT_NEAR(sum.kinetic, whole_e.kinetic, 1e-12 * std::abs(whole_e.kinetic));
  EXPECT_NEAR(sum.potential, whole_e.potential, 1e-12 * std::abs(whole_e.potential));
  EXPECT_NEAR(sum.dissipated, whole_e.dissipated, 1e-12 * std::abs(whole_e.dissipated));
}

class TwoParts : public ::testing::TestWithParam<std::pair<const char*, double>> {};
INSTANTIATE_TEST_SUITE_P(LocalModel, TwoParts,
                         ::testing::Values(std::pair{kScene, 0.3}, std::pair{kTwoBodies, 0.3025}));
TEST_P(TwoParts, GiveTheWholeModelsForcesBitForBit) {
  two_parts_give_the_whole_models_forces("cpu", GetParam().first, GetParam().second);
}

// On a GPU the shares are read on the copy stream while the parts' own entries are summed
// (ContactStage::shares), then merged in key order.
TEST_P(TwoParts, OnTheGpuGiveTheWholeModelsForcesBitForBit) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  two_parts_give_the_whole_models_forces("cuda", GetParam().first, GetParam().second);
}

// Two arrays, byte for byte.
template <class T>
bool same(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Every array of two parts' models and ids, byte for byte.
void expect_same_parts(const LocalModel& reused, const LocalModel& fresh) {
  const Model &a = reused.model, &b = fresh.model;
  EXPECT_TRUE(same(a.X, b.X) && same(a.x, b.x) && same(a.v, b.v) && same(a.fext, b.fext) &&
              same(a.fpre, b.fpre) && same(a.mass, b.mass) && same(a.inv_mass, b.inv_mass) &&
              same(a.relax_inv_mass, b.relax_inv_mass) && same(a.flags, b.flags) &&
              same(a.gid, b.gid) && same(a.body, b.body));
  EXPECT_TRUE(same(a.tets, b.tets) && same(a.dX_inv, b.dX_inv) && same(a.vol0, b.vol0) &&
              same(a.tet_material, b.tet_material) && same(a.tet_gid, b.tet_gid) &&
              same(a.corner_off, b.corner_off) && same(a.corner_ent, b.corner_ent));
  EXPECT_EQ(a.n_free_vertices, b.n_free_vertices);
  EXPECT_EQ(a.n_free_tets, b.n_free_tets);
  EXPECT_EQ(a.n_counted_tets, b.n_counted_tets);
  const ContactModel &ca = a.contact, &cb = b.contact;
  EXPECT_EQ(ca.enabled, cb.enabled);
  EXPECT_TRUE(same(ca.tri_v, cb.tri_v) && same(ca.tri_body, cb.tri_body) &&
              same(ca.edges, cb.edges) && same(ca.edge_tri, cb.edge_tri) &&
              same(ca.own_v_off, cb.own_v_off) && same(ca.own_e_off, cb.own_e_off) &&
              same(ca.own_v, cb.own_v) && same(ca.own_e, cb.own_e));
  EXPECT_TRUE(same(ca.prim_v, cb.prim_v) && same(ca.prim_body, cb.prim_body) &&
              same(ca.prim_tri_off, cb.prim_tri_off) && same(ca.prim_tri, cb.prim_tri) &&
              same(ca.wall_vertices, cb.wall_vertices) && same(ca.body_h, cb.body_h));
  EXPECT_EQ(ca.n_free_prims, cb.n_free_prims);
  EXPECT_TRUE(same(reused.ids.vertex, fresh.ids.vertex) &&
              same(reused.ids.triangle, fresh.ids.triangle) &&
              same(reused.ids.edge, fresh.ids.edge) &&
              same(reused.ids.vertex_local, fresh.ids.vertex_local) &&
              same(reused.ids.triangle_local, fresh.ids.triangle_local) &&
              same(reused.ids.edge_local, fresh.ids.edge_local));
}

// A layout's values of a per-vertex global array.
std::vector<Vec3> values(const LocalLayout& L, const std::vector<Vec3>& from) {
  std::vector<Vec3> out;
  for (auto gv : L.vertices) out.push_back(from[gv]);
  return out;
}

// A rebuild into an earlier part's LocalModel (the distributed backend keeps one, so that its
// arrays' storage is reused) gives the same model as a fresh build, here from a larger part into
// a smaller one, and without contact after with.
TEST(LocalModel, BuildIntoAnEarlierPartsStorageEqualsAFreshBuild) {
  auto pb = make_problem(kScene);
  const Model& g = pb.model;
  const ModelIndex ix = index_model(g);
  const LocalLayout big = layout_of(g, ix, 0, 0.45), small = layout_of(g, ix, 1, 0.45);
  ASSERT_GT(big.tets.size(), small.tets.size());
  LocalModel reused;
  build_local_model(g, ix, big, values(big, g.x), values(big, g.v), reused);
  for (bool contact : {true, false}) {
    build_local_model(g, ix, small, values(small, g.x), values(small, g.v), reused, contact);
    const LocalModel fresh =
        build_local_model(g, ix, small, values(small, g.x), values(small, g.v), contact);
    expect_same_parts(reused, fresh);
    EXPECT_EQ(fresh.model.contact.enabled, contact);
    if (contact) EXPECT_GT(fresh.model.contact.prim_v.size(), 0u);
  }
}

// One part of kScene (cut at x = 0.3) with two ghost sets: its tets' other vertices (narrow),
// and those and the other side's vertices in a band (wide); the same owned vertices and tets.
// `moved`: the model's positions moved a little (a later layout's).
struct GhostLayouts {
  testing::Problem pb = make_problem(kScene);
  const Model& g = pb.model;
  const ModelIndex ix = index_model(g);
  const LocalLayout narrow = layout_of(g, ix, 0, 0.3), wide = layout_of(g, ix, 0, 0.3, 0.25);
  std::vector<Vec3> moved = g.x;
  GhostLayouts() {
    for (auto& p : moved) p += Vec3{0.001, -0.002, 0.003};
  }
};

// A rebuild of the ghosts alone (the same owned vertices and tets, same_tets: the owned
// vertices' and tets' reference data stand) into the last part's storage equals a fresh
// build, whether the ghosts grow or shrink, with x and v of the new build.
TEST(LocalModel, AGhostOnlyRebuildIntoTheLastPartEqualsAFreshBuild) {
  const GhostLayouts s;
  const auto& [pb, g, ix, narrow, wide, moved] = s;
  ASSERT_EQ(narrow.tets, wide.tets);
  ASSERT_EQ(narrow.n_owned, wide.n_owned);
  ASSERT_GT(wide.n_free, narrow.n_free);
  ASSERT_GT(narrow.n_interior, 0);
  for (const auto& [first, second] : {std::pair{&narrow, &wide}, std::pair{&wide, &narrow}}) {
    LocalModel reused;
    build_local_model(g, ix, *first, values(*first, g.x), values(*first, g.v), reused);
    build_local_model(g, ix, *second, values(*second, moved), values(*second, g.v), reused, true,
                      true);
    const LocalModel fresh =
        build_local_model(g, ix, *second, values(*second, moved), values(*second, g.v));
    expect_same_parts(reused, fresh);
  }
}

// A rank's ghosts rebuilt with its owned part the same (the distributed install of its own
// export): upload_same_tets of the new part, with the contact history alone loaded after it,
// steps as a fresh upload of that part with the whole state loaded (owned x, v and dissipation
// as the backend had them, the ghosts' x and v from the part, their dissipation zero, every
// tet's dissipation kept), bit for bit, whether the ghosts grow (their numbers and the
// boundary tets' vertex numbers change) or shrink.
void ghost_upload_keeps_the_owned_state(const char* backend) {
  const GhostLayouts s;
  const auto& [pb, g, ix, narrow, wide, moved] = s;
  ASSERT_EQ(narrow.tets, wide.tets);
  ASSERT_LT(narrow.n_interior, narrow.n_home);
  const double dt = 1e-4;
  // The ghosts' shares go to a rank 1 (this test exchanges none).
  auto route = [](Backend& be, const LocalModel& lm, const LocalLayout& L) {
    ShareRoutes r{{}, {}, lm.ids.triangle, lm.ids.edge};
    r.rank.assign(L.n_free - L.n_owned, 1);
    r.index.assign(L.n_free - L.n_owned, 0);
    be.set_share_routes(r);
  };
  auto step = [&](Backend& be) {
    be.compute_forces(dt, g.mass_damping);
    be.kick(dt);
    be.drift(dt);
  };
  for (const auto& [first, second] : {std::pair{&narrow, &wide}, std::pair{&wide, &narrow}}) {
    const LocalModel a = build_local_model(g, ix, *first, values(*first, g.x), values(*first, g.v));
    auto kept = make_backend(backend), fresh = make_backend(backend);
    kept->upload(a.model);
    route(*kept, a, *first);
    for (int n = 0; n < 20; ++n) step(*kept);
    const BackendState before = kept->save_state();
    // The new part's x and v: the owned vertices' from the backend, the others' moved.
    const LocalLayout& L = *second;
    std::vector<Vec3> x = values(L, moved), v = values(L, g.v);
    std::copy_n(before.x.begin(), L.n_owned, x.begin());
    std::copy_n(before.v.begin(), L.n_owned, v.begin());
    const LocalModel b = build_local_model(g, ix, L, x, v);
    ContactState history;
    history.dissipated = before.contact->dissipated;
    kept->upload_same_tets(b.model, L.n_interior);
    kept->load_history(history);
    route(*kept, b, L);
    BackendState st;
    st.x = x;
    st.v = v;
    st.f.assign(x.size(), Vec3{});
    st.diss_v.assign(x.size(), 0.0);
    std::copy_n(before.diss_v.begin(), L.n_owned, st.diss_v.begin());
    st.diss_t = before.diss_t;
    st.contact = history;
    fresh->upload(b.model);
    fresh->load_state(st);
    route(*fresh, b, L);
    for (int n = 0; n < 20; ++n) step(*kept), step(*fresh);
    const BackendState p = kept->save_state(), q = fresh->save_state();
    EXPECT_TRUE(same(p.x, q.x) && same(p.v, q.v) && same(p.f, q.f));
    EXPECT_TRUE(same(p.diss_v, q.diss_v) && same(p.diss_t, q.diss_t));
    EXPECT_EQ(kept->energies().total(), fresh->energies().total());
    EXPECT_FALSE(same(p.x, before.x));
  }
}

TEST(LocalModel, AGhostOnlyUploadKeepsTheOwnedStateAsALoadGivesIt) {
  ghost_upload_keeps_the_owned_state("cpu");
}

TEST(LocalModel, OnTheGpuAGhostOnlyUploadKeepsTheOwnedStateAsALoadGivesIt) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  ghost_upload_keeps_the_owned_state("cuda");
}

// A part's primitives, triangles and edges are found among its bodies' (ModelIndex's per-body
// ranges): after a build of the other body's part into the same storage, the part names none of
// that body's features, and equals a fresh build, global -> local maps included. A model whose
// items are not in body order is refused.
TEST(LocalModel, APartAfterAnotherBodysPartHoldsOnlyItsBodysFeatures) {
  auto pb = make_problem(kTwoBodies);
  const Model& g = pb.model;
  const ModelIndex ix = index_model(g);
  const ContactModel& c = g.contact;
  ASSERT_EQ(ix.body_tri_off.size(), 3u);
  ASSERT_EQ(ix.body_prim_off.size(), 3u);
  ASSERT_EQ(ix.body_edge_off.size(), 3u);
  ASSERT_EQ(ix.body_tet_off.size(), 3u);
  for (std::int64_t b = 0; b < 2; ++b) {
    for (auto t = ix.body_tet_off[b]; t < ix.body_tet_off[b + 1]; ++t)
      EXPECT_EQ(g.body[g.tets[t][0]], b);
    for (auto s = ix.body_tri_off[b]; s < ix.body_tri_off[b + 1]; ++s) EXPECT_EQ(c.tri_body[s], b);
    for (auto p = ix.body_prim_off[b]; p < ix.body_prim_off[b + 1]; ++p)
      EXPECT_EQ(c.prim_body[p], b);
    for (auto e = ix.body_edge_off[b]; e < ix.body_edge_off[b + 1]; ++e)
      EXPECT_EQ(g.body[c.edges[e][0]], b);
  }
  EXPECT_EQ(ix.body_tri_off[2], static_cast<std::int64_t>(c.tri_v.size()));
  const LocalLayout a = layout_of(g, ix, 0, 0.3025), b = layout_of(g, ix, 1, 0.3025);
  LocalModel reused;
  build_local_model(g, ix, b, values(b, g.x), values(b, g.v), reused);
  ASSERT_GT(reused.ids.triangle.size(), 0u);
  build_local_model(g, ix, a, values(a, g.x), values(a, g.v), reused);
  const LocalModel fresh = build_local_model(g, ix, a, values(a, g.x), values(a, g.v));
  EXPECT_EQ(reused.ids.triangle, fresh.ids.triangle);
  EXPECT_EQ(reused.ids.edge, fresh.ids.edge);
  EXPECT_EQ(reused.ids.triangle_local, fresh.ids.triangle_local);
  EXPECT_EQ(reused.ids.edge_local, fresh.ids.edge_local);
  EXPECT_EQ(reused.model.contact.prim_v, fresh.model.contact.prim_v);
  ASSERT_GT(fresh.ids.triangle.size(), 0u);
  for (auto s : fresh.ids.triangle) EXPECT_EQ(c.tri_body[s], 0);
  for (auto s = ix.body_tri_off[1]; s < ix.body_tri_off[2]; ++s)
    EXPECT_EQ(reused.ids.triangle_local[s], -1);
  // A model that does not keep its items in body order is refused.
  Model unordered = g;
  std::swap(unordered.contact.tri_body.front(), unordered.contact.tri_body.back());
  EXPECT_THROW(index_model(unordered), std::logic_error);
}

// A body this rank owns whole, closed (ModelIndex::body_closed: the boxes' are), gives all its
// primitives, triangles and edges without a test: the part equals the one built with every
// body's items tested (no body_whole), with the other body's ghosts in the band, into fresh
// storage and into the other part's.
TEST(LocalModel, AWholeBodyHoldsAllItsFeaturesWithoutATest) {
  auto pb = make_problem(kTwoBodies);
  const Model& g = pb.model;
  const ModelIndex ix = index_model(g);
  EXPECT_EQ(ix.body_closed, (std::vector<std::uint8_t>{1, 1}));
  for (int side : {0, 1}) {
    const LocalLayout L = layout_of(g, ix, side, 0.3025, 0.05);
    ASSERT_EQ(L.body_whole[side], kWholeHere);
    ASSERT_GT(L.n_free, L.n_owned);  // the other body's ghosts
    LocalLayout tested = L;
    tested.body_whole.clear();
    const LocalModel fast = build_local_model(g, ix, L, values(L, g.x), values(L, g.v));
    const LocalModel slow = build_local_model(g, ix, tested, values(L, g.x), values(L, g.v));
    expect_same_parts(fast, slow);
    const LocalLayout other = layout_of(g, ix, 1 - side, 0.3025, 0.05);
    LocalModel reused;
    build_local_model(g, ix, other, values(other, g.x), values(other, g.v), reused);
    build_local_model(g, ix, L, values(L, g.x), values(L, g.v), reused);
    expect_same_parts(reused, slow);
    EXPECT_GT(slow.ids.triangle.size(), static_cast<std::size_t>(ix.body_tri_off[1]) / 2);
  }
  // A primitive that names another body's triangle opens its body.
  Model open = g;
  open.contact.prim_tri[open.contact.prim_tri_off[0]] =
      static_cast<std::int32_t>(ix.body_tri_off[1]);
  EXPECT_EQ(index_model(open).body_closed, (std::vector<std::uint8_t>{0, 1}));
}

// A part's corner lists (taken from the global index, not sorted) hold each owned vertex's
// corners in the one-rank order: by corner, then tet global id.
TEST(LocalModel, CornerListsAreInTheOneRankOrder) {
  auto pb = make_problem(kScene);
  const Model& g = pb.model;
  const ModelIndex ix = index_model(g);
  for (int side = 0; side < 2; ++side) {
    const LocalLayout L = layout_of(g, ix, side, 0.3);
    std::vector<Vec3> x;
    for (auto gv : L.vertices) x.push_back(g.x[gv]);
    const Model m = build_local_model(g, ix, L, x, x).model;
    const std::int64_t nt = m.n_tets();
    std::vector<std::vector<std::pair<int, std::uint64_t>>> want(L.n_owned);
    for (std::int64_t t = 0; t < nt; ++t)
      for (int k = 0; k < 4; ++k)
        if (m.tets[t][k] < L.n_owned) want[m.tets[t][k]].push_back({k, m.tet_gid[t]});
    ASSERT_EQ(static_cast<std::int64_t>(m.corner_off.size()), L.n_owned + 1);
    std::int64_t bad = 0;
    for (std::int64_t i = 0; i < L.n_owned; ++i) {
      std::sort(want[i].begin(), want[i].end());
      std::vector<std::pair<int, std::uint64_t>> got;
      for (std::int64_t q = m.corner_off[i]; q < m.corner_off[i + 1]; ++q) {
        const std::int64_t e = m.corner_ent[q], k = e / nt, t = e % nt;
        bad += m.tets[t][k] != i;
        got.push_back({static_cast<int>(k), m.tet_gid[t]});
      }
      bad += got != want[i];
    }
    EXPECT_EQ(bad, 0) << "side " << side;
  }
}

// The anchor of a record (the rank owning it evaluates it): a point-face record's face vertex
// when the face's body is whole and first (face_leads), else a point-face or wall record's free
// side-1 vertex, else the free vertex of smallest global id (for an edge pair, of the body
// first: a whole body before a split one, else by body_priority), or none.
// A vertex's shares are merged in the one-rank order of its entries: by record key k1, then k2,
// then slot (share_less); the owner sorts each vertex's shares so before the merge, whatever
// order they arrived in.
TEST(LocalModel, AVertexsSharesAreTakenInKeyOrder) {
  auto share = [](std::uint64_t k1, std::uint64_t k2, int slot) {
    ContactShare c;
    c.k1 = k1, c.k2 = k2, c.slot = slot;
    return c;
  };
  const std::vector<ContactShare> run = {share(7, 1, 0), share(3, 9, 2), share(7, 0, 3),
                                         share(3, 9, 1), share(2, 50, 0)};
  EXPECT_TRUE(share_less(run[4], run[3]));   // k1 first
  EXPECT_TRUE(share_less(run[2], run[0]));   // then k2
  EXPECT_TRUE(share_less(run[3], run[1]));   // then the slot
  EXPECT_FALSE(share_less(run[1], run[1]));  // strict
  std::vector<std::int64_t> order = {0, 1, 2, 3, 4};
  std::sort(order.begin(), order.end(),
            [&](std::int64_t a, std::int64_t b) { return share_less(run[a], run[b]); });
  EXPECT_EQ(order, (std::vector<std::int64_t>{4, 3, 1, 2, 0}));
}

TEST(LocalModel, AnchorSlotKnownAnswers) {
  struct Ids {  // gid = index; ids >= 1000000 are a fixed body's; body = id / 100
    bool free(std::int64_t i) const { return i < 1000000; }
    std::uint64_t gid(std::int64_t i) const { return static_cast<std::uint64_t>(i); }
    std::int64_t body(std::int64_t i) const { return i / 100; }
    bool whole(std::int64_t b) const { return b % 3 != 0; }
  } ids;
  // Which of bodies b, b + 1 comes first.
  auto first = [&](std::int64_t b) {
    if (ids.whole(b) != ids.whole(b + 1)) return ids.whole(b) ? b : b + 1;
    return body_priority(b + 1) < body_priority(b) ? b + 1 : b;
  };
  const std::int64_t pf[4] = {7, 3, 2, 1}, wall[4] = {7, -1, -1, -1};
  EXPECT_EQ(anchor_slot(kPointFace, pf, ids), 0);
  EXPECT_EQ(anchor_slot(kWall, wall, ids), 0);
  const std::int64_t fixed_pf[4] = {1000001, 3, 2, 1};  // a fixed vertex on a free face
  EXPECT_EQ(anchor_slot(kPointFace, fixed_pf, ids), 3);
  const std::int64_t edges[4] = {5, 9, 2, 7};
  EXPECT_EQ(anchor_slot(kEdgeEdge, edges, ids), 2);
  const std::int64_t fixed_edge[4] = {1000000, 9, 1000002, 7};
  EXPECT_EQ(anchor_slot(kEdgeEdge, fixed_edge, ids), 3);
  const std::int64_t none[4] = {1000001, 1000002, -1, -1};
  EXPECT_EQ(anchor_slot(kEdgeEdge, none, ids), -1);
  // Two free bodies' edges: the smaller id of the edge of the body first, whichever edge comes
  // first in the record; where both bodies are whole or split, each side anchors about half.
  int lower = 0, ties = 0;
  for (std::int64_t b = 0; b < 300; ++b) {
    const std::int64_t e[4] = {100 * b + 5, 100 * b + 9, 100 * b + 107, 100 * b + 103};
    const std::int64_t swapped[4] = {e[2], e[3], e[0], e[1]};
    const int k = anchor_slot(kEdgeEdge, e, ids);
    EXPECT_EQ(k, first(b) == b ? 0 : 3) << "bodies " << b << ", " << b + 1;
    EXPECT_EQ(swapped[anchor_slot(kEdgeEdge, swapped, ids)], e[k]);
    if (ids.whole(b) == ids.whole(b + 1)) {
      ++ties;
      lower += k == 0;
    }
  }
  EXPECT_EQ(ties, 100);
  EXPECT_GT(lower, 30);
  EXPECT_LT(lower, 70);
  // A vertex of body b + 1 on a face of body b: the face's vertex when b is whole and first
  // (face_leads), else the point.
  int faces = 0;
  for (std::int64_t b = 0; b < 300; ++b) {
    const std::int64_t p[4] = {100 * b + 107, 100 * b + 3, 100 * b + 2, 100 * b + 1};
    const bool leads = ids.whole(b) && first(b) == b;
    EXPECT_EQ(anchor_slot(kPointFace, p, ids), leads ? 1 : 0) << "bodies " << b + 1 << ", " << b;
    faces += leads;
  }
  EXPECT_GT(faces, 100);  // the 100 whole bodies b before a split b + 1, and some of the others
  EXPECT_LT(faces, 200);
}

// The narrow phase skips an edge pair another rank evaluates before loading its vertices, from
// one key per edge (ContactTopology::evaluates_edges): the same answer as the record's anchor
// (Evaluator::owns) for every pair of edges in each part, across the cut too; for a body and
// a fixed floor (kScene) and for two free bodies (kTwoBodies: body_order).
class EdgeKeys : public ::testing::TestWithParam<std::pair<const char*, double>> {};
INSTANTIATE_TEST_SUITE_P(LocalModel, EdgeKeys,
                         ::testing::Values(std::pair{kScene, 0.3}, std::pair{kTwoBodies, 0.35}));
TEST_P(EdgeKeys, TellTheEdgePairsAnchorOwner) {
  const auto [scene, cut] = GetParam();
  auto pb = make_problem(scene, "test.yaml", "cpu");
  const Model& g = pb.model;
  const ModelIndex ix = index_model(g);
  std::int64_t two_bodies = 0;  // crossing pairs of two free bodies' edges
  for (int side = 0; side < 2; ++side) {
    const LocalLayout L = layout_of(g, ix, side, cut);
    std::vector<Vec3> x, v;
    for (auto gv : L.vertices) {
      x.push_back(g.x[gv]);
      v.push_back(g.v[gv]);
    }
    const LocalModel lm = build_local_model(g, ix, L, x, v);
    ContactStage<HostExec> stage;
    stage.upload(lm.model);
    const ContactTopology t = stage.topology();
    ASSERT_FALSE(t.eval.all);
    const auto& edges = lm.model.contact.edges;
    const auto ne = static_cast<int>(edges.size());
    std::int64_t mismatched = 0, here = 0, crossing = 0;
    for (int a = 0; a < ne; ++a)
      for (int b = a + 1; b < ne; ++b) {
        const std::int32_t ends[4] = {edges[a][0], edges[a][1], edges[b][0], edges[b][1]};
        const bool owns = t.eval.owns(kEdgeEdge, ends);
        mismatched += t.evaluates_edges(a, b) != owns || t.evaluates_edges(b, a) != owns;
        here += owns;
        int owned = 0;
        for (const std::int32_t i : ends) owned += i < lm.model.n_free_vertices;
        crossing += owned > 0 && owned < 4;
        two_bodies += owned > 0 && owned < 4 && ends[0] < t.eval.nfree && ends[2] < t.eval.nfree &&
                      lm.model.body[ends[0]] != lm.model.body[ends[2]];
      }
    EXPECT_EQ(mismatched, 0) << "side " << side;
    EXPECT_GT(here, 0) << "side " << side;
    EXPECT_GT(crossing, 0) << "side " << side;
  }
  EXPECT_EQ(two_bodies > 0, std::string(scene) == kTwoBodies);
}

// A distributed rank queues its interior tets before the ranks agree that the layout stays;
// a rebuild discards that evaluation and undo_dissipation() takes its dissipated energy back,
// bit for bit (the tets then run again on the new layout).
TEST(LocalModel, UndoableElementForcesRestoreTheDissipatedEnergy) {
  auto pb = make_problem(kScene);
  const Model& g = pb.model;
  Model moved = g;
  for (std::int64_t i = 0; i < g.n_free_vertices; ++i)
    moved.v[i] = moved.v[i] + Vec3{0.1 * g.X[i].x, 0, 0};
  Backend& be = *pb.backend;
  be.upload(moved);
  be.compute_forces(1e-4, g.mass_damping);
  const double before = be.energies().dissipated;
  ASSERT_GT(before, 0.0);
  be.element_forces(0, g.n_free_tets, 1e-4, true);
  EXPECT_GT(be.energies().dissipated, before);
  be.undo_dissipation();
  EXPECT_EQ(be.energies().dissipated, before);
  be.undo_dissipation();  // nothing left to undo
  EXPECT_EQ(be.energies().dissipated, before);
  be.element_forces(0, g.n_free_tets, 1e-4, false);  // not undoable: undo is a no-op
  const double after = be.energies().dissipated;
  EXPECT_GT(after, before);
  be.undo_dissipation();
  EXPECT_EQ(be.energies().dissipated, after);
}

}  // namespace
}  // namespace qdemsph
