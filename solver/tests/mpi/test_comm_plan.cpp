// Migration and halo plans under mpirun (STYLE.md items 6 and 9): after a migration every
// global id is present exactly once and carries its payload (payload = f(id)); halo copies
// equal the owner's values and are exactly the items within one cell of the rank's cells
// (brute force over all items); scatter-add sums every copy's contribution once; begin and
// finish with interleaved work and two plans in flight. Run on 1, 2 and 4 ranks.
//
// Every check that precedes a collective call is non-fatal (EXPECT), so a failing rank
// never leaves the others waiting.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>

#include "core/memory.hpp"
#include "parallel/cell_tree.hpp"
#include "parallel/comm_plan.hpp"
#include "parallel/partition.hpp"

using namespace qdemsph;

namespace {

int rank_of(MPI_Comm c = MPI_COMM_WORLD) {
  int r;
  MPI_Comm_rank(c, &r);
  return r;
}
int size_of(MPI_Comm c = MPI_COMM_WORLD) {
  int s;
  MPI_Comm_size(c, &s);
  return s;
}

std::int64_t n_initial(int r) { return 1500 + 400 * r; }
std::uint64_t make_gid(int r, std::int64_t i) {
  return (std::uint64_t(r) << 32) | std::uint64_t(i);
}
double payload(std::uint64_t gid) { return 0.25 * static_cast<double>(gid) + 1.0; }

template <class T>
std::vector<T> allgatherv(const std::vector<T>& mine, MPI_Datatype type) {
  const int p = size_of();
  int n = static_cast<int>(mine.size());
  std::vector<int> counts(p), displs(p + 1, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (int r = 0; r < p; ++r) displs[r + 1] = displs[r] + counts[r];
  std::vector<T> all(displs[p]);
  MPI_Allgatherv(mine.data(), n, type, all.data(), counts.data(), displs.data(), type,
                 MPI_COMM_WORLD);
  return all;
}

// Items of one rank: positions (SoA), ids, payload. Initially scattered at random over the
// ranks, with a crowded blob, so that migration moves most of them.
struct Items {
  std::vector<double> x, y, z, pay;
  std::vector<std::uint64_t> gid;
  std::int64_t size() const { return static_cast<std::int64_t>(gid.size()); }
};

Items initial_items() {
  const int me = rank_of();
  std::mt19937_64 rng(1234 + me);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 0.05);
  Items it;
  for (std::int64_t i = 0; i < n_initial(me); ++i) {
    const bool blob = i % 3 == 0;
    it.x.push_back(blob ? std::clamp(0.3 + N(rng), 0.0, 0.999) : U(rng));
    it.y.push_back(blob ? std::clamp(0.7 + N(rng), 0.0, 0.999) : U(rng));
    it.z.push_back(blob ? std::clamp(0.5 + N(rng), 0.0, 0.999) : U(rng));
    it.gid.push_back(make_gid(me, i));
    it.pay.push_back(payload(it.gid.back()));
  }
  return it;
}

// The decomposition every rank computes from the allgathered keys: a refined tree on the
// curve, cut by cost (one unit per item), as splitters.
struct Decomp {
  SfcGrid grid;
  std::vector<std::uint64_t> splitters;
  int owner(Vec3 p) const { return owner_of_key(splitters, grid.key(p)); }
};

Decomp decompose(const Items& it, Curve curve, int order) {
  Decomp d;
  d.grid = SfcGrid{curve, order, {0, 0, 0}, 1.0};
  d.grid.h = 1.0 / d.grid.side();
  std::vector<std::uint64_t> keys;
  for (std::int64_t i = 0; i < it.size(); ++i)
    keys.push_back(d.grid.key({it.x[i], it.y[i], it.z[i]}));
  const std::vector<std::uint64_t> all = allgatherv(keys, MPI_UINT64_T);
  const std::vector<double> cost(all.size(), 1.0);
  const int p = size_of();
  const auto leaves = refine_cells(curve, order, all, cost, double(all.size()) / (20.0 * p));
  std::vector<std::uint64_t> lk;
  std::vector<double> lc;
  for (const TreeCell& t : leaves) {
    lk.push_back(t.key);
    lc.push_back(t.cost);
  }
  const std::vector<int> owner = partition_cells(lk, lc, p);
  d.splitters = partition_splitters(lk, owner, p);
  return d;
}

Items migrate(const Items& it, const Decomp& d, std::int64_t* moved = nullptr) {
  std::vector<int> dest(it.size());
  for (std::int64_t i = 0; i < it.size(); ++i) dest[i] = d.owner({it.x[i], it.y[i], it.z[i]});
  MigratePlan plan(MPI_COMM_WORLD, dest, it.gid);
  Items out;
  out.gid = plan.new_gids();
  for (auto* v : {&out.x, &out.y, &out.z, &out.pay}) v->assign(plan.n_new(), -1.0);
  Items src = it;
  const CommField s[4] = {comm_field(src.x), comm_field(src.y), comm_field(src.z),
                          comm_field(src.pay)};
  const CommField t[4] = {comm_field(out.x), comm_field(out.y), comm_field(out.z),
                          comm_field(out.pay)};
  plan.begin(s);
  plan.finish(t);
  if (moved) *moved = plan.engine().last_bytes();
  return out;
}

// Ranks owning a cell within one cell of p's cell (the halo band of width L_cell).
std::vector<int> band_ranks(const Decomp& d, Vec3 p) {
  std::vector<int> r;
  const double h = d.grid.h;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c) {
        const Vec3 q{p.x + a * h, p.y + b * h, p.z + c * h};
        if (q.x < 0 || q.y < 0 || q.z < 0 || q.x >= 1 || q.y >= 1 || q.z >= 1) continue;
        r.push_back(d.owner(q));
      }
  std::sort(r.begin(), r.end());
  r.erase(std::unique(r.begin(), r.end()), r.end());
  return r;
}

// Checks after a migration, on every rank: ids exactly once globally, payloads and owners.
void check_migrated(const Items& it, const Decomp& d) {
  const int me = rank_of(), p = size_of();
  std::int64_t bad_owner = 0, bad_payload = 0;
  for (std::int64_t i = 0; i < it.size(); ++i) {
    bad_owner += d.owner({it.x[i], it.y[i], it.z[i]}) != me;
    bad_payload += it.pay[i] != payload(it.gid[i]);
  }
  EXPECT_EQ(bad_owner, 0) << "rank " << me;
  EXPECT_EQ(bad_payload, 0) << "rank " << me;
  std::vector<std::uint64_t> all = allgatherv(it.gid, MPI_UINT64_T);
  std::sort(all.begin(), all.end());
  std::vector<std::uint64_t> want;
  for (int r = 0; r < p; ++r)
    for (std::int64_t i = 0; i < n_initial(r); ++i) want.push_back(make_gid(r, i));
  EXPECT_EQ(all.size(), want.size());
  EXPECT_TRUE(all == want) << "some global id is missing or repeated";
}

}  // namespace

TEST(MigratePlan, EveryIdOnceWithItsPayload) {
  Items it = initial_items();
  // Three decompositions in a row: Hilbert, Peano, Morton (a rebalancing each time).
  const std::pair<Curve, int> curves[] = {
      {Curve::Hilbert, 4}, {Curve::Peano, 3}, {Curve::Morton, 5}};
  for (auto [curve, order] : curves) {
    const Decomp d = decompose(it, curve, order);
    std::int64_t bytes = 0;
    it = migrate(it, d, &bytes);
    SCOPED_TRACE(int(curve));
    check_migrated(it, d);
    // A second migration to the same decomposition moves nothing to other ranks.
    it = migrate(it, d, &bytes);
    EXPECT_EQ(bytes, 0);
    check_migrated(it, d);
  }
}

TEST(MigratePlan, ReplannedWithIdsAsAField) {
  // One plan without ids, planned again for each decomposition (and once with every item to
  // the last rank), moving with move(): the ids travel as a field; each result is a new plan's.
  Items it = initial_items();
  MigratePlan plan(MPI_COMM_WORLD, std::span<const int>{});
  const int p = size_of();
  const std::pair<Curve, int> curves[] = {
      {Curve::Hilbert, 4}, {Curve::Morton, 5}, {Curve::Hilbert, 0}, {Curve::Peano, 3}};
  for (auto [curve, order] : curves) {
    const Decomp d = order > 0 ? decompose(it, curve, order) : Decomp{};
    std::vector<int> dest(it.size(), p - 1);  // order 0: everything to the last rank
    if (order > 0)
      for (std::int64_t i = 0; i < it.size(); ++i) dest[i] = d.owner({it.x[i], it.y[i], it.z[i]});
    plan.replan(dest);
    EXPECT_TRUE(plan.new_gids().empty());
    Items out;
    for (auto* v : {&out.x, &out.y, &out.z, &out.pay}) v->assign(plan.n_new(), -1.0);
    out.gid.assign(plan.n_new(), 0);
    const CommField s[5] = {comm_field(it.x), comm_field(it.y), comm_field(it.z),
                            comm_field(it.pay), comm_field(it.gid)};
    const CommField t[5] = {comm_field(out.x), comm_field(out.y), comm_field(out.z),
                            comm_field(out.pay), comm_field(out.gid)};
    plan.move(s, t);  // those that stay copied directly
    it = out;
    SCOPED_TRACE(order);
    if (order > 0) check_migrated(it, d);
  }
}

TEST(MigratePlan, SendListsKeepItemOrderOnTheThreads) {
  // Enough items that the send lists are built in a block per thread: each rank's list is
  // its items in increasing order, as a serial counting sort gives; a destination outside
  // the ranks is an error that names it (before any message, on every rank alike).
  const int p = size_of();
  const std::int64_t n = 200000;
  std::vector<int> dest(n);
  std::mt19937 rng(7);
  for (auto& d : dest) d = static_cast<int>(rng() % static_cast<unsigned>(p));
  MigratePlan plan(MPI_COMM_WORLD, std::span<const int>{});
  plan.replan(dest);
  std::vector<std::int64_t> want;
  for (int r = 0; r < p; ++r)
    for (std::int64_t i = 0; i < n; ++i)
      if (dest[i] == r) want.push_back(i);
  EXPECT_EQ(plan.engine().send_index(), want);
  dest[n / 2] = p;
  try {
    plan.replan(dest);
    ADD_FAILURE() << "a destination outside the ranks was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("destination rank " + std::to_string(p)),
              std::string::npos)
        << e.what();
  }
}

TEST(MigratePlan, BlockingApplyAndEmptyRanks) {
  // Everything to the last rank, then back to rank 0 with apply().
  Items it = initial_items();
  const int p = size_of(), me = rank_of();
  std::vector<int> dest(it.size(), p - 1);
  MigratePlan a(MPI_COMM_WORLD, dest, it.gid);
  a.apply(it.pay);
  EXPECT_EQ(static_cast<std::int64_t>(it.pay.size()), a.n_new());
  std::int64_t total = 0;
  for (int r = 0; r < p; ++r) total += n_initial(r);
  EXPECT_EQ(a.n_new(), me == p - 1 ? total : 0);
  std::int64_t bad = 0;
  for (std::int64_t i = 0; i < a.n_new(); ++i) bad += it.pay[i] != payload(a.new_gids()[i]);
  EXPECT_EQ(bad, 0);
  std::vector<int> back(a.n_new(), 0);
  MigratePlan b(MPI_COMM_WORLD, back, a.new_gids());
  b.apply(it.pay);
  EXPECT_EQ(b.n_new(), me == 0 ? total : 0);
  bad = 0;
  for (std::int64_t i = 0; i < b.n_new(); ++i) bad += it.pay[i] != payload(b.new_gids()[i]);
  EXPECT_EQ(bad, 0);
}

namespace {

struct HaloSetup {
  Items it;
  Decomp d;
  std::vector<std::int64_t> off;
  std::vector<int> ranks;
  std::unique_ptr<HaloPlan> plan;
};

HaloSetup halo_setup() {
  HaloSetup s;
  Items it0 = initial_items();
  s.d = decompose(it0, Curve::Hilbert, 4);
  s.it = migrate(it0, s.d);
  s.off.push_back(0);
  for (std::int64_t i = 0; i < s.it.size(); ++i) {
    for (int r : band_ranks(s.d, {s.it.x[i], s.it.y[i], s.it.z[i]})) s.ranks.push_back(r);
    s.off.push_back(static_cast<std::int64_t>(s.ranks.size()));
  }
  s.plan = std::make_unique<HaloPlan>(MPI_COMM_WORLD, s.it.size(), s.off, s.ranks, s.it.gid);
  return s;
}

// Other lists for the same items: the band's ranks and, for every third item, the next rank
// too (more ghosts, so a replan's buffers must grow).
std::pair<std::vector<std::int64_t>, std::vector<int>> wider_lists(const HaloSetup& s) {
  const int me = rank_of(), np = size_of();
  std::vector<std::int64_t> off{0};
  std::vector<int> ranks;
  for (std::int64_t i = 0; i < s.it.size(); ++i) {
    ranks.insert(ranks.end(), s.ranks.begin() + s.off[i], s.ranks.begin() + s.off[i + 1]);
    if (s.it.gid[i] % 3 == 0) ranks.push_back((me + 1) % np);
    off.push_back(static_cast<std::int64_t>(ranks.size()));
  }
  return {off, ranks};
}

}  // namespace

// A plan made again on its engine (a layout rebuild) equals a new plan of the same lists.
TEST(HaloPlan, ReplanEqualsANewPlan) {
  HaloSetup s = halo_setup();
  const auto [off, ranks] = wider_lists(s);
  for (int round = 0; round < 2; ++round) {  // wider lists, then the first again
    const auto& o = round == 0 ? off : s.off;
    const auto& r = round == 0 ? ranks : s.ranks;
    s.plan->replan(s.it.size(), o, r, s.it.gid);
    const HaloPlan fresh(MPI_COMM_WORLD, s.it.size(), o, r, s.it.gid);
    EXPECT_EQ(s.plan->n_ghost(), fresh.n_ghost());
    EXPECT_EQ(s.plan->ghost_gids(), fresh.ghost_gids());
    EXPECT_EQ(s.plan->engine().send_index(), fresh.engine().send_index());
    EXPECT_EQ(s.plan->engine().neighbours(), fresh.engine().neighbours());
  }
  if (size_of() > 1) {
    const HaloPlan wide(MPI_COMM_WORLD, s.it.size(), off, ranks, s.it.gid);
    EXPECT_GT(wide.n_ghost(), s.plan->n_ghost());
  }
}

TEST(HaloPlan, GhostsAreTheBandAndEqualOwnerValues) {
  HaloSetup s = halo_setup();
  HaloPlan& h = *s.plan;
  const int me = rank_of();
  const std::int64_t no = h.n_owned(), nt = h.n_total();
  Items& it = s.it;
  for (auto* v : {&it.x, &it.y, &it.z, &it.pay}) v->resize(nt, std::nan(""));
  const CommField f[4] = {comm_field(it.x), comm_field(it.y), comm_field(it.z), comm_field(it.pay)};
  h.gather_begin(f);
  h.gather_finish(f);
  // Brute force: every item owned elsewhere whose band reaches one of this rank's cells.
  const auto gx = allgatherv(std::vector<double>(it.x.begin(), it.x.begin() + no), MPI_DOUBLE);
  const auto gy = allgatherv(std::vector<double>(it.y.begin(), it.y.begin() + no), MPI_DOUBLE);
  const auto gz = allgatherv(std::vector<double>(it.z.begin(), it.z.begin() + no), MPI_DOUBLE);
  const auto gg =
      allgatherv(std::vector<std::uint64_t>(it.gid.begin(), it.gid.end()), MPI_UINT64_T);
  std::set<std::uint64_t> want;
  std::map<std::uint64_t, Vec3> pos;
  for (std::size_t k = 0; k < gg.size(); ++k) {
    const Vec3 p{gx[k], gy[k], gz[k]};
    pos[gg[k]] = p;
    if (s.d.owner(p) == me) continue;
    const auto br = band_ranks(s.d, p);
    if (std::binary_search(br.begin(), br.end(), me)) want.insert(gg[k]);
  }
  const std::set<std::uint64_t> got(h.ghost_gids().begin(), h.ghost_gids().end());
  EXPECT_EQ(got.size(), h.ghost_gids().size()) << "a ghost arrived twice";
  EXPECT_TRUE(got == want) << "rank " << me << ": " << got.size() << " ghosts, want "
                           << want.size();
  std::int64_t bad = 0;
  for (std::int64_t g = 0; g < h.n_ghost(); ++g) {
    const std::uint64_t id = h.ghost_gids()[g];
    const Vec3 p = pos[id];
    bad += it.pay[no + g] != payload(id) || it.x[no + g] != p.x || it.y[no + g] != p.y ||
           it.z[no + g] != p.z;
  }
  EXPECT_EQ(bad, 0) << "rank " << me;
  if (size_of() > 1) {
    EXPECT_GT(h.n_ghost(), 0);
  }
}

TEST(HaloPlan, ScatterAddSumsEveryCopyOnce) {
  HaloSetup s = halo_setup();
  HaloPlan& h = *s.plan;
  const int me = rank_of();
  const std::int64_t no = h.n_owned(), nt = h.n_total();
  // Each ghost contributes (1 + its rank) and (10 + its rank) to a double and an int field.
  std::vector<double> acc(nt, 0.0);
  std::vector<std::int64_t> cnt(nt, 0);
  for (std::int64_t g = no; g < nt; ++g) {
    acc[g] = 1.0 + me;
    cnt[g] = 10 + me;
  }
  const CommField f[2] = {comm_field(acc), comm_field(cnt)};
  h.scatter_add_begin(f);
  h.scatter_add_finish(f);
  std::int64_t bad = 0;
  for (std::int64_t i = 0; i < no; ++i) {
    double want = 0;
    std::int64_t wcnt = 0;
    for (std::int64_t k = s.off[i]; k < s.off[i + 1]; ++k)
      if (s.ranks[k] != me) {
        want += 1.0 + s.ranks[k];
        wcnt += 10 + s.ranks[k];
      }
    bad += acc[i] != want || cnt[i] != wcnt;
  }
  EXPECT_EQ(bad, 0) << "rank " << me;
}

TEST(HaloPlan, BeginFinishWithInterleavedWork) {
  HaloSetup s = halo_setup();
  HaloPlan& h = *s.plan;
  const int me = rank_of();
  const std::int64_t no = h.n_owned(), nt = h.n_total();
  std::vector<double> u(nt, 0.0);
  for (std::int64_t i = 0; i < no; ++i) u[i] = payload(s.it.gid[i]);
  // A second plan in flight at the same time: migrate a copy of the items to rank
  // (r + 1) mod p.
  const int p = size_of();
  std::vector<int> dest(no, (me + 1) % p);
  MigratePlan m(MPI_COMM_WORLD, dest, s.it.gid);
  std::vector<double> moved(m.n_new(), -1);
  const CommField fu = comm_field(u), fs = comm_field(s.it.pay), fm = comm_field(moved);
  std::int64_t bad = 0;
  for (int step = 0; step < 20; ++step) {
    h.gather_begin({&fu, 1});
    if (step == 0) m.begin({&fs, 1});
    EXPECT_THROW(h.gather_begin({&fu, 1}), std::logic_error);  // one exchange per plan
    // Interior work on owned values while messages fly: u_i += 1 for owned items.
    double interior = 0;
    for (std::int64_t i = 0; i < no; ++i) interior += u[i];
    EXPECT_TRUE(std::isfinite(interior));
    if (step == 0) m.finish({&fm, 1});
    h.gather_finish({&fu, 1});
    for (std::int64_t g = 0; g < h.n_ghost(); ++g)
      bad += u[no + g] != payload(h.ghost_gids()[g]) + step;
    for (std::int64_t i = 0; i < no; ++i) u[i] += 1.0;
  }
  EXPECT_EQ(bad, 0) << "rank " << me;
  bad = 0;
  for (std::int64_t i = 0; i < m.n_new(); ++i) bad += moved[i] != payload(m.new_gids()[i]);
  EXPECT_EQ(bad, 0) << "rank " << me;
  EXPECT_THROW(h.gather_finish({&fu, 1}), std::logic_error);  // nothing in flight
  // Records: bytes and seconds per phase accumulate.
  const auto& t = h.engine().seconds();
  EXPECT_TRUE(t.pack >= 0 && t.wait >= 0 && t.unpack >= 0);
  if (p > 1) {
    EXPECT_GT(h.engine().total_bytes(), 0);
  }
}

// The device-resident packed exchange (CUDA IPC between the GPU ranks of a node) delivers the
// records of the host-staged one, exchange after exchange; without a GPU use_device() declines
// and the records stay in host memory. Needs a GPU for the device part (the GPU session runs
// this binary: ci/gpu/pack.sh with PACK_MPI=1).
TEST(HaloPlan, DeviceResidentPackedExchangeEqualsHostStaged) {
  HaloSetup s = halo_setup();
  CommEngine& e = s.plan->engine();
  const int me = rank_of();
  const std::int64_t ns = e.n_send(), nr = e.n_recv();
  auto records = [&](int round) {  // two doubles per send slot
    std::vector<double> r(2 * ns);
    for (std::int64_t k = 0; k < ns; ++k) {
      const std::uint64_t id = s.it.gid[e.send_index()[k]];
      r[2 * k] = payload(id) + round;
      r[2 * k + 1] = -static_cast<double>(id) * (round + 1);
    }
    return r;
  };
  const std::size_t stride = 2 * sizeof(double);
  std::vector<std::vector<double>> staged;
  for (int round = 0; round < 3; ++round) {
    const std::vector<double> r = records(round);
    auto buf = e.packed_send_buffer(stride);
    std::memcpy(buf.data(), r.data(), buf.size());
    e.begin_packed();
    const auto in = e.finish_packed();
    staged.emplace_back(nr * 2);
    std::memcpy(staged.back().data(), in.data(), in.size());
  }
  const bool gpu = cuda_available();
  EXPECT_FALSE(e.use_device(false, stride));
  EXPECT_EQ(e.packed_space(), Space::Host);
  if (!gpu) GTEST_SKIP() << "no GPU: the device-resident exchange is checked on GPU machines";
  const bool on = e.use_device(true, stride);
  EXPECT_EQ(e.packed_space(), on ? Space::Cuda : Space::Host);
  if (!on) GTEST_SKIP() << "use_device declined (QDEMSPH_DEVICE_HALO=0 or ranks on several nodes)";
  std::int64_t bad = 0;
  for (int round = 0; round < 3; ++round) {
    const std::vector<double> r = records(round);
    auto buf = e.packed_send_buffer(stride);
    space_copy(buf.data(), Space::Cuda, r.data(), Space::Host, buf.size());
    e.begin_packed();
    const auto in = e.finish_packed();
    std::vector<double> got(nr * 2);
    space_copy(got.data(), Space::Host, in.data(), Space::Cuda, in.size());
    bad += got != staged[round];
  }
  EXPECT_EQ(bad, 0) << "rank " << me;
  EXPECT_THROW(e.packed_send_buffer(3 * stride), std::logic_error);  // larger than max_stride
  // Planned again (wider lists: the send buffers grow and are mapped again; then the first
  // lists: the mappings stand), the device exchange still equals a host-staged one.
  const auto [off, ranks] = wider_lists(s);
  for (int round = 0; round < 2; ++round) {
    const auto& o = round == 0 ? off : s.off;
    const auto& rk = round == 0 ? ranks : s.ranks;
    s.plan->replan(s.it.size(), o, rk);
    HaloPlan host(MPI_COMM_WORLD, s.it.size(), o, rk);
    ASSERT_EQ(e.packed_space(), Space::Cuda);
    ASSERT_EQ(e.send_index(), host.engine().send_index());
    std::vector<double> r(2 * e.n_send());
    for (std::int64_t k = 0; k < e.n_send(); ++k)
      r[2 * k] = payload(s.it.gid[e.send_index()[k]]), r[2 * k + 1] = k + round;
    auto hb = host.engine().packed_send_buffer(stride);
    std::memcpy(hb.data(), r.data(), hb.size());
    host.engine().begin_packed();
    const auto want = host.engine().finish_packed();
    auto buf = e.packed_send_buffer(stride);
    space_copy(buf.data(), Space::Cuda, r.data(), Space::Host, buf.size());
    e.begin_packed();
    const auto in = e.finish_packed();
    ASSERT_EQ(in.size(), want.size());
    std::vector<std::byte> got(in.size());
    space_copy(got.data(), Space::Host, in.data(), Space::Cuda, in.size());
    EXPECT_EQ(std::memcmp(got.data(), want.data(), got.size()), 0) << "rank " << me;
  }
}

namespace {

// Prints only failures on ranks other than 0 (rank 0 keeps the usual output).
class RankFailurePrinter : public ::testing::EmptyTestEventListener {
 public:
  explicit RankFailurePrinter(int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (r.failed())
      std::fprintf(stderr, "[rank %d] %s:%d: Failure\n%s\n", rank_, r.file_name(), r.line_number(),
                   r.summary());
  }

 private:
  int rank_;
};

}  // namespace

// exchange_begin / exchange_finish: each neighbour's records arrive whole, by source rank (this
// rank's own among them), however many there are, none included (one message a neighbour, sized by
// a probe).
TEST(HaloPlan, VariableLengthExchangeBySourceRank) {
  HaloSetup s = halo_setup();
  CommEngine& e = s.plan->engine();
  const int me = rank_of(), np = size_of();
  const auto count = [](int from, int to) { return (from + 2 * to) % 3; };  // 0, 1 or 2
  struct Rec {
    std::int64_t from, to, k;
  };
  std::vector<int> dest = e.neighbours();
  dest.push_back(me);
  std::sort(dest.begin(), dest.end());
  std::vector<Rec> send;
  std::vector<std::int64_t> off(np + 1, 0);
  for (int r = 0; r < np; ++r) {
    if (std::binary_search(dest.begin(), dest.end(), r))
      for (int k = 0; k < count(me, r); ++k) send.push_back({me, r, k});
    off[r + 1] = static_cast<std::int64_t>(send.size());
  }
  for (int round = 0; round < 2; ++round) {  // twice: no message of the first left over
    e.exchange_begin(std::as_bytes(std::span(send)), off, sizeof(Rec));
    const std::vector<std::byte> in = e.exchange_finish();
    std::vector<Rec> want;
    for (const int r : dest)
      for (int k = 0; k < count(r, me); ++k) want.push_back({r, me, k});
    ASSERT_EQ(in.size(), want.size() * sizeof(Rec));
    for (std::size_t j = 0; j < want.size(); ++j) {
      Rec got;
      std::memcpy(&got, in.data() + j * sizeof(Rec), sizeof(Rec));
      EXPECT_EQ(got.from, want[j].from);
      EXPECT_EQ(got.to, want[j].to);
      EXPECT_EQ(got.k, want[j].k);
    }
  }
}

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int me = rank_of();
  if (me != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new RankFailurePrinter(me));
  }
  int rc = RUN_ALL_TESTS();
  int any = 0;
  MPI_Allreduce(&rc, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}
