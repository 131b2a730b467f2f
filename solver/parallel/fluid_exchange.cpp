#include "parallel/fluid_exchange.hpp"

#include <omp.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <utility>

#include "core/exec_host.hpp"
#include "core/select_host.hpp"
#include "neighbor/scan.hpp"
#include "parallel/balance.hpp"
#include "parallel/band_cells.hpp"
#include "parallel/collectives.hpp"
#include "parallel/comm_plan.hpp"
#include "parallel/distributed_backend_mpi.hpp"
#include "parallel/key_index.hpp"
#include "sph/fluid_setup.hpp"

namespace qdemsph {
namespace {

// The deepest box depth_of() tries, in band cells on each side.
constexpr int kMaxDepth = 8;

// An axis-aligned box of positions (every rank's particles at a layout); unbounded by default.
struct Bounds {
  Vec3 lo{-kInf, -kInf, -kInf}, hi{kInf, kInf, kInf};
  bool holds(Vec3 p) const {
    return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
  }
  static constexpr double kInf = std::numeric_limits<double>::infinity();
};

std::vector<CommField> fields_of(FluidParticles& p) {
  return {comm_field(p.x),    comm_field(p.v),   comm_field(p.rho), comm_field(p.m),
          comm_field(p.type), comm_field(p.gid), comm_field(p.key)};
}

using qdemsph::resize_for_overwrite;  // beside the overload for FluidParticles below

// The fields at n items, contents not kept (resize_for_overwrite): room for 1/8 more, so that
// appending the ghosts to the owned items does not reallocate.
void resize_for_overwrite(FluidParticles& p, std::int64_t n) {
  const auto k = static_cast<std::size_t>(n);
  auto each = [&](auto&... v) { (resize_for_overwrite(v, k), ...); };
  each(p.x, p.v, p.rho, p.m, p.type, p.gid, p.key);
}

// dst item to(k) <- src item from(k) of every field, for k in [0, n) (copy_each).
template <class From, class To>
void copy_items(const std::vector<CommField>& src, const std::vector<CommField>& dst,
                std::int64_t n, From from, To to) {
  for (std::size_t j = 0; j < src.size(); ++j) {
    const std::size_t e = src[j].elem;
    copy_each(
        0, n, e, [&](std::int64_t k) { return dst[j].data + to(k) * e; },
        [&](std::int64_t k) { return src[j].data + from(k) * e; });
  }
}

// The fields at n items, the first ones kept.
void resize(FluidParticles& p, std::int64_t n) {
  const auto k = static_cast<std::size_t>(n);
  p.x.resize(k), p.v.resize(k), p.rho.resize(k), p.m.resize(k);
  p.type.resize(k), p.gid.resize(k), p.key.resize(k);
}

class MpiFluidExchange final : public FluidExchange {
 public:
  MpiFluidExchange(MPI_Comm comm, const ParallelOptions& o, const FluidSetup& f, Space space)
      : space_(space),
        curve_(parse_curve(o.curve)),
        every_(o.rebalance_every),
        threshold_(o.rebalance_threshold),
        max_cell_(o.max_cell_cost),
        support_(f.params.kernel.support()),
        z0_(f.z0),
        period_(f.period_z),
        skin_(kFluidSkin * support_),
        band_((support_ + skin_) / 2, z0_, period_) {
    MPI_Comm_dup(comm, &comm_);
    MPI_Comm_rank(comm_, &me_);
    MPI_Comm_size(comm_, &np_);
    migrate_ = std::make_unique<MigratePlan>(comm_, std::span<const int>{});
  }
  ~MpiFluidExchange() override {
    halo_.reset();
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Comm_free(&comm_);
  }

  std::int64_t distribute(FluidParticles& p, PhaseTimers& timers) override {
    if (!after_keep_) ++evaluations_;  // else keep() counted this evaluation
    rebuilt_ = after_keep_;
    after_keep_ = false;
    const double t0 = MPI_Wtime();
    ++rebuilds_;
    const std::int64_t n = static_cast<std::int64_t>(p.size());
    std::optional<PhaseTimers::Scope> part;
    part.emplace(timers, "sph.rebuild.owners");
    // Each particle's new owner: the piece of the curve holding its curve key on the
    // decomposition's grid.
    resize_for_overwrite(dest_, n);
    if (dec_.splitters.empty() || rebalance_) {  // a new cut, which computes the keys anyway
      recuts_ += !dec_.splitters.empty();
      std::span<const double> cost = p.cost;
      if (p.cost.size() != p.size()) {  // not measured yet
        resize_for_overwrite(cost_, n);
        for_each(HostExec{}, n,
                 [&](std::int64_t i) { cost_[i] = p.type[i] == kSphFluid ? 1.0 : kFluidWallCost; });
        cost = cost_;
      }
      dec_ = balance(comm_, p.x, cost, curve_, max_cell_, &curve_key_);
      for_each(HostExec{}, n,
               [&](std::int64_t i) { dest_[i] = owner_of_key(dec_.splitters, curve_key_[i]); });
    } else {
      // On the standing cut, a particle whose band cell was interior at the last layout (its
      // box of depth d, (2 d + 1)^3 band cells, all this rank's piece within the particles'
      // bounds then: depth_of()) that has moved less than d - 1 band cells since (at most
      // reached_ times its reach, keep()) and not out of those bounds is still in this rank's
      // piece and stays, without its key (most particles: rank 0's owners of the 359 k-particle
      // dam break on 2 ranks of one thread, 14.6 -> 3.1 ms a rebuild).
      const bool known = p.slot.size() == p.size() && n == static_cast<std::int64_t>(depth_.size());
      for_each(HostExec{}, n, [&](std::int64_t i) {
        const std::int64_t s = known ? p.slot[i] : -1;
        const bool stays = s >= 0 && depth_[s] > 0 &&
                           reached_ * reach_[s] < (depth_[s] - 1) * depth_band_ &&
                           bounds_.holds(p.x[i]);
        dest_[i] = stays ? me_ : owner_of_key(dec_.splitters, dec_.grid.key(p.x[i]));
      });
    }
    rebalance_ = false;
    reached_ = kUnknown;

    // Owned particles to the owners of their positions, in place (a rank keeps nearly all of
    // them): those that leave are gathered and sent, the holes they leave are filled from the
    // end, and those that arrive are appended (the owned particles' order is free: the stage
    // lays them out by key).
    part.emplace(timers, "sph.rebuild.migrate");
    select_indices(
        HostExec{}, n, [&](std::int64_t i) { return dest_[i] != me_; }, leave_);
    const auto nl = static_cast<std::int64_t>(leave_.size()), nk = n - nl;
    resize_for_overwrite(out_, nl);
    resize_for_overwrite(out_dest_, static_cast<std::size_t>(nl));
    for_each(HostExec{}, nl, [&](std::int64_t k) { out_dest_[k] = dest_[leave_[k]]; });
    copy_items(
        fields_of(p), fields_of(out_), nl, [&](std::int64_t k) { return leave_[k]; },
        [](std::int64_t k) { return k; });
    migrate_->replan(out_dest_);
    resize_for_overwrite(in_, migrate_->n_new());
    migrate_->move(fields_of(out_), fields_of(in_));
    migrated_bytes_ += migrate_->engine().last_bytes();
    // The holes below nk (leave_ is increasing), each filled by a kept particle at or above it.
    const auto nh = std::lower_bound(leave_.begin(), leave_.end(), nk) - leave_.begin();
    select_indices(
        HostExec{}, nl, [&](std::int64_t j) { return dest_[nk + j] == me_; }, fill_);
    copy_items(
        fields_of(p), fields_of(p), nh, [&](std::int64_t j) { return nk + fill_[j]; },
        [&](std::int64_t j) { return leave_[j]; });
    const std::int64_t nown = nk + migrate_->n_new();
    resize(p, nown);
    copy_items(
        fields_of(in_), fields_of(p), nown - nk, [](std::int64_t k) { return k; },
        [&](std::int64_t k) { return nk + k; });

    part.emplace(timers, "sph.rebuild.ghosts");
    find_ghost_ranks(p.x, nown);
    part.emplace(timers, "sph.rebuild.halo");
    std::optional<PhaseTimers::Scope> sub;
    sub.emplace(timers, "sph.rebuild.halo.plan");
    if (halo_) {  // ids go as a field
      halo_->replan(nown, g_.off, g_.ranks);
    } else {
      halo_ = std::make_unique<HaloPlan>(comm_, nown, g_.off, g_.ranks);
      halo_->engine().use_device(space_ == Space::Cuda, 6 * sizeof(double));
    }
    sub.emplace(timers, "sph.rebuild.halo.gather");
    resize(p, halo_->n_total());
    const auto f = fields_of(p);
    halo_->gather_begin(f);
    halo_->gather_finish(f);
    halo_bytes_ += halo_->engine().last_bytes();
    sub.reset();
    part.reset();
    p.cost.clear();
    p.slot.clear();
    // This part of the rebuild, until the stage's part is measured too (time_step).
    rebuild_s_ = std::max(rebuild_s_, MPI_Wtime() - t0);
    return nown;
  }

  bool keep(double reached, double load) override {
    ++steps_;
    ++evaluations_;
    time_step();
    if (rebalance_due(load)) {
      rebalance_ = true;
    } else {
      MPI_Allreduce(MPI_IN_PLACE, &reached, 1, MPI_DOUBLE, MPI_MAX, comm_);
      if (reached <= 1) return true;
      reached_ = reached;
      widen_skin();
    }
    after_keep_ = true;
    return false;
  }
  bool wants_load() const override { return every_ > 0 && (steps_ + 1) % every_ == 0; }
  double skin() const override { return skin_; }
  const std::vector<double>& reach() const override { return reach_; }
  const std::vector<std::uint8_t>& depth() const override { return depth_; }

  const std::vector<std::int64_t>& send_slots() const override {
    return halo_->engine().send_index();
  }
  std::span<std::byte> send_buffer(std::size_t stride) override {
    return halo_->engine().packed_send_buffer(stride);
  }
  Space buffer_space() const override { return halo_->engine().packed_space(); }
  void mark_packed() override { halo_->engine().mark_packed(); }
  void begin_refresh() override { halo_->engine().begin_packed(); }
  std::span<const std::byte> finish_refresh() override {
    const auto in = halo_->engine().finish_packed();
    halo_bytes_ += halo_->engine().last_bytes();
    return in;
  }

  void sum(std::span<double> v) override {
    allreduce_sum_same(comm_, v.data(), static_cast<int>(v.size()));
  }
  void max(std::span<double> v) override {
    MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_MAX, comm_);
  }
  std::vector<Vec3> gather(const std::vector<Vec3>& v) override { return gatherv(comm_, v); }
  std::vector<double> gather(const std::vector<double>& v) override { return gatherv(comm_, v); }
  std::vector<std::uint8_t> gather(const std::vector<std::uint8_t>& v) override {
    return gatherv(comm_, v);
  }
  std::vector<std::uint64_t> gather(const std::vector<std::uint64_t>& v) override {
    return gatherv(comm_, v);
  }
  int rank() const override { return me_; }
  int size() const override { return np_; }
  FluidTraffic traffic() override {
    std::int64_t b[3] = {halo_bytes_, migrated_bytes_, band_bytes_};
    MPI_Allreduce(MPI_IN_PLACE, b, 3, MPI_INT64_T, MPI_SUM, comm_);
    return {evaluations_, rebuilds_, recuts_, b[0], b[1], b[2], skin_};
  }

 private:
  // find_ghost_ranks()'s work arrays (g_), kept so that a rebuild reuses their storage.
  struct GhostBlock {                     // find_ghost_ranks(): one block of particles'
    KeyIndex cells;                       // distinct band cells
    std::vector<std::uint64_t> cell_key;  // per cell: its key
    std::vector<std::uint8_t> depth;      // per cell: depth_of() (0: on the piece's border)
    KeyIndex in_piece;                    // interior(): tree cells tested, and the answers
    std::vector<std::uint8_t> in_piece_value;
    std::vector<std::int64_t> cell_off;  // per cell: a range of cell_ranks
    std::vector<int> cell_ranks;
  };
  struct GhostScratch {
    std::vector<GhostBlock> block;                        // one per thread
    std::vector<std::int64_t> cell_of;                    // per particle: its cell in its block
    std::vector<std::pair<std::uint64_t, int>> occupied;  // other ranks' (cell, rank), sorted
    KeyIndex occupied_cells;                              // its distinct cells
    std::vector<std::int64_t> occupied_off;               // per distinct cell: its range
    std::vector<std::int64_t> off;                        // per particle: a range of ranks
    std::vector<int> ranks;
  };

  std::uint64_t cell_key(Vec3 p) const {
    const BandCell c = band_.cell(p);
    return band_key(c.i[0], c.i[1], c.i[2]);
  }

  // The ranks that get a ghost copy of each of the nown owned particles of o_ (g_.off,
  // g_.ranks: HaloPlan's lists): the band cells of this rank's owned particles are published
  // to all, and a particle goes to every other rank with an owned particle in the 5^3 cells
  // around its own. A cell whose 5^3 cells lie inside this rank's piece (interior) has no
  // other rank's particle around it: only the others, near the piece's border, are published
  // and looked up. The particles are split into as many contiguous blocks as threads, each
  // with its own table of the distinct cells of its particles (a cell at a block's edge is in
  // two tables, and tested twice), so all but the publication runs in parallel.
  void find_ghost_ranks(const std::vector<Vec3>& x, std::int64_t nown) {
    bounds_ = particle_bounds(x, nown);
    GhostScratch& g = g_;
    const std::int64_t nb = nown >= kMinParallel ? omp_get_max_threads() : 1;
    const auto lo = [&](std::int64_t b) { return nown * b / nb; };
    if (static_cast<std::int64_t>(g.block.size()) < nb) g.block.resize(nb);
    resize_for_overwrite(g.cell_of, nown);
    // Each block's distinct cells, in the order of their first particle (one lookup for a run
    // of particles in the same cell), and whether each is on the piece's border.
#pragma omp parallel for schedule(static) if (nb > 1)
    for (std::int64_t b = 0; b < nb; ++b) {
      GhostBlock& w = g.block[b];
      w.cells.clear();
      w.cell_key.clear();
      w.depth.clear();
      w.in_piece.clear();  // the decomposition may be new
      w.in_piece_value.clear();
      std::uint64_t last = 0;
      for (std::int64_t i = lo(b); i < lo(b + 1); ++i) {
        const std::uint64_t k = cell_key(x[i]);
        if (i > lo(b) && k == last) {
          g.cell_of[i] = g.cell_of[i - 1];
          continue;
        }
        last = k;
        g.cell_of[i] = w.cells.insert(k);
        if (g.cell_of[i] == static_cast<std::int64_t>(w.cell_key.size())) {
          w.cell_key.push_back(k);
          w.depth.push_back(depth_of(k, w));
        }
      }
    }
    // The border cells published (each once); the other ranks' (cell, rank) sorted, and each
    // distinct cell's range.
    std::vector<std::pair<std::uint64_t, std::int64_t>> pub;
    for (std::int64_t b = 0; b < nb; ++b)
      for (std::size_t c = 0; c < g.block[b].cell_key.size(); ++c)
        if (g.block[b].depth[c] == 0) pub.push_back({g.block[b].cell_key[c], me_});
    std::sort(pub.begin(), pub.end());
    pub.erase(std::unique(pub.begin(), pub.end()), pub.end());
    g.occupied.clear();
    for (const auto& [c, r] : allgatherv(comm_, pub, &band_bytes_))
      if (r != me_) g.occupied.push_back({c, static_cast<int>(r)});
    std::sort(g.occupied.begin(), g.occupied.end());
    g.occupied_cells.clear();
    g.occupied_off.clear();
    for (std::size_t k = 0; k < g.occupied.size(); ++k)
      if (g.occupied_cells.insert(g.occupied[k].first) ==
          static_cast<std::int64_t>(g.occupied_off.size()))
        g.occupied_off.push_back(static_cast<std::int64_t>(k));
    g.occupied_off.push_back(static_cast<std::int64_t>(g.occupied.size()));
    // Per cell of each block, the other ranks within the band (sorted, once each); per
    // particle, its cell's count (then the offsets), its cell's depth and its reach.
    const double w_min = std::min(band_.band, band_.band_z);
    resize_for_overwrite(g.off, nown + 1);
    resize_for_overwrite(depth_, nown);
    resize_for_overwrite(reach_, nown);
#pragma omp parallel for schedule(static) if (nb > 1)
    for (std::int64_t b = 0; b < nb; ++b) {
      GhostBlock& w = g.block[b];
      w.cell_off.assign(1, 0);
      w.cell_ranks.clear();
      for (std::size_t c = 0; c < w.cell_key.size(); ++c) {
        if (w.depth[c] == 0) {
          const std::size_t first = w.cell_ranks.size();
          band_.for_each_neighbour(band_cell_of_key(w.cell_key[c]), [&](std::uint64_t k) {
            const std::int64_t d = g.occupied_cells.find(k);
            if (d < 0) return;
            for (std::int64_t q = g.occupied_off[d]; q < g.occupied_off[d + 1]; ++q)
              w.cell_ranks.push_back(g.occupied[q].second);
          });
          std::sort(w.cell_ranks.begin() + first, w.cell_ranks.end());
          w.cell_ranks.erase(std::unique(w.cell_ranks.begin() + first, w.cell_ranks.end()),
                             w.cell_ranks.end());
        }
        w.cell_off.push_back(static_cast<std::int64_t>(w.cell_ranks.size()));
      }
      for (std::int64_t i = lo(b); i < lo(b + 1); ++i) {
        g.off[i] = w.cell_off[g.cell_of[i] + 1] - w.cell_off[g.cell_of[i]];
        depth_[i] = w.depth[g.cell_of[i]];
        reach_[i] = reach_of(depth_[i], w_min);
      }
    }
    depth_band_ = w_min;
    exclusive_scan(HostExec{}, View<std::int64_t>{g.off.data(), nown + 1}, nown);
    // Per particle, its cell's ranks.
    resize_for_overwrite(g.ranks, g.off[nown]);
#pragma omp parallel for schedule(static) if (nb > 1)
    for (std::int64_t b = 0; b < nb; ++b) {
      const GhostBlock& w = g.block[b];
      for (std::int64_t i = lo(b); i < lo(b + 1); ++i)
        std::copy(w.cell_ranks.begin() + w.cell_off[g.cell_of[i]],
                  w.cell_ranks.begin() + w.cell_off[g.cell_of[i] + 1], g.ranks.begin() + g.off[i]);
    }
  }

  // The bounds of the first nown positions of every rank.
  Bounds particle_bounds(const std::vector<Vec3>& x, std::int64_t nown) {
    auto e = reduce_max_each<6>(
        HostExec{}, nown,
        [&](std::int64_t i) {
          return std::array<double, 6>{-x[i].x, -x[i].y, -x[i].z, x[i].x, x[i].y, x[i].z};
        },
        -std::numeric_limits<double>::infinity());
    MPI_Allreduce(MPI_IN_PLACE, e.data(), 6, MPI_DOUBLE, MPI_MAX, comm_);
    return {{-e[0], -e[1], -e[2]}, {e[3], e[4], e[5]}};
  }

  // The depth of band cell `key` in this rank's piece: the largest k of 2, 4, 8 whose box of
  // (2 k + 1)^3 band cells around it is interior(), 0 when none is (the cell is on the piece's
  // border: another rank's particle may be within the ghost band of its particles). The widest
  // box is tried first: interior() holds for a box inside one it holds for (the smaller box's
  // tree cells lie in the larger one's), and most cells are deep (one test, not three).
  int depth_of(std::uint64_t key, GhostBlock& memo) const {
    int k = kMaxDepth;
    while (k >= 2 && !interior(key, k, memo)) k /= 2;
    return k >= 2 ? k : 0;
  }
  // How far a particle of a cell of depth d (depth_of) may move while the layout stands. At the
  // layout every other rank's particle that is no ghost of this rank was at least max(d, 2)
  // band cells of width w from it: beyond the ghost band of its cell (2 cells), or outside its
  // box (d cells). Two particles of different ranks, neither the other's ghost, stay beyond
  // the kernel support while each has moved at most half of its distance less the support:
  // skin / 2 on the border (2 w = support + skin), more inside. Larger reaches let the layout
  // stand longer where the flow is far from every cut (a closed tank's surge along its floor
  // and far wall: 55 -> 29 layouts on two GPUs).
  double reach_of(int d, double w) const { return (std::max(d, 2) * w - support_) / 2; }

  // True when every point of the (2 k + 1)^3 band cells around cell `key` within the particles'
  // bounds (bounds_: no rank has a particle outside) belongs to this rank: that part of the box
  // lies in at most 2 x 2 x 2 cells of some tree level, and each of their curve segments (keys
  // are hierarchical, sfc.hpp) lies in this rank's piece. Conservative: false may be answered
  // for an interior cell (it is then published needlessly), never true for another. Periodic
  // z: a box across the seam is not interior. Without the bounds, a box reaching past the
  // particles into empty space that another rank's piece covers was not interior: the dam
  // break's free surfaces at its open sides had the border's reach there.
  bool interior(std::uint64_t key, int k, GhostBlock& memo) const {
    const SfcGrid& g = dec_.grid;
    const std::uint64_t first = dec_.splitters[me_], last = dec_.splitters[me_ + 1];
    if (first >= last) return false;
    const BandCell b = band_cell_of_key(key);
    const std::int64_t* c = b.i;
    if (band_.nz > 0 && (c[2] < k || c[2] + k + 1 > band_.nz)) return false;
    // The box's finest cells, one more on each side against round-off in band_cell's floor.
    std::uint32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = g.coord(band_.lo(c[a] - k, a), g.lo[a]);
      hi[a] = g.coord(band_.lo(c[a] + k + 1, a), g.lo[a]);
      lo[a] -= lo[a] > 0;
      hi[a] += hi[a] + 1 < g.side();
      // Within the finest cells of the particles' bounds (coord() does not decrease).
      lo[a] = std::max(lo[a], g.coord(bounds_.lo[a], g.lo[a]));
      hi[a] = std::min(hi[a], g.coord(bounds_.hi[a], g.lo[a]));
      if (lo[a] > hi[a]) return true;  // no particle in the box
    }
    const std::uint32_t base = curve_base(g.curve);
    std::uint32_t s = 1;  // finest cells per side of a cell of the level
    std::uint64_t span = 1;
    auto fits = [&] {
      for (int a = 0; a < 3; ++a)
        if (hi[a] / s - lo[a] / s > 1) return false;
      return true;
    };
    // Levels whose cells are at most half as wide as the box cannot fit (hi / s - lo / s >=
    // (hi - lo) / s >= 2): skipped without the divisions of fits().
    const std::uint32_t wide = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    int l = g.order;
    for (; l > 0 && 2 * std::uint64_t{s} <= wide; --l)
      s *= base, span *= std::uint64_t(base) * base * base;
    for (; l > 0 && !fits(); --l) s *= base, span *= std::uint64_t(base) * base * base;
    if (!fits()) return false;
    for (std::uint32_t x = lo[0] / s; x <= hi[0] / s; ++x)
      for (std::uint32_t y = lo[1] / s; y <= hi[1] / s; ++y)
        for (std::uint32_t z = lo[2] / s; z <= hi[2] / s; ++z) {
          // Neighbouring band cells test the same tree cells: each one's answer is kept
          // (memo.in_piece; s < 2^16 and coordinates < 2^16 name it).
          const std::int64_t m = memo.in_piece.insert(
              std::uint64_t{s} << 48 | std::uint64_t{x} << 32 | std::uint64_t{y} << 16 | z);
          if (m == static_cast<std::int64_t>(memo.in_piece_value.size())) {
            const std::uint64_t k = sfc_key(g.curve, x * s, y * s, z * s, g.order);
            const std::uint64_t seg = k - k % span;
            memo.in_piece_value.push_back(seg >= first && seg + span <= last);
          }
          if (!memo.in_piece_value[m]) return false;
        }
    return true;
  }

  // Every rebalance_every steps: the owned cost's max / mean - 1 over the ranks against the
  // threshold, and whether a new cut pays for its layout rebuild (recut_pays; a threshold of
  // 0 re-cuts at every measurement). The same decision on every rank.
  bool rebalance_due(double load) {
    if (every_ <= 0 || steps_ % every_ != 0) return false;
    double total = load;
    allreduce_sum_same(comm_, &total, 1);
    double most[3] = {load, window_n_ > 0 ? window_s_ / window_n_ : 0.0, rebuild_s_};
    MPI_Allreduce(MPI_IN_PLACE, most, 3, MPI_DOUBLE, MPI_MAX, comm_);
    window_s_ = 0, window_n_ = 0;
    const double mean = total / np_;
    if (!(mean > 0 && most[0] / mean - 1 > threshold_)) return false;
    return threshold_ == 0 || recut_pays(1 - mean / most[0], most[1], every_, most[2]);
  }

  // The wall time between keep() calls: a step's (window_s_ / window_n_, and since_s_ since
  // the last rebuild), or, for the interval that holds a layout rebuild a keep() asked for,
  // the rebuild's (less a step).
  void time_step() {
    const double now = MPI_Wtime();
    if (last_keep_ > 0) {
      const double dt = now - last_keep_;
      if (rebuilt_) {
        rebuild_s_ = std::max(rebuild_s_, dt - (window_n_ > 0 ? window_s_ / window_n_ : 0.0));
      } else {
        window_s_ += dt;
        since_s_ += dt;
        ++window_n_;
      }
    }
    rebuilt_ = false;
    last_keep_ = now;
  }

  // Before a rebuild the motion asked for: the skin of the next layout (widened_margin, from
  // the largest rebuild and stepping times over the ranks).
  void widen_skin() {
    double t[2] = {rebuild_s_, since_s_};
    MPI_Allreduce(MPI_IN_PLACE, t, 2, MPI_DOUBLE, MPI_MAX, comm_);
    since_s_ = 0;
    const double skin =
        widened_margin(skin_, kMaxMarginGrowth * kFluidSkin * support_, t[0], t[1], kFluidSkinStep);
    if (skin != skin_) {
      skin_ = skin;
      band_ = BandGrid((support_ + skin_) / 2, z0_, period_);
    }
  }

  Space space_;  // where the stage's arrays live (a GPU stage's ghosts may stay on the device)
  MPI_Comm comm_ = MPI_COMM_NULL;
  int me_ = 0, np_ = 1;
  Curve curve_;
  long every_ = 0;
  double threshold_ = 0, max_cell_ = 0;
  double support_, z0_, period_;  // the kernel support; the band grid's z origin and period
  double skin_ = 0;               // the ghost band's margin beyond the kernel support (widen_skin)
  BandGrid band_;                 // band cells: half of support + skin wide, wrapping a periodic z
  long steps_ = 0;                // keep() calls
  bool rebalance_ = false;        // the next distribute() cuts the partition again
  // Wall times the re-cut decision weighs (time_step): steps since the last measurement, and
  // the longest layout rebuild so far (the exchange's part, then the whole interval).
  double last_keep_ = 0, window_s_ = 0, since_s_ = 0, rebuild_s_ = 0;
  long window_n_ = 0;
  bool rebuilt_ = false;  // a keep()-asked distribute() ran since the last keep()
  // Traffic (this rank's bytes sent): evaluations counts keep() calls and the distribute()
  // calls no keep() asked for (the first, and the one after a load_state).
  bool after_keep_ = false;  // the next distribute() is the one a keep() asked for
  std::int64_t evaluations_ = 0, rebuilds_ = 0, recuts_ = 0;
  std::int64_t halo_bytes_ = 0, migrated_bytes_ = 0, band_bytes_ = 0;
  Decomposition dec_;
  std::unique_ptr<MigratePlan> migrate_;  // re-planned at each distribute(): buffers kept
  std::unique_ptr<HaloPlan> halo_;        // planned again at each distribute(): buffers kept
  // distribute()'s work arrays, kept so that a rebuild reuses their storage.
  std::vector<double> cost_;              // per particle: its cost before any is measured
  std::vector<std::uint64_t> curve_key_;  // per particle: its key on dec_.grid
  std::vector<int> dest_;                 // per particle: its new owner
  std::vector<std::int64_t> leave_;       // the particles that change owner, increasing
  std::vector<std::int64_t> fill_;        // the kept particles from the kept count on, less it
  std::vector<int> out_dest_;             // per leaving particle: its new owner
  FluidParticles out_, in_;               // the particles that leave, and those that arrive
  GhostScratch g_;
  // The owned particles of the last layout, by slot: their band cells' depth (depth_of(), no
  // other rank's particle within that many band cells of width depth_band_) and their reach
  // (reach_of()); reached_: every particle's displacement since, at most, as a multiple of its
  // reach (keep()), unknown after distribute() until keep() measures it.
  static constexpr double kUnknown = std::numeric_limits<double>::infinity();
  Bounds bounds_;  // every rank's owned positions at the last layout
  std::vector<std::uint8_t> depth_;
  std::vector<double> reach_;
  double depth_band_ = 0, reached_ = kUnknown;
};

}  // namespace

std::unique_ptr<FluidExchange> make_fluid_exchange(MPI_Comm comm, const ParallelOptions& options,
                                                   const FluidSetup& fluid, Space space) {
  return std::make_unique<MpiFluidExchange>(comm, options, fluid, space);
}

std::unique_ptr<FluidExchange> make_fluid_exchange(const ParallelOptions& options,
                                                   const FluidSetup& fluid, Space space) {
  return make_fluid_exchange(MPI_COMM_WORLD, options, fluid, space);
}

}  // namespace qdemsph
