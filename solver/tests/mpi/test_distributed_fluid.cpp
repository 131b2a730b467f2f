// The SPH fluid on 1, 2 and 4 ranks against one rank (docs/parallel.md, "Fluid"): a small 3D
// dam break in a tank (fluid and wall particles), the same SphStage with a FluidExchange and
// without one, stepped with the fluid's velocity Verlet (fluid_stage.hpp):
//  - positions, velocities, densities and pressures equal one rank bit for bit at every step
//    checked, with the ghost layout kept between rebuilds: on Hilbert's curve for 300 steps
//    with the partition cut again every 50 steps (threshold 0) and the skin rule rebuilding
//    the layout between cuts (on 4 ranks at steps 242 and 285), on Morton's and Peano's with
//    the partition cut again every 10 steps;
//  - after every step every particle id is present exactly once over the ranks (the gather
//    to rank 0 concatenates every rank's owned particles);
//  - the gathered state is the one-rank state in the one-rank order (a checkpoint of N ranks
//    is the one-rank file); restarting N ranks from a one-rank state continues exactly;
//  - a dam break coupled to a free cube (markers in the fluid's exchange, every marker's force
//    summed over the ranks and gathered to the cube's vertices in the one-rank order) equals
//    one rank bit for bit;
//  - a slab periodic in z (fluid.periodic_z: the ghost band wraps across the seam) equals one
//    rank bit for bit, with one band cell across the period and with six;
//  - on a GPU machine, CUDA stages on one GPU a rank equal one GPU bit for bit;
//  - the exchange's traffic (summary.json `parallel`: fluid_halo_bytes_per_step,
//    fluid_migrated_bytes) is what its plans send: ghosts x bytes per ghost x refreshes.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <numeric>
#include <set>
#include <string>

#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "core/memory.hpp"
#include "distributed_fixture.hpp"
#include "integrate/stepper.hpp"
#include "parallel/collectives.hpp"
#include "parallel/fluid_exchange.hpp"
#include "parallel/parallel_record.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/fluid_stage.hpp"

using namespace qdemsph;
using namespace qdemsph::mpi_testing;

namespace {

// A water column released in a 3D tank (2 wall layers), about 1,900 particles.
const char* kDamScene = R"(
run: {end_time: 0.1, dt: 2.0e-4}
gravity: [0, 0, -9.81]
fluid:
  spacing: 0.02
  blocks: [{min: [0, 0, 0], max: [0.2, 0.12, 0.2]}]
  tanks: [{min: [0, 0, 0], max: [0.5, 0.12, 0.3], thickness_layers: 2}]
)";

constexpr double kH = 2.0e-4;  // the fluid step (below the scene's CFL limit, 2.6e-4 s)

FluidSetup dam_setup() {
  const Scene s = parse_scene(kDamScene, "dam.yaml");
  return build_fluid(s.fluid, s.gravity);
}

std::unique_ptr<FluidStage> distributed_stage(const FluidSetup& f,
                                              const std::string& curve = "hilbert",
                                              long rebalance_every = 50) {
  return make_fluid_stage("cpu", f, nullptr,
                          make_fluid_exchange(options(rebalance_every, 0.0, curve), f));
}

void step(FluidStage& s) {
  s.kick(0.5 * kH);
  s.drift(kH);
  s.compute();
  s.kick(0.5 * kH);
}

struct StateDiff {
  double x = 0, v = 0, a = 0, rho = 0, p = 0, m = 0;
  bool same_order = true;  // gid and type in the same order
  double max() const { return std::max({x, v, a, rho, p, m}); }
  // Each field's difference the larger of this one's and d's.
  void widen(const StateDiff& d) {
    x = std::max(x, d.x), v = std::max(v, d.v), a = std::max(a, d.a);
    rho = std::max(rho, d.rho), p = std::max(p, d.p), m = std::max(m, d.m);
  }
};

StateDiff diff(const FluidState& a, const FluidState& b) {
  StateDiff d;
  if (a.gid != b.gid || a.type != b.type) {
    d.same_order = false;
    return d;
  }
  for (std::size_t i = 0; i < a.gid.size(); ++i) {
    d.x = std::max(d.x, norm(a.x[i] - b.x[i]));
    d.v = std::max(d.v, norm(a.v[i] - b.v[i]));
    d.a = std::max(d.a, norm(a.a[i] - b.a[i]));
    d.rho = std::max(d.rho, std::abs(a.rho[i] - b.rho[i]));
    d.p = std::max(d.p, std::abs(a.p[i] - b.p[i]));
    d.m = std::max(d.m, std::abs(a.m[i] - b.m[i]));
  }
  return d;
}

// This rank's contiguous share of the setup's particles, as a stage hands them to its first
// distribute() (order key = global id).
FluidParticles share_of(const FluidSetup& f) {
  const int me = rank_of(), np = size_of();
  const std::int64_t n = f.size(), b = n * me / np, e = n * (me + 1) / np;
  FluidParticles p;
  for (std::int64_t i = b; i < e; ++i) {
    p.x.push_back(f.x[i]), p.v.push_back(f.v[i]), p.rho.push_back(f.rho[i]);
    p.m.push_back(f.m[i]), p.type.push_back(f.type[i]), p.gid.push_back(f.gid[i]);
    p.key.push_back(f.gid[i]);
  }
  return p;
}

// Every particle id once among the gathered particles (rank 0).
bool each_id_once(const FluidState& s, std::int64_t n) {
  std::vector<std::uint64_t> g = s.gid;
  std::sort(g.begin(), g.end());
  std::vector<std::uint64_t> want(static_cast<std::size_t>(n));
  std::iota(want.begin(), want.end(), std::uint64_t{0});
  return g == want;
}

}  // namespace

// A new cut must save more over the next window than a layout rebuild costs: on 2 H100s a
// 4.2 ms step of 1.1 M particles per rank, 10 % above the mean for 100 steps, saves ~38 ms,
// less than one rebuild there (~0.8 s), more than a rebuild of a small scene.
TEST(DistributedFluid, RecutPaysOnlyWhenTheSavingExceedsTheRebuild) {
  const double excess = 1 - 1 / 1.1;  // max / mean - 1 = 0.1
  EXPECT_FALSE(recut_pays(excess, 4.2e-3, 100, 0.8));
  EXPECT_TRUE(recut_pays(excess, 4.2e-3, 100, 0.02));
  EXPECT_FALSE(recut_pays(0.0, 4.2e-3, 100, 0.0));
  EXPECT_TRUE(recut_pays(excess, 4.2e-3, 1000, 0.3));
}

// A margin grows when the last rebuild took more than a tenth of the stepping since the one
// before, by the factor that brings the rebuild to a tenth at the same speed, at least 2, at
// most `step` a rebuild and `most` in all: 0.5 s against 200 steps of 4 ms (0.8 s) asks for
// x6.25; against 1,000 steps (4 s) for x1.25, so x2; against 1,500 steps (6 s) nothing.
TEST(DistributedFluid, MarginsWidenWhenRebuildsAreDear) {
  EXPECT_DOUBLE_EQ(widened_margin(1.0, 16.0, 0.5, 0.8, 16.0), 6.25);
  EXPECT_DOUBLE_EQ(widened_margin(1.0, 16.0, 0.5, 0.8, 2.0), 2.0);
  EXPECT_DOUBLE_EQ(widened_margin(1.0, 16.0, 0.5, 4.0, 16.0), 2.0);
  EXPECT_DOUBLE_EQ(widened_margin(1.0, 16.0, 0.5, 6.0, 16.0), 1.0);
  EXPECT_DOUBLE_EQ(widened_margin(3.0, 4.0, 0.5, 0.8, 16.0), 4.0);
  EXPECT_DOUBLE_EQ(widened_margin(4.0, 4.0, 0.5, 0.8, 16.0), 4.0);
}

TEST(DistributedFluid, DamBreakEqualsOneRankBitForBit) {
  const FluidSetup f = dam_setup();
  const bool root = rank_of() == 0;
  std::unique_ptr<FluidStage> ref = root ? make_fluid_stage("cpu", f) : nullptr;
  auto dist = distributed_stage(f);
  EXPECT_EQ(dist->size(), f.size());
  EXPECT_EQ(dist->n_fluid(), f.n_fluid);
  StateDiff worst;
  double kinetic = 0, vmax = 0;
  int bad_ids = 0, checks = 0;
  constexpr int kSteps = 300;
  for (int n = 0; n <= kSteps; ++n) {
    if (n > 0) {
      if (ref) step(*ref);
      step(*dist);
    }
    const FluidState b = dist->save_state();
    const FluidStats sb = dist->stats();
    if (!root) continue;
    bad_ids += !each_id_once(b, f.size());
    const FluidState a = ref->save_state();
    const StateDiff d = diff(a, b);
    EXPECT_TRUE(d.same_order) << "step " << n;
    worst.widen(d);
    const FluidStats sa = ref->stats();
    kinetic = std::max(kinetic, std::abs(sa.kinetic - sb.kinetic) / sa.kinetic);
    vmax = std::max(vmax, std::abs(sa.v_max - sb.v_max));
    ++checks;
  }
  if (root) {
    std::printf(
        "[fluid dam break, %d ranks, %ld particles, %d steps] max |dx| = %.3e m, |dv| = %.3e "
        "m/s, |drho| = %.3e, |dp| = %.3e Pa, kinetic %.3e (relative)\n",
        size_of(), static_cast<long>(f.size()), kSteps, worst.x, worst.v, worst.rho, worst.p,
        kinetic);
    EXPECT_EQ(checks, kSteps + 1);
    EXPECT_EQ(bad_ids, 0) << "a particle id missing or present twice after a migration";
    EXPECT_EQ(worst.max(), 0.0);
    EXPECT_EQ(vmax, 0.0);
    EXPECT_LT(kinetic, 1e-13);
    // The fluid moved: the front ran past the column.
    const FluidHost h = ref->download();
    double front = 0;
    for (std::size_t i = 0; i < h.x.size(); ++i)
      if (h.type[i] == kSphFluid) front = std::max(front, h.x[i].x);
    EXPECT_GT(front, 0.21);
  }
}

// On a GPU machine (skipped elsewhere): CUDA stages, one GPU a rank, their refreshes resident
// on the devices and the passes over particles no ghost is near running while the records
// are copied, equal one GPU bit for bit.
TEST(DistributedFluid, GpuRanksEqualOneGpuBitForBit) {
  if (!cuda_available()) GTEST_SKIP() << "no GPU: checked on GPU machines";
  const FluidSetup f = dam_setup();
  const bool root = rank_of() == 0;
  std::unique_ptr<FluidStage> ref = root ? make_fluid_stage("cuda", f) : nullptr;
  auto dist =
      make_fluid_stage("cuda", f, nullptr, make_fluid_exchange(options(50, 0.0), f, Space::Cuda));
  StateDiff worst;
  constexpr int kSteps = 300;
  for (int n = 1; n <= kSteps; ++n) {
    if (ref) step(*ref);
    step(*dist);
    if (n % 50 != 0) continue;
    const FluidState b = dist->save_state();
    if (!root) continue;
    const StateDiff d = diff(ref->save_state(), b);
    EXPECT_TRUE(d.same_order) << "step " << n;
    worst.widen(d);
  }
  if (!root) return;
  std::printf("[fluid dam break on GPUs, %d ranks, %d steps] max |dx| = %.3e m, |drho| = %.3e\n",
              size_of(), kSteps, worst.x, worst.rho);
  EXPECT_EQ(worst.max(), 0.0);
}

TEST(DistributedFluid, MortonAndPeanoPartitionsEqualOneRank) {
  const FluidSetup f = dam_setup();
  for (const char* curve : {"morton", "peano"}) {
    SCOPED_TRACE(curve);
    auto ref = rank_of() == 0 ? make_fluid_stage("cpu", f) : nullptr;
    auto dist = distributed_stage(f, curve, 10);
    for (int n = 0; n < 100; ++n) {
      if (ref) step(*ref);
      step(*dist);
    }
    const FluidState b = dist->save_state();
    if (ref) {
      EXPECT_TRUE(each_id_once(b, f.size()));
      const StateDiff d = diff(ref->save_state(), b);
      EXPECT_TRUE(d.same_order);
      EXPECT_EQ(d.max(), 0.0);
    }
  }
}

TEST(DistributedFluid, RestartFromOneRankStateContinuesExactly) {
  const FluidSetup f = dam_setup();
  // The reference on every rank (its state is what a checkpoint read by every rank gives).
  auto ref = make_fluid_stage("cpu", f);
  for (int n = 0; n < 60; ++n) step(*ref);
  auto dist = distributed_stage(f);
  dist->load_state(ref->save_state());
  for (int n = 0; n < 60; ++n) {
    step(*ref);
    step(*dist);
  }
  const FluidState b = dist->save_state();
  if (rank_of() == 0) {
    const StateDiff d = diff(ref->save_state(), b);
    EXPECT_TRUE(d.same_order);
    EXPECT_EQ(d.max(), 0.0);
  }
}

// The coupled scene (distributed_fixture.hpp, CoupledRun): the Stepper over a DistributedBackend
// with a distributed fluid against one rank's, both partitions cut again every 25 steps.
TEST(DistributedFluid, CoupledDamBreakWithCubeEqualsOneRankBitForBit) {
  const Problem r = load(kCoupledScene);
  const FluidSetup f = coupled_fluid(r);
  ASSERT_GT(f.n_marker, 0);
  const bool root = rank_of() == 0;
  std::unique_ptr<CoupledRun> one = root ? std::make_unique<CoupledRun>(r.model, f) : nullptr;
  CoupledRun many(r.model, f, MPI_COMM_WORLD);
  Backend* ref_be = one ? one->be.get() : nullptr;
  FluidStage* ref_fluid = one ? one->fluid.get() : nullptr;
  Stepper* ref = one ? one->st.get() : nullptr;
  Backend* be = many.be.get();
  FluidStage* fluid = many.fluid.get();
  Stepper& st = *many.st;
  constexpr int kSteps = 400;
  StateDiff worst;
  double dx = 0, dv = 0, force = 0;
  int bad_ids = 0;
  for (int n = 1; n <= kSteps; ++n) {
    if (ref) ref->step();
    st.step();
    if (n % 10 != 0) continue;
    const FluidState b = fluid->save_state();
    const HostFields hb = be->download(false);
    const Vec3 fb = fluid->stats().force_on_bodies;
    if (!root) continue;
    bad_ids += !each_id_once(b, f.size());
    const StateDiff d = diff(ref_fluid->save_state(), b);
    EXPECT_TRUE(d.same_order) << "step " << n;
    worst.widen(d);
    const HostFields ha = ref_be->download(false);
    dx = std::max(dx, max_diff(ha.x, hb.x));
    dv = std::max(dv, max_diff(ha.v, hb.v));
    force = std::max(force, norm(ref_fluid->stats().force_on_bodies - fb));
  }
  const std::int64_t rebalances = many.dist->rebalances();
  if (root) {
    std::printf(
        "[coupled dam break, %d ranks, %ld particles (%ld markers), %d steps] fluid max |dx| = "
        "%.3e m, |dv| = %.3e m/s, |dp| = %.3e Pa; cube max |dx| = %.3e m, |dv| = %.3e m/s; "
        "force on the cube %.3e N\n",
        size_of(), static_cast<long>(f.size()), static_cast<long>(f.n_marker), kSteps, worst.x,
        worst.v, worst.p, dx, dv, force);
    EXPECT_EQ(bad_ids, 0) << "a particle id missing or present twice after a migration";
    EXPECT_EQ(worst.max(), 0.0);
    EXPECT_EQ(dx, 0.0);
    EXPECT_EQ(dv, 0.0);
    EXPECT_EQ(force, 0.0);
    // The water reached the cube and moved it.
    const HostFields h = ref_be->download(false);
    double moved = 0;
    for (std::int64_t i = 0; i < r.model.n_vertices(); ++i)
      moved = std::max(moved, std::abs(h.x[i].x - r.model.x[i].x));
    std::printf("[coupled dam break] the cube's largest x displacement %.3e m, %ld rebalances\n",
                moved, static_cast<long>(rebalances));
    EXPECT_GT(moved, 1e-3);
    if (size_of() > 1) EXPECT_GT(rebalances, 0);
  }
}

// The traffic of one layout: each rank's contiguous share of the dam break distributed (the
// particles migrate, the ghosts are filled with every travelling field: x, v, rho, m, type,
// gid, key), then kRefreshes steps' refreshes as the stage does them (records of x, v; then
// of rho, p, m twice). The counts come from what the layout holds: a rank's ghosts, its owned
// particles from other ranks' shares.
TEST(DistributedFluid, TrafficIsWhatThePlansSend) {
  const FluidSetup f = dam_setup();
  const int me = rank_of(), np = size_of();
  auto ex = make_fluid_exchange(options(50, 0.0), f);
  FluidParticles p = share_of(f);
  const std::vector<std::uint64_t> share(p.gid.begin(), p.gid.end());
  PhaseTimers parts;
  const std::int64_t nown = ex->distribute(p, parts);
  for (const char* k :
       {"sph.rebuild.owners", "sph.rebuild.migrate", "sph.rebuild.ghosts", "sph.rebuild.halo"})
    EXPECT_TRUE(parts.seconds().contains(k)) << k;  // the rebuild's parts are timed
  std::int64_t count[2] = {static_cast<std::int64_t>(p.size()) - nown, 0};  // ghosts, arrived
  for (std::int64_t i = 0; i < nown; ++i)
    count[1] += std::find(share.begin(), share.end(), p.gid[i]) == share.end();
  MPI_Allreduce(MPI_IN_PLACE, count, 2, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  constexpr int kRefreshes = 5;
  for (int k = 0; k < kRefreshes; ++k)
    for (std::size_t record : {2 * sizeof(Vec3), 3 * sizeof(double), 3 * sizeof(double)}) {
      ex->send_buffer(record);  // the bytes depend on the record size only
      ex->begin_refresh();
      ex->finish_refresh();
    }
  const FluidTraffic t = ex->traffic();
  constexpr std::int64_t kRecord = 2 * sizeof(Vec3) + 2 * sizeof(double) + sizeof(std::uint8_t) +
                                   2 * sizeof(std::uint64_t);  // 81: the fields that travel
  constexpr std::int64_t kStep = 2 * sizeof(Vec3) + 2 * 3 * sizeof(double);  // 96
  const std::int64_t want_halo = count[0] * (kRecord + kRefreshes * kStep);
  EXPECT_EQ(t.evaluations, 1);
  EXPECT_EQ(t.rebuilds, 1);
  EXPECT_EQ(t.halo_bytes, want_halo);
  EXPECT_EQ(t.migrated_bytes, count[1] * kRecord);
  ParallelRecord r;
  r.set_fluid(t);
  EXPECT_EQ(r.fluid_halo_bytes_per_step, static_cast<double>(want_halo));
  EXPECT_EQ(r.fluid_migrated_bytes, t.migrated_bytes + t.band_bytes);
  if (np == 1) {
    EXPECT_EQ(t.halo_bytes, 0);
    EXPECT_EQ(t.migrated_bytes + t.band_bytes, 0);
  } else {
    EXPECT_GT(count[0], 0);
    EXPECT_GT(count[1], 0);
    EXPECT_GT(t.band_bytes, 0);  // (cell key, rank) pairs, each sent to the other ranks
    EXPECT_EQ(t.band_bytes % (16 * (np - 1)), 0);
  }
  if (me == 0)
    std::printf(
        "[fluid traffic, %d ranks] %ld ghosts, %ld particles migrated: halo %ld B (%ld x (%ld + "
        "%d x %ld)), migration %ld B, band cells %ld B\n",
        np, static_cast<long>(count[0]), static_cast<long>(count[1]),
        static_cast<long>(t.halo_bytes), static_cast<long>(count[0]), static_cast<long>(kRecord),
        kRefreshes, static_cast<long>(kStep), static_cast<long>(t.migrated_bytes),
        static_cast<long>(t.band_bytes));
}

// The first layout, built in the stage's constructor, is set-up (sph.setup, reported in the
// parallel record's setup_s), not a step's upkeep; the steps' upkeep is sph.halo / sph.rebuild.
TEST(DistributedFluid, FirstLayoutIsSetUpNotAStep) {
  const FluidSetup f = dam_setup();
  auto s = distributed_stage(f);
  const auto first = s->stage_seconds();
  ASSERT_TRUE(first.contains("sph.setup"));
  EXPECT_GT(first.at("sph.setup"), 0.0);
  EXPECT_EQ(first.size(), 1u);
  step(*s);
  const auto after = s->stage_seconds();
  EXPECT_EQ(after.at("sph.setup"), first.at("sph.setup"));
  EXPECT_TRUE(after.contains("sph.halo"));
}

// The ghost search splits a rank's particles into a block per thread (each with its own
// table of band cells): the layout (owned particles, then ghosts, in order) is the same for
// any thread count. A finer dam (~50,000 particles) so that every rank's share is split.
TEST(DistributedFluid, LayoutDoesNotDependOnTheThreadCount) {
  Scene s = parse_scene(kDamScene, "dam.yaml");
  s.fluid.spacing = 0.005;
  const FluidSetup f = build_fluid(s.fluid, s.gravity);
  ASSERT_GE(f.size() / size_of(), 2 * kMinParallel);
  const int threads = omp_get_max_threads();
  auto layout = [&](int nt) {
    omp_set_num_threads(nt);
    auto ex = make_fluid_exchange(options(50, 0.0), f);
    FluidParticles p = share_of(f);
    PhaseTimers parts;
    const std::int64_t nown = ex->distribute(p, parts);
    omp_set_num_threads(threads);
    return std::pair{nown, p.gid};
  };
  const auto one = layout(1), four = layout(4);
  EXPECT_EQ(one.first, four.first);
  EXPECT_EQ(one.second, four.second);
  if (size_of() > 1) EXPECT_GT(one.second.size(), static_cast<std::size_t>(one.first));
}

// A rebuild on the standing cut (the skin rule's) given the particles' slots of the last
// layout skips the owner search for those whose band cell was interior then: the particles it
// owns afterwards are those of the full search. Every particle moved 0.6 skin (past the rule's
// half skin, less than a band cell), in one of six directions, so some cross the cut.
TEST(DistributedFluid, StandingCutRebuildOwnsWhatTheFullSearchOwns) {
  const FluidSetup f = dam_setup();
  auto known = make_fluid_exchange(options(50, 0.0), f),
       full = make_fluid_exchange(options(50, 0.0), f);
  FluidParticles p = share_of(f), q = share_of(f);
  PhaseTimers parts;
  const std::int64_t n0 = known->distribute(p, parts);
  ASSERT_EQ(full->distribute(q, parts), n0);
  ASSERT_EQ(p.gid, q.gid);
  for (auto* v : {&p.x, &p.v}) v->resize(n0);  // the owned particles, as a stage hands them
  for (auto* v : {&p.rho, &p.m}) v->resize(n0);
  for (auto* v : {&p.gid, &p.key}) v->resize(n0);
  p.type.resize(n0);
  const double d = 0.6 * known->skin();
  for (std::int64_t i = 0; i < n0; ++i) {
    Vec3 step{};
    step[static_cast<int>(p.gid[i] % 3)] = p.gid[i] % 2 ? d : -d;
    p.x[i] += step;
  }
  FluidParticles moved = p;
  p.slot.resize(n0);
  std::iota(p.slot.begin(), p.slot.end(), std::int64_t{0});
  const double reached = d / (0.5 * known->skin());  // a border particle's reach: skin / 2
  ASSERT_FALSE(known->keep(reached, 0.0));
  ASSERT_FALSE(full->keep(reached, 0.0));
  const std::int64_t n1 = known->distribute(p, parts);
  EXPECT_EQ(full->distribute(moved, parts), n1);
  EXPECT_EQ(std::vector<std::uint64_t>(p.gid.begin(), p.gid.begin() + n1),
            std::vector<std::uint64_t>(moved.gid.begin(), moved.gid.begin() + n1));
  EXPECT_TRUE(p.slot.empty());  // slots do not travel
  std::int64_t changed = 0;     // particles that changed owner, over the ranks
  for (std::int64_t i = 0; i < n1; ++i)
    changed += std::find(q.gid.begin(), q.gid.begin() + n0, p.gid[i]) == q.gid.begin() + n0;
  MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (size_of() > 1) EXPECT_GT(changed, 0);
}

// While no particle has moved more than its reach, every particle of another rank within the
// kernel support of an owned one is held by this rank, and none comes that near an owned one
// whose depth is not 0 (the stage's passes over those run while ghost values travel). Each
// owned particle moves its whole reach towards the other ranks' particles (their centroid),
// and the pairs are checked against all of them. Deep particles may move more than the
// border's skin / 2.
TEST(DistributedFluid, ParticlesWithinTheirReachKeepEveryNeighbourHeld) {
  const FluidSetup f = dam_setup();
  const int me = rank_of(), np = size_of();
  auto ex = make_fluid_exchange(options(1000, 0.1), f);
  FluidParticles p = share_of(f);
  PhaseTimers parts;
  const std::int64_t nown = ex->distribute(p, parts);
  const std::vector<double>& reach = ex->reach();
  const std::vector<std::uint8_t>& depth = ex->depth();
  ASSERT_EQ(static_cast<std::int64_t>(reach.size()), nown);
  ASSERT_EQ(static_cast<std::int64_t>(depth.size()), nown);
  long sent_deep = 0;  // ghosts elsewhere of slots whose depth is not 0
  for (std::int64_t s : ex->send_slots()) sent_deep += depth.at(s) != 0;
  // Every rank's owned particles (position, id, rank) before and after the move.
  struct Item {
    Vec3 x;
    std::uint64_t gid;
    int rank;
  };
  auto all_of = [&](const std::vector<Vec3>& x) {
    std::vector<Item> mine;
    for (std::int64_t i = 0; i < nown; ++i) mine.push_back({x[i], p.gid[i], me});
    return allgatherv(MPI_COMM_WORLD, mine);
  };
  const std::vector<Item> before = all_of(p.x);
  Vec3 centre{};
  double others = 0;
  for (const Item& it : before)
    if (it.rank != me) centre += it.x, ++others;
  std::vector<Vec3> x(p.x.begin(), p.x.begin() + nown);
  double most = 0;
  for (std::int64_t i = 0; i < nown; ++i) {
    most = std::max(most, reach[i]);
    if (others == 0) continue;
    const Vec3 d = centre / others - x[i];
    x[i] += (0.999 * reach[i] / norm(d)) * d;
  }
  const std::vector<Item> after = all_of(x);
  const std::set<std::uint64_t> held(p.gid.begin(), p.gid.end());
  const double support = f.params.kernel.support();
  long count[5] = {0, 0, sent_deep, 0, 0};  // missing, near a deep one, sent_deep, deep, border
  for (std::int64_t i = 0; i < nown; ++i) {
    ++count[depth[i] == 0 ? 4 : 3];
    for (const Item& it : after) {
      const bool near = it.rank != me && norm(x[i] - it.x) < support;
      count[0] += near && !held.count(it.gid);
      count[1] += near && depth[i] != 0;
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, count, 5, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &most, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (me == 0)
    std::printf(
        "[fluid reach, %d ranks] largest reach %.4f m (skin / 2 = %.4f m), %ld pairs within "
        "the support not held; %ld particles of depth 0, %ld deeper, %ld pairs within the "
        "support of a deeper one\n",
        np, most, ex->skin() / 2, count[0], count[4], count[3], count[1]);
  EXPECT_EQ(count[0], 0);
  EXPECT_EQ(count[1], 0);
  EXPECT_EQ(count[2], 0);
  EXPECT_GT(count[3], 0);  // most particles read no ghost
  if (np > 1) EXPECT_GT(count[4], 0);
  EXPECT_GT(most, ex->skin() / 2);  // some particles lie deep inside their rank's piece
}

// The stage's traffic over a run: one evaluation per compute() (the constructor's and one
// per step), rebuilds by the skin rule and the cuts, and on one rank nothing sent.
TEST(DistributedFluid, StageTrafficPerEvaluation) {
  const FluidSetup f = dam_setup();
  auto ex = make_fluid_exchange(options(50, 0.0), f);
  FluidExchange* x = ex.get();
  auto dist = make_fluid_stage("cpu", f, nullptr, std::move(ex));
  constexpr int kSteps = 120;
  for (int n = 0; n < kSteps; ++n) step(*dist);
  const FluidTraffic t = x->traffic();
  ParallelRecord r;
  r.set_fluid(t);
  EXPECT_EQ(t.evaluations, kSteps + 1);
  EXPECT_GE(t.rebuilds, 1);  // the first layout, then the skin rule and the cuts
  // Threshold 0: a new cut at each measurement (steps 50 and 100) where the costs differ.
  EXPECT_EQ(t.recuts, size_of() > 1 ? 2 : 0);
  EXPECT_EQ(r.fluid_recuts, t.recuts);
  if (size_of() == 1) {
    EXPECT_EQ(r.fluid_halo_bytes_per_step, 0.0);
    EXPECT_EQ(r.fluid_migrated_bytes, 0);
  } else {
    EXPECT_GT(r.fluid_halo_bytes_per_step, 0.0);
    EXPECT_GT(r.fluid_migrated_bytes, 0);
  }
  if (rank_of() == 0)
    std::printf(
        "[fluid stage traffic, %d ranks, %d steps] %ld rebuilds (%ld cuts), halo %.0f B per "
        "evaluation, migrated %ld B\n",
        size_of(), kSteps, static_cast<long>(t.rebuilds), static_cast<long>(t.recuts),
        r.fluid_halo_bytes_per_step, static_cast<long>(r.fluid_migrated_bytes));
}

// A dam break in a slab periodic in z (fluid.periodic_z, walls in x and y only, gravity along
// -y), the fluid given z velocities up to 1 m/s so that particles cross the seam: `layers`
// particle layers across the period.
FluidSetup periodic_setup(int layers) {
  const double z = 0.01 * layers;
  const std::string zs = std::to_string(z);
  const Scene s = parse_scene(R"(
run: {end_time: 0.1, dt: 2.0e-4}
gravity: [0, -9.81, 0]
fluid:
  spacing: 0.01
  blocks: [{min: [0, 0, 0], max: [0.1, 0.12, )" +
                                  zs + R"(]}]
  periodic_z: [0.0, )" + zs + R"(]
  walls:
    - {min: [-0.02, -0.02, 0.0], max: [0.0, 0.15, )" +
                                  zs + R"(]}
    - {min: [0.0, -0.02, 0.0], max: [0.25, 0.0, )" +
                                  zs + R"(]}
    - {min: [0.25, -0.02, 0.0], max: [0.27, 0.15, )" +
                                  zs + R"(]}
)",
                              "periodic.yaml");
  FluidSetup f = build_fluid(s.fluid, s.gravity);
  for (std::int64_t i = 0; i < f.size(); ++i)
    if (f.type[i] == kSphFluid) f.v[i].z = (static_cast<double>(f.gid[i] % 7) - 3.0) / 3.0;
  return f;
}

TEST(DistributedFluid, PeriodicSlabEqualsOneRankBitForBit) {
  // 3 layers: the period (0.03 m) is below the band cell (0.016 m) x 2, one band cell across
  // it; 10 layers: six band cells, a seam between ranks' pieces.
  for (int layers : {3, 10}) {
    SCOPED_TRACE(std::to_string(layers) + " layers");
    const FluidSetup f = periodic_setup(layers);
    ASSERT_GT(f.period_z, 0.0);
    const bool root = rank_of() == 0;
    auto ref = root ? make_fluid_stage("cpu", f) : nullptr;
    auto ex = make_fluid_exchange(options(25, 0.0), f);
    FluidExchange* x = ex.get();
    auto dist = make_fluid_stage("cpu", f, nullptr, std::move(ex));
    constexpr int kSteps = 100;
    StateDiff worst;
    int bad_ids = 0, outside = 0;
    for (int n = 1; n <= kSteps; ++n) {
      if (ref) step(*ref);
      step(*dist);
      if (n % 20 != 0) continue;
      const FluidState b = dist->save_state();
      if (!root) continue;
      bad_ids += !each_id_once(b, f.size());
      for (const Vec3& p : b.x) outside += p.z < f.z0 || p.z >= f.z0 + f.period_z;
      const StateDiff d = diff(ref->save_state(), b);
      EXPECT_TRUE(d.same_order) << "step " << n;
      worst.widen(d);
    }
    const FluidTraffic t = x->traffic();
    if (root) {
      std::printf(
          "[periodic slab, %d layers, %d ranks, %ld particles, %d steps] max |dx| = %.3e m, "
          "|dv| = %.3e m/s, |drho| = %.3e, |dp| = %.3e Pa; %ld layout rebuilds\n",
          layers, size_of(), static_cast<long>(f.size()), kSteps, worst.x, worst.v, worst.rho,
          worst.p, static_cast<long>(t.rebuilds));
      EXPECT_EQ(bad_ids, 0);
      EXPECT_EQ(outside, 0) << "a particle outside the period";
      EXPECT_EQ(worst.max(), 0.0);
    }
  }
}

// The partition weighs the particles' measured costs: the dam break's particles with x below
// 0.1 m cost 20, the others 1. Cut by those costs, the ranks' owned costs are even to 0.1 (the
// balancer's 5 % plus its tree's largest cell) and their particle counts are not; cut without
// costs (the defaults by type), the same costs are not even.
TEST(DistributedFluid, PartitionWeighsTheMeasuredCosts) {
  const FluidSetup f = dam_setup();
  const int me = rank_of(), np = size_of();
  auto cost_of = [](const Vec3& x) { return x.x < 0.1 ? 20.0 : 1.0; };
  // {max / mean - 1 of the owned cost, of the owned count} over the ranks.
  auto spread = [&](bool weighted) {
    auto ex = make_fluid_exchange(options(50, 0.0), f);
    FluidParticles p = share_of(f);
    if (weighted)
      for (const Vec3& x : p.x) p.cost.push_back(cost_of(x));
    PhaseTimers parts;
    const std::int64_t nown = ex->distribute(p, parts);
    EXPECT_TRUE(p.cost.empty());  // costs do not travel
    double mine[2] = {0, static_cast<double>(nown)};
    for (std::int64_t i = 0; i < nown; ++i) mine[0] += cost_of(p.x[i]);
    double most[2] = {mine[0], mine[1]}, sum[2] = {mine[0], mine[1]};
    MPI_Allreduce(MPI_IN_PLACE, most, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, sum, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    return std::array<double, 2>{most[0] / (sum[0] / np) - 1, most[1] / (sum[1] / np) - 1};
  };
  const auto w = spread(true), c = spread(false);
  if (me == 0)
    std::printf(
        "[fluid partition, %d ranks] by cost: cost spread %.3f, count spread %.3f; by count: cost "
        "spread %.3f, count spread %.3f\n",
        np, w[0], w[1], c[0], c[1]);
  EXPECT_LE(w[0], 0.1);
  if (np > 1) {
    EXPECT_GT(w[1], 0.1);          // the cheap part's ranks own more particles
    EXPECT_GT(c[0], w[0] + 0.05);  // a cut without the costs leaves them less even
  }
}
