// WCSPH fluid stage written once over an execution space (HostExec, CudaExec).
//
// Data (SoA, n = fluid + marker + wall particles, kept sorted by (group, cell) with the groups
// fluid | body markers | walls: re-sorted at every compute() by a counting sort, so each group
// is one contiguous range (fluid loops run over [0, nf) only, evenly split between threads),
// the particles of one group in one cell are contiguous and memory access is local):
//   x, v, a (Vec3 buffers), rho, p, drho, m (double), type (uint8), gid (uint64), key (uint64:
//   the particle's place in this order, (group, cell) << 26 | place in the cell, carried to
//   the next sort of a distributed run: fluid_exchange.hpp), slot (int64: the index in the
//   layout of the last redistribution; slot >= n_own: a ghost).
// On several ranks (a FluidExchange) the particles are the rank's owned ones and ghosts within
// one kernel support + skin; every loop skips ghosts, whose values come from their owners: x, v
// at each compute() (all fields when the layout is rebuilt: fluid_exchange.hpp, keep()), rho,
// p, m after the density and after the wall pressure pass; those refreshes pack and unpack
// the ghost records where the arrays live (start_refresh, finish_refresh), and the passes over
// the particles no ghost is near run while they travel (over_fluid).
// Wall particles are fixed; markers move with the bodies (sph/solid_coupling.hpp); the p and rho
// of both come from the fluid by Adami extrapolation.
//
// Per pair evaluation (fluid-fluid): ~150 flops, reads 2 x 9 doubles (pr = p / rho^2 computed
// once per particle after the equation of state, so the force pass divides once per pair, in
// the artificial viscosity of approaching pairs); per particle and step
// ~3 passes over ~75 neighbours (Wendland C2 at h = 1.3 dx, support 2h).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <type_traits>
#include <utility>

#include "core/error.hpp"
#include "core/error_flag.hpp"
#include "core/memory.hpp"
#include "core/radix_sort.hpp"
#include "core/select_host.hpp"
#include "core/timers.hpp"
#include "neighbor/cell_grid.hpp"
#include "physics/sph_boundary.hpp"
#include "physics/sph_pair.hpp"
#include "sph/fluid_exchange.hpp"
#include "sph/fluid_stage.hpp"
#include "sph/solid_coupling.hpp"

namespace qdemsph {

// Particle groups in sorted order.
enum SphGroup : int { kGroupFluid = 0, kGroupMarker = 1, kGroupWall = 2, kSphGroups = 3 };
QDEMSPH_HD int sph_group(std::uint8_t type) {
  return type == kSphFluid ? kGroupFluid : (type == kSphSolid ? kGroupMarker : kGroupWall);
}

// Cells are half the kernel support wide: the 5 x 5 x 5 cells around a particle cover the
// support sphere with 42 % fewer candidates than 3 x 3 x 3 cells of one support width.
inline constexpr int kSphCellsPerSupport = 2;

// Order keys (fluid_exchange.hpp): (group, cell) sort key << kSphKeyShift | place in the cell.
inline constexpr int kSphKeyShift = 26;

// The density and force passes on a GPU: at most 85 registers a thread (768 threads an SM;
// with 98 and 90 only 512 fitted: the dam break's step 4.01 -> 3.61 ms on an H100), in blocks
// of 64 threads. A block holds its place on the SM until its slowest warp ends, and a particle
// at a free surface or a wall visits fewer candidates than one in the bulk: the weak dam break
// (1.1 M particles, an H200) 3.57 -> 3.43 ms a step with blocks of 64, 3.45 with 128
// (references/benchmarks/scaling/2026-11-28_sph_blocks/).
inline constexpr MinBlocks<12, 64> kSphPassLaunch{};

// Neighbour ranges over arrays sorted by (group, cell): the particles of group q in cell c are
// [start[q nc + c], start[q nc + c + 1]), nc the number of cells. Calls f(j, zz) for every
// particle of the groups [G0, G1) in the (2R + 1)^3 cells around p, R = kSphCellsPerSupport;
// zz is the unwrapped z cell: f sees particle j at g.image(x[j], zz) (a periodic z, cell_grid.hpp).
// The cells x0..x1 of a (z, y) row are one range per group, in the order of the sums. On a GPU
// a row's ranges are walked as one loop: a warp's threads, whose particles lie in different
// cells, then wait for each other once a row, not once a range (by a wall one thread has wall
// candidates where its neighbour has fluid ones, and a loop per range paid for both); the loop
// is not unrolled (fewer registers). On two H100s the dam break's passes took 4 % less, and the
// busy imbalance of its two pieces (one holds the end wall) went 0.05 -> 0.03. The host keeps
// its loop per range (a tight inner loop).
template <int G0, int G1, class F>
QDEMSPH_HD void sph_for_each_near(const CellGrid& g, const std::int64_t* start, Vec3 p, F&& f) {
  constexpr int R = kSphCellsPerSupport, NG = G1 - G0;
  const std::int64_t nc = std::int64_t(g.n[0]) * g.n[1] * g.n[2];
  const bool pz = g.period_z > 0;
  const int cx = g.coord(p.x, 0), cy = g.coord(p.y, 1),
            cz = pz ? g.unwrapped_z(p.z) : g.coord(p.z, 2);
  const int x0 = cx > R ? cx - R : 0, x1 = cx + R < g.n[0] ? cx + R : g.n[0] - 1;
  for (int zz = cz - R; zz <= cz + R; ++zz) {
    int z = zz;
    if (pz) {
      z %= g.n[2];
      z = z < 0 ? z + g.n[2] : z;
    } else if (z < 0 || z >= g.n[2]) {
      continue;
    }
    for (int y = cy - R; y <= cy + R; ++y) {
      if (y < 0 || y >= g.n[1]) continue;
      const std::int64_t* s = start + G0 * nc + g.key(0, y, z);
#ifdef __CUDA_ARCH__
      std::int64_t first[NG];
      int upto[NG];  // group q's candidates: upto[q - 1] <= k < upto[q] (a row's count fits)
#pragma unroll
      for (int q = 0; q < NG; ++q) {
        first[q] = s[q * nc + x0];
        upto[q] = (q > 0 ? upto[q - 1] : 0) + static_cast<int>(s[q * nc + x1 + 1] - first[q]);
      }
#pragma unroll 1
      for (int k = 0; k < upto[NG - 1]; ++k) {
        std::int64_t j = first[0] + k;
#pragma unroll
        for (int q = 1; q < NG; ++q)
          if (k >= upto[q - 1]) j = first[q] + (k - upto[q - 1]);
        f(j, zz);
      }
#else
      for (int q = 0; q < NG; ++q)
        for (std::int64_t j = s[q * nc + x0]; j < s[q * nc + x1 + 1]; ++j) f(j, zz);
#endif
    }
  }
}

template <class Exec>
class SphStage final : public FluidStage {
  static constexpr Space S = Exec::space;

 public:
  // `solid`: the bodies' state when the setup has markers (else unused, may be null).
  // `exchange`: a distributed run's (every rank passes the whole setup and starts from the
  // contiguous share [n r / N, n (r + 1) / N) of it, which the first compute() moves to the
  // owners); null on one rank.
  explicit SphStage(const FluidSetup& f, const SolidViews* solid = nullptr,
                    std::unique_ptr<FluidExchange> exchange = nullptr)
      : P_(f.params),
        n_global_(f.size()),
        nf_global_(f.n_fluid),
        nm_(f.n_marker),
        wall_volume_(f.dx * f.dx * f.dx),
        ex_(std::move(exchange)) {
    grid_all_ =
        CellGrid::cover(f.lo, f.hi, P_.kernel.support() / kSphCellsPerSupport, f.z0, f.period_z);
    grid_ = grid_all_;
    start_.resize(kSphGroups * grid_.count() + 1);
    if (double(kSphGroups) * double(grid_all_.count()) >= std::ldexp(1.0, 64 - kSphKeyShift))
      throw InputError(
          "fluid: too many neighbour cells for the particle order keys (coarsen "
          "fluid.spacing or shrink the fluid's box)");
    const std::int64_t r = ex_ ? ex_->rank() : 0, nr = ex_ ? ex_->size() : 1;
    const std::int64_t b = n_global_ * r / nr, e = n_global_ * (r + 1) / nr;
    auto part = [&](const auto& v) {
      return std::remove_cvref_t<decltype(v)>(v.begin() + b, v.begin() + e);
    };
    std::vector<std::uint64_t> key(f.gid.begin() + b, f.gid.begin() + e);  // the setup's order
    set_owned(part(f.x), part(f.v), part(f.rho), part(f.m), part(f.type), part(f.gid), key);
    if (nm_ > 0) {
      if (!solid) throw InputError("the fluid has body markers but no body state to couple to");
      coupling_ = std::make_unique<SolidCoupling<Exec>>(f.markers, f.n_fluid + f.n_wall, *solid);
    }
    if (!ex_) sort();  // groups contiguous before the first compute places the markers
    setting_up_ = true;
    compute();
    setting_up_ = false;
    timers_.clear_except("sph.setup");  // the first layout is set-up, not a step's upkeep
  }

  void kick(double h) override {
    const auto a = a_.cview();
    const auto v = v_.view();
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    for_each(
        Exec{}, nf_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (slot[i] < nown) v.set(i, v[i] + h * a[i]);
        });
  }

  void drift(double h) override {
    const auto v = v_.cview();
    const auto x = x_.view();
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    const CellGrid g = grid_;
    for_each(
        Exec{}, nf_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (slot[i] < nown) x.set(i, g.wrap(x[i] + h * v[i]));
        });
    pending_dt_ += h;
  }

  void compute() override {
    // The fluid step since the last compute: the density update's dt and the markers' H.
    const double ddt = pending_dt_;
    pending_dt_ = 0;
    // Markers first, so that a distributed layout's skin rule sees where they moved (every rank
    // places the markers it holds from the same vertex positions: a ghost's is its owner's).
    if (coupling_) coupling_->place(x_.view(), v_.view(), gid_.cview(), type_.cview(), n_, ddt);
    if (ex_) {
      bool keep = false;
      {
        exec_sync(Exec{});  // the work before is the step's (timers_ below)
        auto s = timers_.scope("sph.halo");
        auto s1 = timers_.scope("sph.halo.skin");
        keep = laid_out_ && ex_->keep(reached(), ex_->wants_load() ? owned_cost() : 0.0);
      }
      if (keep) {
        refresh_positions();
      } else {
        auto s = timers_.scope(setting_up_ ? "sph.setup" : "sph.rebuild");
        redistribute();
      }
    }
    sort();
    const SphParams P = P_;
    const CellGrid g = grid_;
    const std::int64_t* start = start_.cview().p;
    const std::int64_t nf = nf_;
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    const auto x = x_.cview(), v = v_.cview();
    const auto gid = gid_.cview();
    const auto m = m_.view();
    const auto rho = rho_.view();
    const auto p = p_.view();
    const auto drho = drho_.view();
    // Distributed: each owned particle's cost, the neighbour candidates its passes visit (the
    // partition's weights, fluid_exchange.hpp): a fluid particle's density and force passes
    // visit the same candidates, a wall's Adami pass the fluid ones, a marker's Adami and
    // force passes the fluid ones.
    double* const cost = ex_ ? cost_.view().p : nullptr;
    // Density rate at the drifted positions and half-step velocities (continuity + delta-SPH),
    // then rho_{n+1} = rho_n + dt drho: the pressure is taken at the same time as the positions
    // (a density lagging half a step behind the positions makes the acoustic modes grow).
    const auto density_rate = QDEMSPH_LAMBDA(std::int64_t i) {
      const PairState si{x[i], v[i], rho[i], m[i], 0.0};
      double dr = 0;
      std::int64_t visited = 0;
      const double s2 = P.kernel.support2;
      sph_for_each_near<kGroupFluid, kSphGroups>(g, start, si.x, [&](std::int64_t j, int zz) {
        ++visited;
        const Vec3 xj = g.image(x[j], zz);
        const double r2 = norm2(si.x - xj);  // 0: i itself (not its periodic images)
        if (r2 == 0 || r2 >= s2) return;     // most candidates: no further loads
        const PairState sj{xj, v[j], rho[j], m[j], 0.0};
        dr += sph_density_rate(P, si, sj, j < nf);
      });
      drho[i] = dr;
      if (cost) cost[i] = 2.0 * visited;
    };
    const auto pr = pr_.view();
    // Distributed, the records on the GPUs: the passes over particles near ghosts on the side
    // stream, beside those over the others (its blocks first; neither launch drains alone).
    const bool side = ex_ && ex_->buffer_space() == Space::Cuda;
    if (ex_) {
      // The particles near ghosts first; then the ghosts' new rho, p (the equation of state
      // applied to the records: rho itself is read until the pass ends) and m travel while
      // the others run.
      const GhostColumns c = pressure_columns();
      {
        SideQueue q(side);
        over_fluid(true, density_rate, kSphPassLaunch);
        start_refresh(
            c, QDEMSPH_LAMBDA(std::int64_t i, int k) {
              const double r = i < nf ? P.eos.next_density(rho[i], drho[i], ddt) : rho[i];
              return k == 0 ? r : k == 1 ? (i < nf ? P.eos.pressure(r) : p[i]) : m[i];
            });
      }
      over_fluid(false, density_rate, kSphPassLaunch);
      finish_refresh(c);  // the side stream's work is done: its records were waited for
      ghost_pressure_terms();
    } else {
      over_owned(0, nf, density_rate, kSphPassLaunch);
    }
    // Equation of state (fluid), density floored at the tension cut-off (sph_eos.hpp); the
    // pair term p / rho^2 of every particle once (sph_pair.hpp).
    for_each(
        Exec{}, nf, QDEMSPH_LAMBDA(std::int64_t i) {
          if (slot[i] >= nown) return;
          rho[i] = P.eos.next_density(rho[i], drho[i], ddt);
          p[i] = P.eos.pressure(rho[i]);
          pr[i] = p[i] / (rho[i] * rho[i]);
        });
    // Wall and marker pressure and density by extrapolation from the fluid (Adami, with gravity
    // only: solid_coupling.hpp says why a body's acceleration is left out). Mass rho V with the
    // particle's volume: dx^3 for walls, the body lattice cell for markers.
    {
      const double wall_volume = wall_volume_;
      const std::uint64_t g0 = coupling_ ? coupling_->gid0() : 0;
      const auto mvol = coupling_ ? coupling_->volume() : View<const double>{};
      const std::int64_t nm = nml_;
      over_owned(
          nf, n_ - nf, QDEMSPH_LAMBDA(std::int64_t i) {
            const std::int64_t q = i - nf;
            const Vec3 xi = x[i];
            AdamiSum s;
            std::int64_t visited = 0;
            sph_for_each_near<kGroupFluid, kGroupFluid + 1>(
                g, start, xi, [&](std::int64_t j, int zz) {
                  ++visited;
                  adami_add(s, P.kernel, xi, g.image(x[j], zz), p[j], rho[j]);
                });
            if (cost) cost[i] = (q < nm ? 2.0 : 1.0) * visited;
            const double pw = adami_pressure(s, P.gravity, Vec3{});
            p[i] = pw;
            rho[i] = P.eos.density(pw);
            pr[i] = pw / (rho[i] * rho[i]);
            m[i] = rho[i] * (q < nm ? mvol[gid[i] - g0] : wall_volume);
          });
    }
    // Pair sums: acceleration of fluid particles. Distributed: the ghost walls' p, rho, m
    // travel while the particles with no ghost near run, then the others.
    const auto a = a_.view();
    const bool wall_visc = P.wall_viscosity;
    const auto force = QDEMSPH_LAMBDA(std::int64_t i) {
      const PairState si{x[i], v[i], rho[i], m[i], pr[i]};
      Vec3 f{};
      const double s2 = P.kernel.support2;
      sph_for_each_near<kGroupFluid, kSphGroups>(g, start, si.x, [&](std::int64_t j, int zz) {
        const Vec3 xj = g.image(x[j], zz);
        const double r2 = norm2(si.x - xj);
        if (r2 == 0 || r2 >= s2) return;
        const PairState sj{xj, v[j], rho[j], m[j], pr[j]};
        f += j < nf ? sph_pair_force(P, si, sj, true) : sph_boundary_force(P, si, sj, wall_visc);
      });
      a.set(i, P.gravity + f / si.m);
    };
    if (ex_) {
      const GhostColumns c = pressure_columns();
      {
        SideQueue q(side);
        start_refresh(
            c, QDEMSPH_LAMBDA(std::int64_t i, int k) { return c.c[k][i]; });
      }
      over_fluid(false, force, kSphPassLaunch);
      {
        SideQueue q(side, &packed_);
        finish_refresh(c);
        ghost_pressure_terms();
        over_fluid(true, force, kSphPassLaunch);
        if (side) forces_.record();
      }
      if (side) forces_.follow();
    } else {
      over_owned(0, nf, force, kSphPassLaunch);
    }
    if (coupling_) {
      // The fluid's force on each marker: the exact negative of each pair force the marker
      // exerts on the fluid (sph_pair.hpp), so the coupling conserves momentum. Distributed:
      // each marker's by its owner, then every marker's on every rank (a sum over the ranks in
      // which one term is not zero: exact), so every rank gathers the same vertex forces.
      const auto F = coupling_->force();
      const std::uint64_t g0 = coupling_->gid0();
      if (ex_)
        for_each(
            Exec{}, nm_, QDEMSPH_LAMBDA(std::int64_t k) { F.set(k, Vec3{}); });
      for_each(
          Exec{}, nml_, QDEMSPH_LAMBDA(std::int64_t q) {
            const std::int64_t i = nf + q;
            if (slot[i] >= nown) return;
            const PairState si{x[i], v[i], rho[i], m[i], pr[i]};
            Vec3 f{};
            const double s2 = P.kernel.support2;
            sph_for_each_near<kGroupFluid, kGroupFluid + 1>(
                g, start, si.x, [&](std::int64_t j, int zz) {
                  const Vec3 xj = g.image(x[j], zz);
                  if (norm2(si.x - xj) >= s2) return;
                  const PairState sj{xj, v[j], rho[j], m[j], pr[j]};
                  f -= sph_boundary_force(P, sj, si, wall_visc);
                });
            F.set(static_cast<std::int64_t>(gid[i] - g0), f);
          });
      if (ex_) {
        // Each marker's force comes from the rank that owns it (the others hold zero).
        const std::size_t bytes = nm_ * sizeof(double);
        std::vector<double> h(nm_);
        double* const comp[3] = {F.x, F.y, F.z};
        for (double* c : comp) {
          space_copy(h.data(), Space::Host, c, S, bytes);
          ex_->sum(h);
          space_copy(c, S, h.data(), Space::Host, bytes);
        }
      }
      coupling_->apply(ddt);
    }
  }

  FluidStats stats() override {
    const auto v = v_.cview(), a = a_.cview();
    const auto m = m_.cview(), rho = rho_.cview();
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    const double rho0 = P_.eos.rho0;
    const std::int64_t nf = nf_;
    FluidStats s;
    s.kinetic = reduce_sum(
        Exec{}, nf,
        QDEMSPH_LAMBDA(std::int64_t i) { return slot[i] < nown ? 0.5 * m[i] * norm2(v[i]) : 0.0; });
    for (int c = 0; c < 3; ++c) {
      const double* vc = c == 0 ? v.x : (c == 1 ? v.y : v.z);
      s.momentum[c] = reduce_sum(
          Exec{}, nf,
          QDEMSPH_LAMBDA(std::int64_t i) { return slot[i] < nown ? m[i] * vc[i] : 0.0; });
    }
    s.v_max = reduce_max(
        Exec{}, nf, QDEMSPH_LAMBDA(std::int64_t i) { return slot[i] < nown ? norm(v[i]) : 0.0; },
        0.0);
    s.a_max = reduce_max(
        Exec{}, nf, QDEMSPH_LAMBDA(std::int64_t i) { return slot[i] < nown ? norm(a[i]) : 0.0; },
        0.0);
    s.rho_dev = reduce_max(
        Exec{}, nf,
        QDEMSPH_LAMBDA(std::int64_t i) { return slot[i] < nown ? fabs(rho[i] / rho0 - 1.0) : 0.0; },
        0.0);
    if (coupling_) s.force_on_bodies = coupling_->total_force();
    if (ex_) {
      double sums[4] = {s.kinetic, s.momentum.x, s.momentum.y, s.momentum.z};
      double maxs[3] = {s.v_max, s.a_max, s.rho_dev};
      ex_->sum(sums);
      ex_->max(maxs);
      s.kinetic = sums[0];
      s.momentum = Vec3{sums[1], sums[2], sums[3]};
      s.v_max = maxs[0], s.a_max = maxs[1], s.rho_dev = maxs[2];
    }
    return s;
  }

  SphDtLimits dt_limits() override {
    const FluidStats s = stats();
    const double c_max = P_.eos.sound_speed(P_.eos.rho0 * (1.0 + s.rho_dev));
    return sph_dt_limits(P_.kernel.h, c_max, s.v_max, s.a_max, P_.nu);
  }

  std::int64_t find_non_finite() override {
    const auto x = x_.cview(), v = v_.cview();
    const auto rho = rho_.cview();
    const auto gid = gid_.cview();
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    double r = reduce_max(
        Exec{}, n_,
        QDEMSPH_LAMBDA(std::int64_t i) {
          const double s = x.x[i] + x.y[i] + x.z[i] + v.x[i] + v.y[i] + v.z[i] + rho[i];
          return slot[i] >= nown || is_finite(s) ? 0.0 : static_cast<double>(gid[i] + 1);
        },
        0.0);
    if (ex_) ex_->max({&r, 1});
    return static_cast<std::int64_t>(r) - 1;
  }

  // Distributed: rank 0 gets every particle in the one-rank order (other ranks: empty).
  FluidHost download() override {
    FluidState s = save_state();
    return {std::move(s.x), std::move(s.v),    std::move(s.rho),
            std::move(s.p), std::move(s.type), std::move(s.gid)};
  }

  // Distributed: the owned particles of every rank on rank 0, in the order of their keys: the
  // one-rank order, so a checkpoint of N ranks is the one-rank file (other ranks: empty).
  FluidState save_state() override {
    if (!ex_)
      return {x_.to_host(), v_.to_host(), a_.to_host(),    rho_.to_host(),
              p_.to_host(), m_.to_host(), type_.to_host(), gid_.to_host()};
    pick_owned();
    std::vector<std::uint64_t> mine;
    take_owned(key_.cview(), mine);
    const auto key = ex_->gather(mine);
    by_key_.resize(key.size());
    for (std::size_t k = 0; k < key.size(); ++k) by_key_[k] = {key[k], std::int64_t(k)};
    radix_sort(by_key_, by_key_scratch_);
    auto all = [&](auto view) {
      std::vector<std::remove_cvref_t<decltype(view[0])>> o;
      take_owned(view, o);
      const auto g = ex_->gather(o);
      o.resize(g.size());
      for (std::size_t k = 0; k < g.size(); ++k) o[k] = g[by_key_[k].second];
      return o;
    };
    return {all(x_.cview()), all(v_.cview()), all(a_.cview()),    all(rho_.cview()),
            all(p_.cview()), all(m_.cview()), all(type_.cview()), all(gid_.cview())};
  }

  // Distributed: every rank passes the whole state and keeps its contiguous share (the next
  // compute() moves the particles to their owners).
  void load_state(const FluidState& s) override {
    const auto n = static_cast<std::size_t>(n_global_);
    if (s.x.size() != n || s.v.size() != n || s.a.size() != n || s.rho.size() != n ||
        s.p.size() != n || s.m.size() != n || s.type.size() != n || s.gid.size() != n)
      throw InputError("fluid state does not fit the scene (particle count)");
    const std::int64_t r = ex_ ? ex_->rank() : 0, nr = ex_ ? ex_->size() : 1;
    const std::int64_t b = n_global_ * r / nr, e = n_global_ * (r + 1) / nr;
    auto part = [&](const auto& v) {
      return std::remove_cvref_t<decltype(v)>(v.begin() + b, v.begin() + e);
    };
    std::vector<std::uint64_t> key(e - b);  // the state is in its order
    std::iota(key.begin(), key.end(), std::uint64_t(b));
    set_owned(part(s.x), part(s.v), part(s.rho), part(s.m), part(s.type), part(s.gid), key);
    a_.assign(part(s.a));
    p_.assign(part(s.p));
    pending_dt_ = 0;
  }

  std::map<std::string, double> stage_seconds() const override { return timers_.seconds(); }
  std::int64_t size() const override { return n_global_; }
  std::int64_t n_fluid() const override { return nf_global_; }
  std::int64_t n_marker() const override { return nm_; }
  const SphParams& params() const override { return P_; }
  std::size_t device_bytes() const override {
    return x_.bytes() + v_.bytes() + a_.bytes() + rho_.bytes() + p_.bytes() + drho_.bytes() +
           pr_.bytes() + m_.bytes() + x0_.bytes() + reach_.bytes() + type_.bytes() + gid_.bytes() +
           key_.bytes() + slot_.bytes() + tmp3_.bytes() + tmpd_.bytes() + tmpu_.bytes() +
           tmpt_.bytes() + tmpi_.bytes() + send_.bytes() + inv_.bytes() + pack_.bytes() +
           cost_.bytes() + picked_.bytes() + up_.bytes() + depth_.bytes() + near_order_.bytes() +
           near_start_.bytes() + keys_.bytes() + start_.bytes() + order_.bytes() +
           scratch_.bytes() + (coupling_ ? coupling_->bytes() : 0);
  }

  // Public only because nvcc's extended lambdas need an accessible enclosing function.
  // Stable sort by (group, cell) (sort_by_key, neighbor/cell_grid.hpp), then the per-particle
  // arrays that carry state across steps gathered into the new order.
  void sort() {
    if (keys_.size() != n_) keys_.resize(n_);
    const auto k = keys_.view();
    const auto x = x_.cview();
    const auto type = type_.cview();
    const CellGrid g = grid_;
    const std::int64_t nc = grid_.count();
    for_each(
        Exec{}, n_,
        QDEMSPH_LAMBDA(std::int64_t i) { k[i] = sph_group(type[i]) * nc + g.key_of(x[i]); });
    if (order_.size() != n_) order_.resize(n_);
    sort_by_key(Exec{}, keys_.cview(), kSphGroups * nc, start_.view(), order_.view(), scratch_);
    const auto ord = order_.cview();
    // a, p and drho are not carried: compute() rewrites them (fluid: density, EOS and force
    // passes; boundary: Adami) before anything reads them.
    permute_state(ord);
    permute(slot_, tmpi_, ord);
    // The order key of each particle: its bucket (in the whole box's grid) and its place in it.
    const auto key = key_.view();
    const auto kc = keys_.cview();
    const std::int64_t* start = start_.cview().p;
    const std::int64_t nca = grid_all_.count();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          const std::int64_t b = kc[ord[i]];
          const std::int64_t q = b / nc, c = b - q * nc;
          const std::int64_t cx = c % g.n[0] + g.first[0], cy = c / g.n[0] % g.n[1] + g.first[1],
                             cz = c / (std::int64_t(g.n[0]) * g.n[1]) + g.first[2];
          const std::int64_t ba = q * nca + (cz * g.full[1] + cy) * g.full[0] + cx;
          key[i] = (static_cast<std::uint64_t>(ba) << kSphKeyShift) |
                   static_cast<std::uint64_t>(i - start[b]);
        });
    if (ex_) {  // the particle in each layout slot, for the refreshes until the next sort
      const auto slot = slot_.cview();
      const auto inv = inv_.view();
      for_each(
          Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { inv[slot[i]] = i; });
      // The owned fluid particles no ghost is near, then those near ghosts, each in this order
      // (over_fluid's lists; the ghosts last): a pass over one kind runs full warps, where a
      // test per particle left the warps on the border between the kinds half idle in both
      // passes (~40 % of a rank's warps in a two-rank dam break).
      const auto depth = depth_.cview();
      const std::int64_t nown = n_own_;
      for_each(
          Exec{}, nf_, QDEMSPH_LAMBDA(std::int64_t i) {
            k[i] = slot[i] >= nown ? 2 : depth[slot[i]] == 0 ? 1 : 0;
          });
      if (near_order_.size() != nf_) near_order_.resize(nf_);
      if (near_start_.size() != 4) near_start_.resize(4);
      sort_by_key(Exec{}, View<const std::int64_t>{keys_.cview().p, nf_}, 3, near_start_.view(),
                  near_order_.view(), scratch_);
    }
  }
  template <class T>
  void permute(Buffer<T>& b, Buffer<T>& tmp, View<const std::int64_t> ord) {
    if (tmp.size() != n_) tmp.resize(n_);
    const auto src = b.cview();
    const auto dst = tmp.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst[i] = src[ord[i]]; });
    b.swap(tmp);
  }
  // The particles' carried state (x, v, rho, m, type, gid) into the order ord.
  void permute_state(View<const std::int64_t> ord) {
    permute3(x_, ord);
    permute3(v_, ord);
    permute(rho_, tmpd_, ord);
    permute(m_, tmpd_, ord);
    permute(type_, tmpt_, ord);
    permute(gid_, tmpu_, ord);
  }
  void permute3(Vec3Buffer& b, View<const std::int64_t> ord) {
    if (tmp3_.size() != n_) tmp3_.resize(n_);
    const auto src = b.cview();
    const auto dst = tmp3_.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst.set(i, src[ord[i]]); });
    std::swap(b, tmp3_);
  }

  // Distributed: the owned particles to the exchange, which migrates them and adds the
  // ghosts; the result laid out in the order of the keys (the one-rank order restricted to
  // this rank's particles), slot = its place in the exchange's layout.
  void redistribute() {
    FluidParticles& q = q_;  // its storage reused
    std::optional<PhaseTimers::Scope> part;
    part.emplace(timers_, "sph.rebuild.out");
    pick_owned();
    take_owned(x_.cview(), q.x);
    take_owned(v_.cview(), q.v);
    take_owned(rho_.cview(), q.rho);
    take_owned(m_.cview(), q.m);
    take_owned(type_.cview(), q.type);
    take_owned(gid_.cview(), q.gid);
    take_owned(key_.cview(), q.key);
    q.cost.clear();
    q.slot.clear();
    if (laid_out_) {
      take_owned(cost_.cview(), q.cost);  // measured by the last compute()
      take_owned(slot_.cview(), q.slot);
    }
    part.reset();
    const std::int64_t nown = ex_->distribute(q, timers_);
    part.emplace(timers_, "sph.rebuild.in");
    std::optional<PhaseTimers::Scope> sub;
    sub.emplace(timers_, "sph.rebuild.in.order");
    const std::int64_t n = static_cast<std::int64_t>(q.size());
    const std::uint64_t place = (std::uint64_t{1} << kSphKeyShift) - 1;
    // One pass over the particles, on the threads, for their extremes: of the positions each
    // may reach while the layout stands (an owned particle its reach, a ghost skin / 2, a wall
    // none; a cell coordinate does not decrease with the position, so the extreme cells are
    // those of the extreme positions) and the keys' buckets and places (the key sort below),
    // where six passes over every particle's cell and three over the keys were: 4.1 -> 0.8 ms a
    // rebuild of rank 0's ~200 k particles (the dam break of 359 k particles on 2 ranks of one
    // thread, median of 3 runs on the 2-core VM).
    const std::vector<double>& reach = ex_->reach();
    const double ghost_reach = 0.5 * ex_->skin();
    const auto e = reduce_max_each<9>(
        HostExec{}, n,
        [&](std::int64_t k) {
          const double r = q.type[k] == kSphWall ? 0.0 : k < nown ? reach[k] : ghost_reach;
          const Vec3 x = q.x[k];
          const auto b = static_cast<double>(q.key[k] >> kSphKeyShift);
          return std::array<double, 9>{r - x.x, r - x.y, r - x.z,
                                       x.x + r, x.y + r, x.z + r,
                                       -b,      b,       static_cast<double>(q.key[k] & place)};
        },
        -std::numeric_limits<double>::infinity());
    // The neighbour grid: the window of the whole box's cells that holds where this rank's
    // particles can go while the layout stands, so none leaves it (coordinates outside a window
    // are clamped into its border cells). A periodic z keeps all its cells (they wrap: a rank
    // at the seam holds ghosts from the other side).
    const auto cell = [&](double x, int a) { return std::isfinite(x) ? grid_all_.coord(x, a) : 0; };
    int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(cell(-e[a], a), 0);
      hi[a] = std::min(std::max(cell(e[3 + a], a), lo[a]), grid_all_.n[a] - 1);
      if (a == 2 && grid_all_.period_z > 0) lo[a] = 0, hi[a] = grid_all_.n[a] - 1;
    }
    grid_ = grid_all_.window(lo, hi);
    start_.resize(kSphGroups * grid_.count() + 1);
    // The layout slots in the order of the keys (slot_), sorted where the stage's arrays live
    // (sort_order: by radix, on the host's threads or the device's) on the bits that tell them
    // apart (keys are unique: each is its owner's place for the particle): the bucket less the
    // rank's smallest, above the place in the bucket in the bits the largest place needs (~28
    // bits where the keys have ~49: 4 passes, not 7). Before, a device's were sorted on the
    // host and uploaded.
    const auto b0 = n > 0 ? static_cast<std::uint64_t>(-e[6]) : 0;
    const auto b1 = n > 0 ? static_cast<std::uint64_t>(e[7]) : 0;
    const int pb = n > 0 ? std::bit_width(static_cast<std::uint64_t>(e[8])) : 0;
    const std::uint64_t* kq = readable(q.key);
    keys_.resize_for_overwrite(n);
    const auto by_key = keys_.view();
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t k) {
          by_key[k] =
              static_cast<std::int64_t>(((kq[k] >> kSphKeyShift) - b0) << pb | (kq[k] & place));
        });
    slot_.resize_for_overwrite(n);
    sort_order(Exec{}, keys_.cview(), n > 0 ? std::bit_width((b1 - b0 + 1) << pb) : 0, slot_.view(),
               scratch_);
    // Each particle i in the order of the keys from layout slot slot_[i], gathered where the
    // stage's arrays live (gather_layout()): a host stage's from q in place, a device's from q's
    // fields uploaded as they are. Before, a device's were gathered on the host, one component
    // at a time, into page-locked staging and uploaded in order: random reads of every field on
    // the host threads.
    sub.emplace(timers_, "sph.rebuild.in.fields");
    size_for(q.type);
    n_own_ = nown;
    gather_from(key_, kq);         // q.key is there already
    gather_layout(x_, q.x, &x0_);  // and the owned positions by slot
    gather_layout(v_, q.v);
    gather_layout(rho_, q.rho);
    gather_layout(m_, q.m);
    gather_layout(type_, q.type);
    gather_layout(gid_, q.gid);
    reach_.assign(reach);
    depth_.assign(ex_->depth());
    n_fluid_near_ = n_fluid_far_ = 0;  // the owned fluid particles near ghosts, and the others
    for (std::int64_t k = 0; k < nown; ++k)
      if (q.type[k] == kSphFluid) ++(ex_->depth()[k] == 0 ? n_fluid_near_ : n_fluid_far_);
    send_.assign(ex_->send_slots());
    inv_.resize(n_);
    cost_.resize(n_);
    laid_out_ = true;
  }

  // Distributed: the owned particles' cost in the last compute() (0 before the first).
  double owned_cost() {
    const auto c = cost_.cview();
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    return reduce_sum(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { return slot[i] < nown ? c[i] : 0.0; });
  }

  // Distributed: the largest displacement of an owned particle since the last redistribute()
  // (across a periodic z's seam, the nearest image's) as a multiple of its reach.
  double reached() {
    const auto x = x_.cview(), x0 = x0_.cview();
    const auto slot = slot_.cview();
    const auto reach = reach_.cview();
    const std::int64_t nown = n_own_;
    const CellGrid g = grid_all_;
    return std::sqrt(reduce_max(
        Exec{}, nf_ + nml_,  // fluid and markers, the groups first in order (walls do not move)
        QDEMSPH_LAMBDA(std::int64_t i) {
          if (slot[i] >= nown) return 0.0;
          const double r = reach[slot[i]];
          return norm2(g.nearest(x[i] - x0[slot[i]])) / (r * r);
        },
        0.0));
  }

  // body(i) for the owned particles i of [first, first + n).
  template <class Body, int N = 1, int T = 256>
  void over_owned(std::int64_t first, std::int64_t n, const Body& body,
                  MinBlocks<N, T> launch = {}) {
    const auto slot = slot_.cview();
    const std::int64_t nown = n_own_;
    for_each(
        Exec{}, n,
        QDEMSPH_LAMBDA(std::int64_t q) {
          if (slot[first + q] < nown) body(first + q);
        },
        launch);
  }
  // Distributed: body(i) for the owned fluid particles i near ghosts (their band cell's depth
  // is 0: another rank's particle may come within the kernel support while the layout stands,
  // FluidExchange::depth()), or for the others, which read no ghost (the passes over them run
  // while ghost values travel); from the lists of the last sort.
  template <class Body, int N = 1, int T = 256>
  void over_fluid(bool near_ghosts, const Body& body, MinBlocks<N, T> launch = {}) {
    const std::int64_t* order = near_order_.cview().p + (near_ghosts ? n_fluid_far_ : 0);
    for_each(
        Exec{}, near_ghosts ? n_fluid_near_ : n_fluid_far_,
        QDEMSPH_LAMBDA(std::int64_t q) { body(order[q]); }, launch);
  }

  // Component arrays of this rank's particles whose ghost entries a refresh sets.
  struct GhostColumns {
    static constexpr int kMax = 6;
    double* c[kMax] = {};
    int n = 0;
    void add(Vec3View v) { c[n++] = v.x, c[n++] = v.y, c[n++] = v.z; }
    void add(View<double> v) { c[n++] = v.p; }
  };

  // Distributed: the ghosts' entries of columns f from their owners, in two halves: work
  // queued between them reads no ghost entry of f (over_fluid(false)) and runs while the
  // records travel. start_refresh packs the records (one double per column; column c of owned
  // particle i's is record(i, c)) where the arrays live, a GPU stage copying only the records
  // between device and host, and posts those staged through the host; device-resident ones
  // are posted by finish_refresh, the exchange waiting for the pack only
  // (FluidExchange::mark_packed), so on a GPU the work between runs beside the copies.
  // finish_refresh unpacks the records into the ghosts. "sph.halo" times the host's wait for
  // the exchange alone.
  template <class Record>
  void start_refresh(const GhostColumns f, const Record& record) {
    const std::int64_t ns = send_.size(), ng = n_ - n_own_;
    const int w = f.n;
    const auto at = inv_.cview();
    const auto send = send_.cview();
    const std::span<std::byte> out = ex_->send_buffer(w * sizeof(double));
    // Records where the exchange keeps them (a device-resident exchange: this stage's device),
    // or packed here and copied once.
    const Space where = ex_->buffer_space();
    double* pk = reinterpret_cast<double*>(out.data());
    if (where != S) {
      if (pack_.size() < w * std::max(ns, ng)) pack_.resize(w * std::max(ns, ng));
      pk = pack_.view().p;
    }
    for_each(
        Exec{}, ns, QDEMSPH_LAMBDA(std::int64_t k) {
          const std::int64_t i = at[send[k]];
          for (int c = 0; c < w; ++c) pk[w * k + c] = record(i, c);
        });
    if (where != S) space_copy(out.data(), where, pk, S, out.size());
    if (where == Space::Host) {
      auto s = timers_.launch("sph.halo");
      auto s1 = timers_.launch("sph.halo.mpi");
      ex_->begin_refresh();
    } else {
      ex_->mark_packed();
      packed_.record();
    }
  }
  void finish_refresh(const GhostColumns f) {
    const std::int64_t ng = n_ - n_own_, nown = n_own_;
    const int w = f.n;
    const auto at = inv_.cview();
    const Space where = ex_->buffer_space();
    std::span<const std::byte> in;
    {
      if (where != Space::Host) packed_.wait();  // the pack and the passes before: the step's
      auto s = timers_.launch("sph.halo");
      auto s1 = timers_.launch("sph.halo.mpi");
      if (where != Space::Host) ex_->begin_refresh();
      in = ex_->finish_refresh();
    }
    const double* rv = reinterpret_cast<const double*>(in.data());
    if (where != S) {
      space_copy(pack_.view().p, S, in.data(), where, in.size());
      rv = pack_.view().p;
    }
    for_each(
        Exec{}, ng, QDEMSPH_LAMBDA(std::int64_t k) {
          const std::int64_t i = at[nown + k];
          for (int c = 0; c < w; ++c) f.c[c][i] = rv[w * k + c];
        });
  }
  void refresh_positions() {
    GhostColumns f;
    f.add(x_.view());
    f.add(v_.view());
    start_refresh(
        f, QDEMSPH_LAMBDA(std::int64_t i, int c) { return f.c[c][i]; });
    finish_refresh(f);
  }
  // rho, p, m: the columns of the refreshes after the density and the wall pressure passes.
  GhostColumns pressure_columns() {
    GhostColumns f;
    f.add(rho_.view());
    f.add(p_.view());
    f.add(m_.view());
    return f;
  }
  // The ghosts' p / rho^2 from their refreshed p and rho, as the owners have it.
  void ghost_pressure_terms() {
    const auto rho = rho_.cview(), p = p_.cview();
    const auto pr = pr_.view();
    const auto at = inv_.cview();
    const std::int64_t nown = n_own_;
    for_each(
        Exec{}, n_ - nown, QDEMSPH_LAMBDA(std::int64_t k) {
          const std::int64_t i = at[nown + k];  // ghost k's particle
          pr[i] = p[i] / (rho[i] * rho[i]);
        });
  }

  // b[i] = h[slot_[i]] for each of the n_ particles (redistribute()): on the host from h in
  // place, on a device from h uploaded into up_ (one copy, bounced through page-locked chunks:
  // memory_cuda.cu) and gathered there.
  template <class T>
  void gather_layout(Buffer<T>& b, const std::vector<T>& h) {
    gather_from(b, readable(h));
  }
  // b[i] = src[slot_[i]], src where the stage's arrays live.
  template <class T>
  void gather_from(Buffer<T>& b, const T* src) {
    const std::int64_t* ord = slot_.cview().p;
    b.resize_for_overwrite(n_);
    const auto dst = b.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst[i] = src[ord[i]]; });
  }
  // The same for 3-vectors; `by_slot` also gets the first n_own_ entries of h in their order.
  void gather_layout(Vec3Buffer& b, const std::vector<Vec3>& h, Vec3Buffer* by_slot = nullptr) {
    const Vec3* src = readable(h);
    const std::int64_t* ord = slot_.cview().p;
    b.resize_for_overwrite(n_);
    const auto dst = b.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst.set(i, src[ord[i]]); });
    if (!by_slot) return;
    by_slot->resize_for_overwrite(n_own_);
    const auto own = by_slot->view();
    for_each(
        Exec{}, n_own_, QDEMSPH_LAMBDA(std::int64_t k) { own.set(k, src[k]); });
  }
  // h's entries where this stage's kernels read them: h itself on the host, else a copy in up_
  // (valid until the next call).
  template <class T>
  const T* readable(const std::vector<T>& h) {
    if constexpr (S == Space::Host) {
      return h.data();
    } else {
      T* at = up_room<T>(h.size());
      if (!h.empty()) space_copy(at, S, h.data(), Space::Host, sizeof(T) * h.size());
      return at;
    }
  }
  // up_ as room for n entries of T (readable(), take_owned()).
  template <class T>
  T* up_room(std::size_t n) {
    up_.resize_for_overwrite(static_cast<std::int64_t>((sizeof(T) * n + 7) / 8));
    return reinterpret_cast<T*>(up_.view().p);
  }

  // out = the owned particles' entries (pick_) of a local array, gathered where it lives: in
  // place on the host; a device's into up_, then one download (bounced through page-locked
  // chunks, memory_cuda.cu). Before, each device array came down whole, a component at a time,
  // and was gathered on the host.
  // v: a View<const T> or, for T = Vec3, a Vec3CView.
  template <class V, class T>
  void take_owned(const V v, std::vector<T>& out) {
    T* at = owned_out(out);
    const std::int64_t* pick = S == Space::Host ? pick_.data() : picked_.cview().p;
    for_each(
        Exec{}, static_cast<std::int64_t>(out.size()),
        QDEMSPH_LAMBDA(std::int64_t k) { at[k] = v[pick[k]]; });
    owned_down(out, at);
  }
  // take_owned's target: out itself on the host, else up_.
  template <class T>
  T* owned_out(std::vector<T>& out) {
    resize_for_overwrite(out, pick_.size());
    if constexpr (S == Space::Host) {
      return out.data();
    } else {
      return up_room<T>(out.size());
    }
  }
  // A device's take_owned result, from up_ into out.
  template <class T>
  void owned_down(std::vector<T>& out, const T* at) {
    if (S != Space::Host && !out.empty())
      space_copy(out.data(), Space::Host, at, S, sizeof(T) * out.size());
  }

 private:
  // pick_ = the owned particles (slot < n_own_), in local order; a device stage's also there
  // (picked_).
  void pick_owned() {
    const std::int64_t* slot = host_readable(slot_.cview().p, n_);
    const std::int64_t nown = n_own_;
    select_indices(
        HostExec{}, n_, [&](std::int64_t i) { return slot[i] < nown; }, pick_);
    if constexpr (S != Space::Host) picked_.assign(pick_);
  }
  // The n entries at p where the host reads them: p itself, or a host copy of a device array.
  template <class T>
  const T* host_readable(const T* p, std::int64_t n) {
    if constexpr (S == Space::Host) {
      return p;
    } else {
      staging_.resize(sizeof(T) * n);
      space_copy(staging_.data(), Space::Host, p, S, sizeof(T) * n);
      return reinterpret_cast<const T*>(staging_.data());
    }
  }

  // The rank's particles, all owned, each in its own layout slot (slot = index).
  void set_owned(const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                 const std::vector<double>& rho, const std::vector<double>& m,
                 const std::vector<std::uint8_t>& type, const std::vector<std::uint64_t>& gid,
                 const std::vector<std::uint64_t>& key) {
    size_for(type);
    n_own_ = n_;
    x_.assign(x);
    v_.assign(v);
    rho_.assign(rho);
    m_.assign(m);
    type_.assign(type);
    gid_.assign(gid);
    key_.assign(key);
    std::vector<std::int64_t> index(x.size());
    std::iota(index.begin(), index.end(), std::int64_t{0});
    slot_.assign(index);
    laid_out_ = false;
  }
  // The counts of particles of these types, and the per-step arrays (not carried) sized to them.
  void size_for(const std::vector<std::uint8_t>& type) {
    n_ = static_cast<std::int64_t>(type.size());
    nf_ = std::count(type.begin(), type.end(), std::uint8_t{kSphFluid});
    nml_ = std::count(type.begin(), type.end(), std::uint8_t{kSphSolid});
    a_.resize(n_);
    p_.resize(n_);
    drho_.resize(n_);
    pr_.resize(n_);
  }

  SphParams P_;
  std::int64_t n_global_ = 0, nf_global_ = 0;  // particles and fluid particles of all ranks
  std::int64_t nm_ = 0;                        // markers of all ranks
  std::int64_t n_ = 0, nf_ = 0;                // this rank's, ghosts included
  std::int64_t nml_ = 0;                       // this rank's markers, ghosts included
  std::int64_t n_own_ = 0;                     // this rank's owned particles
  bool laid_out_ = false;    // distributed: the exchange's layout is this rank's particles
  bool setting_up_ = false;  // in the constructor's compute()
  double pending_dt_ = 0;    // time drifted since the last compute(): the density update's dt
  double wall_volume_ = 0;   // dx^3
  Vec3Buffer x_{S}, v_{S}, a_{S}, tmp3_{S};
  Buffer<double> rho_{S}, p_{S}, drho_{S}, m_{S}, tmpd_{S};
  Vec3Buffer x0_{S};         // distributed: owned positions at the last redistribute(), by slot
  Buffer<double> reach_{S};  // distributed: how far each may move from there (FluidExchange)
  Buffer<std::uint8_t> depth_{S};  // distributed: its band cell's depth, by slot (FluidExchange)
  // Distributed: the owned fluid particles no ghost is near, then those near ghosts, then the
  // ghosts, in the last sort's order (over_fluid; near_start_: where each kind starts).
  Buffer<std::int64_t> near_order_{S}, near_start_{S};
  std::int64_t n_fluid_near_ = 0, n_fluid_far_ = 0;  // their counts, the layout's
  DeviceMark packed_;     // distributed, on a GPU: a refresh's records are packed
  DeviceMark forces_;     // distributed, on a GPU: the side stream's force pass is done
  Buffer<double> pr_{S};  // p / rho^2 of this step (set after the sort, not carried over)
  Buffer<std::uint8_t> type_{S}, tmpt_{S};
  Buffer<std::uint64_t> gid_{S}, key_{S}, tmpu_{S};
  Buffer<std::int64_t> slot_{S}, tmpi_{S};
  Buffer<std::int64_t> send_{S};  // distributed: the layout slots whose records go out
  Buffer<std::int64_t> inv_{S};   // distributed: the particle in each layout slot (last sort)
  Buffer<double> pack_{S};        // distributed, on a device: the records sent and received
  Buffer<double> cost_{S};        // distributed: each particle's cost in the last compute()
  // Distributed, on a device: the owned particles (pick_), and a field of q on its way
  // (take_owned(), gather_layout()).
  Buffer<std::int64_t> picked_{S};
  Buffer<double> up_{S};
  CellGrid grid_all_;  // the whole fluid box
  CellGrid grid_;      // the cells searched: the whole box, or a rank's window of it
  Buffer<std::int64_t> keys_{S}, start_{S}, order_{S}, scratch_{S};
  // Distributed: redistribute()'s host work arrays, kept so that a rebuild reuses their storage.
  FluidParticles q_;                // the owned particles out, this rank's particles back
  std::vector<std::int64_t> pick_;  // the owned particles' indices (pick_owned())
  // Distributed: save_state()'s records of every rank's particles by key.
  std::vector<std::pair<std::uint64_t, std::int64_t>> by_key_, by_key_scratch_;
  StagingBytes staging_;                           // a GPU stage's slots copied out (pick_owned())
  std::unique_ptr<SolidCoupling<Exec>> coupling_;  // null without bodies
  std::unique_ptr<FluidExchange> ex_;              // null on one rank
  // Distributed: the layout's upkeep inside compute(): "sph.halo" (the skin test and the host's
  // part of the ghost refreshes; of it "sph.halo.skin" the test, "sph.halo.mpi" the refreshes'
  // exchanges, without packing and unpacking; while a GPU runs the passes over particles no
  // ghost is near, the time its host waits in an exchange counts here), "sph.rebuild"
  // (redistribute(): migration and the new ghost layout, after a load_state too), "sph.setup"
  // (the first layout, in the constructor: not a step's); each scope starts after the work
  // before it is done, so the passes' device work queued earlier is not counted in it. One
  // rank times nothing here (no synchronisation added).
  PhaseTimers timers_{[] { exec_sync(Exec{}); }};
};

}  // namespace qdemsph
