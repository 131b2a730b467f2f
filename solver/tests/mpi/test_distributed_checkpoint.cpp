// Checkpoints of distributed runs under mpirun (1, 2 and 4 ranks): capture_checkpoint and
// restore_checkpoint (integrate/restart.hpp) over a DistributedBackend, whose save_state
// gathers the whole model's state to rank 0 and whose load_state gives each rank a share, on
// the contact scene (tangential history across rank borders, rebalanced every 10 steps):
//
//  - the checkpoint written on all P ranks holds the state of the one-rank checkpoint of the
//    same step bit for bit (vertices and tets by id, history entries in key order);
//  - that file restarted on P, P/2 and 1 ranks, and the one-rank file restarted on P ranks,
//    continue exactly as the one-rank restart of the same file: positions, velocities,
//    forces, dissipation and contact history bit for bit (forces are summed in the one-rank
//    order on any rank count), energies to round-off (sums reduced over ranks);
//  - the one-rank restart of the P-rank file equals the uninterrupted run bit for bit (the
//    file holds the force of the last evaluation, so nothing is recomputed);
//  - a fluid coupled to a body (distributed_fixture.hpp, kCoupledScene): the checkpoint of P
//    ranks equals the one-rank one (with the fluid's coupling force fc on the body's vertices,
//    which the next sub-steps add to the forces), and the P-rank and one-rank files restarted
//    on P, P/2 and 1 ranks continue bit for bit as the uninterrupted one-rank run (fluid and
//    body).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "distributed_fixture.hpp"
#include "integrate/restart.hpp"
#include "integrate/stepper.hpp"
#include "io/checkpoint_h5.hpp"
#include "parallel/distributed_backend_mpi.hpp"
#include "tests/scene_fixture.hpp"

using namespace qdemsph;
using namespace qdemsph::mpi_testing;

namespace {

namespace fs = std::filesystem;

// The checkpoint at step 30 (dt 0.2 ms): 66 history entries, point-face and edge-edge, as
// the cubes leave the block; the 150 steps after it take the touches to their end and bring
// cube a against the wall (wall history).
constexpr int kBefore = 30, kAfter = 150;

void run(Stepper& st, int n) {
  for (int k = 0; k < n; ++k) st.step();
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// The active entries of a history (a checkpoint keeps those: an inactive one is never looked
// up).
ContactState active_of(const ContactState& c) {
  ContactState a;
  for (std::size_t e = 0; e < c.size(); ++e)
    if (c.active[e]) a.push_back(c, e);
  return a;
}

// The history entries of two states, field by field, bit for bit (keys: empty in a
// checkpoint, whose contact_keys hold them).
void expect_same_history(const ContactState& a, const ContactState& b, const std::string& what) {
  EXPECT_EQ(a.k1, b.k1) << what << ": history keys differ";
  EXPECT_EQ(a.k2, b.k2) << what << ": history keys differ";
  EXPECT_TRUE(same_bits(a.xi, b.xi)) << what << ": tangential springs differ";
  EXPECT_TRUE(same_bits(a.h, b.h)) << what << ": non-potential forces differ";
  EXPECT_TRUE(same_bits(a.energy, b.energy)) << what << ": stored energies differ";
  EXPECT_TRUE(same_bits(a.energy_t, b.energy_t)) << what << ": stored energies differ";
  EXPECT_EQ(a.v, b.v) << what << ": record vertices differ";
  EXPECT_TRUE(same_bits(a.w, b.w)) << what << ": record weights differ";
  EXPECT_EQ(a.n1, b.n1) << what;
}

// Two whole-model states (a checkpoint's, one rank's, or a distributed save_state on rank 0)
// must be equal bit for bit, the history compared by its active entries (`live`: the states
// of running backends, which also keep inactive ones); returns the largest position
// difference for the record.
double expect_same_state(const BackendState& a, const BackendState& b, bool live,
                         const std::string& what) {
  EXPECT_TRUE(same_bits(a.x, b.x)) << what << ": positions differ";
  EXPECT_TRUE(same_bits(a.v, b.v)) << what << ": velocities differ";
  EXPECT_TRUE(same_bits(a.f, b.f)) << what << ": forces differ";
  EXPECT_TRUE(same_bits(a.diss_v, b.diss_v)) << what << ": vertex dissipation differs";
  EXPECT_TRUE(same_bits(a.diss_t, b.diss_t)) << what << ": tet dissipation differs";
  EXPECT_TRUE(a.contact && b.contact) << what;
  if (a.contact && b.contact) {
    if (live)
      expect_same_history(active_of(*a.contact), active_of(*b.contact), what);
    else
      expect_same_history(*a.contact, *b.contact, what);
  }
  return a.x.size() == b.x.size() ? max_diff(a.x, b.x) : INFINITY;
}

double relative(double a, double b, double scale) { return std::abs(a - b) / scale; }

// The restarts each test makes: the p-rank checkpoint `b` on p, p / 2 and 1 ranks, and the
// one-rank checkpoint `a` on p ranks.
struct Restart {
  const Checkpoint* c;
  fs::path file;
  int written_on, ranks;
};
std::vector<Restart> restart_cases(const Checkpoint& a, const fs::path& one_file,
                                   const Checkpoint& b, const fs::path& all_file, int p) {
  std::vector<Restart> cases{{&b, all_file, p, p}};
  for (int m : {p / 2, 1})
    if (m >= 1 && m != cases.back().ranks) cases.push_back({&b, all_file, p, m});
  if (p > 1) cases.push_back({&a, one_file, 1, p});
  return cases;
}

}  // namespace

TEST(DistributedCheckpoint, WrittenOnAnyRanksRestartsOnAnyRanks) {
  const Problem r = load(kContactScene);
  const double dt = choose_dt(r.model, std::nullopt, 0.5);
  const int p = size_of(), me = rank_of();
  // Own folder per rank count: ctest may run the np1/np2/np4 entries at the same time.
  const fs::path dir = qdemsph::testing::scratch_dir("mpi_checkpoint_np" + std::to_string(p));
  const fs::path one_file = dir / "one_rank.h5", all_file = dir / "all_ranks.h5";

  // One rank, uninterrupted: kBefore steps, a checkpoint, kAfter more.
  auto straight_be = make_host_backend();
  straight_be->upload(r.model);
  Stepper straight(r.model, *straight_be, dt);
  run(straight, kBefore);
  const Checkpoint one =
      capture_checkpoint(r.scene, r.model, dt, *straight_be, nullptr, nullptr, straight);
  run(straight, kAfter);
  // All ranks: the same kBefore steps, the checkpoint gathered to rank 0 (collective).
  Checkpoint all;
  {
    auto dist = make_distributed_backend(MPI_COMM_WORLD, make_host_backend(), options(10, 0.0));
    dist->upload(r.model);
    Stepper st(r.model, *dist, dt);
    run(st, kBefore);
    all = capture_checkpoint(r.scene, r.model, dt, *dist, nullptr, nullptr, st);
  }
  if (me == 0) {
    write_checkpoint(one_file, one);
    write_checkpoint(all_file, all);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const Checkpoint a = read_checkpoint(one_file), b = read_checkpoint(all_file);

  // The files hold the same state (the contact dissipation is a sum over ranks: round-off).
  EXPECT_EQ(a.vertex_gid, b.vertex_gid);
  EXPECT_EQ(a.tet_gid, b.tet_gid);
  ASSERT_TRUE(b.solid.contact.has_value());
  EXPECT_GT(b.contact_keys.size(), 0u) << "no contact at the checkpoint";
  EXPECT_EQ(a.contact_keys.size(), b.contact_keys.size());
  for (std::size_t k = 0; k < std::min(a.contact_keys.size(), b.contact_keys.size()); ++k) {
    EXPECT_EQ(a.contact_keys[k].type, b.contact_keys[k].type) << "history entry " << k;
    EXPECT_EQ(a.contact_keys[k].a, b.contact_keys[k].a) << "history entry " << k;
    EXPECT_EQ(a.contact_keys[k].b, b.contact_keys[k].b) << "history entry " << k;
  }
  expect_same_state(a.solid, b.solid, false, "one-rank vs all-rank checkpoint");
  EXPECT_LE(relative(a.solid.contact->dissipated, b.solid.contact->dissipated,
                     std::abs(a.solid.contact->dissipated)),
            1e-12);

  // Reference: the one-rank restart of the P-rank file; it equals the uninterrupted run.
  auto ref_be = make_host_backend();
  ref_be->upload(r.model);
  Stepper ref(r.model, *ref_be, dt);
  restore_checkpoint(b, all_file.string(), r.scene, r.model, dt, *ref_be, nullptr, nullptr, ref);
  run(ref, kAfter);
  const BackendState want = ref_be->save_state();
  const Energies ew = ref_be->energies();
  const double scale = std::abs(ew.kinetic) + std::abs(ew.strain) + std::abs(ew.potential) +
                       std::abs(ew.dissipated) + std::abs(ew.contact) +
                       std::abs(ew.contact_dissipated);
  expect_same_state(straight_be->save_state(), want, true, "uninterrupted vs one-rank restart");
  EXPECT_LE(relative(straight_be->energies().total(), ew.total(), scale), 1e-12);
  if (me == 0)
    std::printf("[checkpoint, %d ranks] %zu vertices, %zu history entries\n", p,
                b.vertex_gid.size(), b.contact_keys.size());

  const std::vector<Restart> cases = restart_cases(a, one_file, b, all_file, p);
  for (const Restart& c : cases) {
    SCOPED_TRACE(std::to_string(c.written_on) + " -> " + std::to_string(c.ranks) + " ranks");
    MPI_Comm sub;
    MPI_Comm_split(MPI_COMM_WORLD, me < c.ranks ? 0 : MPI_UNDEFINED, me, &sub);
    if (sub == MPI_COMM_NULL) continue;
    auto dist = make_distributed_backend(sub, make_host_backend(), options(10, 0.0));
    dist->upload(r.model);
    Stepper st(r.model, *dist, dt);
    restore_checkpoint(*c.c, c.file.string(), r.scene, r.model, dt, *dist, nullptr, nullptr, st);
    run(st, kAfter);
    const BackendState got = dist->save_state();  // collective: on rank 0 of `sub`
    const Energies e = dist->energies();
    if (rank_of(sub) == 0) {
      EXPECT_EQ(st.steps(), ref.steps());
      EXPECT_EQ(st.time(), ref.time());
      const double dx = expect_same_state(want, got, true, "restart vs the one-rank restart");
      const double de = relative(e.total(), ew.total(), scale);
      const double dd =
          relative(e.contact_dissipated, ew.contact_dissipated, std::abs(ew.contact_dissipated));
      EXPECT_LE(de, 1e-12);
      EXPECT_LE(dd, 1e-12);
      std::printf(
          "[checkpoint %d -> %d ranks] max |dx| = %.3e m, energy %.3e, contact "
          "dissipation %.3e (relative), %ld rebalances\n",
          c.written_on, c.ranks, dx, de, dd, static_cast<long>(dist->rebalances()));
    }
    MPI_Comm_free(&sub);
  }
}

namespace {

// Every field of two fluid states, bit for bit.
void expect_same_fluid(const FluidState& a, const FluidState& b, const std::string& what) {
  EXPECT_EQ(a.gid, b.gid) << what << ": particle order differs";
  EXPECT_EQ(a.type, b.type) << what;
  EXPECT_TRUE(same_bits(a.x, b.x)) << what << ": fluid positions differ";
  EXPECT_TRUE(same_bits(a.v, b.v)) << what << ": fluid velocities differ";
  EXPECT_TRUE(same_bits(a.a, b.a)) << what << ": fluid accelerations differ";
  EXPECT_TRUE(same_bits(a.rho, b.rho)) << what << ": fluid densities differ";
  EXPECT_TRUE(same_bits(a.p, b.p)) << what << ": fluid pressures differ";
  EXPECT_TRUE(same_bits(a.m, b.m)) << what << ": fluid masses differ";
}

// The body's state of a coupled run (no contact history in the comparison: the cube rests on
// a wall, whose entries expect_same_state compares).
double expect_same_body(const BackendState& a, const BackendState& b, const std::string& what) {
  EXPECT_TRUE(same_bits(a.fc, b.fc)) << what << ": coupling forces differ";
  return expect_same_state(a, b, true, what);
}

}  // namespace

TEST(DistributedCheckpoint, CoupledFluidRestartsOnAnyRanksExactly) {
  constexpr int kFluidBefore = 150, kFluidAfter = 100;  // fluid steps (2 solid sub-steps each)
  const Problem r = load(kCoupledScene);
  const FluidSetup f = coupled_fluid(r);
  const double dt = CoupledRun::kStep;
  const int p = size_of(), me = rank_of();
  const fs::path dir =
      qdemsph::testing::scratch_dir("mpi_coupled_checkpoint_np" + std::to_string(p));
  const fs::path one_file = dir / "one_rank.h5", all_file = dir / "all_ranks.h5";
  auto capture = [&](CoupledRun& c) {
    return capture_checkpoint(r.scene, r.model, dt, *c.be, c.fluid.get(), &f, *c.st);
  };

  // One rank, uninterrupted (on every rank: each compares its own restarts against it).
  CoupledRun straight(r.model, f);
  run(*straight.st, kFluidBefore);
  const Checkpoint one = capture(straight);
  run(*straight.st, kFluidAfter);
  const BackendState want = straight.be->save_state();
  const FluidState want_fluid = straight.fluid->save_state();
  Checkpoint all;
  {
    CoupledRun many(r.model, f, MPI_COMM_WORLD);
    run(*many.st, kFluidBefore);
    all = capture(many);
  }
  if (me == 0) {
    write_checkpoint(one_file, one);
    write_checkpoint(all_file, all);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const Checkpoint a = read_checkpoint(one_file), b = read_checkpoint(all_file);
  ASSERT_EQ(b.solid.fc.size(), r.model.x.size());
  double fc = 0;
  for (const Vec3& v : b.solid.fc) fc = std::max(fc, norm(v));
  EXPECT_GT(fc, 0.0) << "the water does not push the cube at the checkpoint";
  expect_same_body(a.solid, b.solid, "one-rank vs all-rank checkpoint");
  ASSERT_TRUE(a.fluid && b.fluid);
  expect_same_fluid(*a.fluid, *b.fluid, "one-rank vs all-rank checkpoint");

  // The one-rank restart of the P-rank file equals the uninterrupted run.
  {
    CoupledRun re(r.model, f);
    restore_checkpoint(b, all_file.string(), r.scene, r.model, dt, *re.be, re.fluid.get(), &f,
                       *re.st);
    run(*re.st, kFluidAfter);
    const double dx = expect_same_body(want, re.be->save_state(), "one-rank restart");
    expect_same_fluid(want_fluid, re.fluid->save_state(), "one-rank restart");
    if (me == 0)
      std::printf(
          "[coupled checkpoint, %d ranks] one-rank restart: max |dx| = %.3e m, max |fc| "
          "= %.3e N at the checkpoint\n",
          p, dx, fc);
  }

  const std::vector<Restart> cases = restart_cases(a, one_file, b, all_file, p);
  for (const Restart& c : cases) {
    SCOPED_TRACE(std::to_string(c.written_on) + " -> " + std::to_string(c.ranks) + " ranks");
    MPI_Comm sub;
    MPI_Comm_split(MPI_COMM_WORLD, me < c.ranks ? 0 : MPI_UNDEFINED, me, &sub);
    if (sub == MPI_COMM_NULL) continue;
    {
      CoupledRun re(r.model, f, sub);
      restore_checkpoint(*c.c, c.file.string(), r.scene, r.model, dt, *re.be, re.fluid.get(), &f,
                         *re.st);
      run(*re.st, kFluidAfter);
      const BackendState got = re.be->save_state();  // collective: on rank 0 of `sub`
      const FluidState got_fluid = re.fluid->save_state();
      if (rank_of(sub) == 0) {
        EXPECT_EQ(re.st->steps(), straight.st->steps());
        EXPECT_EQ(re.st->time(), straight.st->time());
        const double dx = expect_same_body(want, got, "restart vs the uninterrupted run");
        expect_same_fluid(want_fluid, got_fluid, "restart vs the uninterrupted run");
        std::printf(
            "[coupled checkpoint %d -> %d ranks] cube max |dx| = %.3e m, fluid max |dx| = %.3e "
            "m, %ld body rebalances\n",
            c.written_on, c.ranks, dx, max_diff(want_fluid.x, got_fluid.x),
            static_cast<long>(re.dist->rebalances()));
      }
    }
    MPI_Comm_free(&sub);
  }
}

// A coupled checkpoint without the coupling force (written before it was stored) is refused
// with a message, not continued inexactly.
TEST(DistributedCheckpoint, CoupledCheckpointWithoutCouplingForceIsRefused) {
  const Problem r = load(kCoupledScene);
  const FluidSetup f = coupled_fluid(r);
  CoupledRun c(r.model, f);
  run(*c.st, 2);
  Checkpoint old =
      capture_checkpoint(r.scene, r.model, CoupledRun::kStep, *c.be, c.fluid.get(), &f, *c.st);
  old.solid.fc.clear();
  CoupledRun re(r.model, f);
  try {
    restore_checkpoint(old, "old.h5", r.scene, r.model, CoupledRun::kStep, *re.be, re.fluid.get(),
                       &f, *re.st);
    ADD_FAILURE() << "a coupled checkpoint without /solid/fc was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("coupling force"), std::string::npos) << e.what();
  }
}
