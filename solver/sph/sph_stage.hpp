// WCSPH fluid stage written once over an execution space (HostExec, CudaExec).
//
// Data (SoA, n = fluid + wall particles, kept sorted by (cell, type): re-sorted at every
// compute() by a counting sort, so neighbour ranges are contiguous, memory access is local and
// the wall-pressure pass visits fluid particles only):
//   x, v, a (Vec3 buffers), rho, p, drho, m (double), type (uint8: fluid / wall), gid (uint64).
// Wall particles are fixed; their p and rho come from the fluid by Adami extrapolation.
//
// Per pair evaluation (fluid-fluid): ~150 flops, reads 2 x 9 doubles; per particle and step
// ~3 passes over ~75 neighbours (Wendland C2 at h = 1.3 dx, support 2h).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/error_flag.hpp"
#include "core/memory.hpp"
#include "neighbor/cell_grid.hpp"
#include "physics/sph_boundary.hpp"
#include "physics/sph_pair.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph {

// Neighbour ranges over arrays sorted by (cell, type): the particles of cell c are
// [start[2c], start[2c+2]), its fluid particles [start[2c], start[2c+1]). Calls f(j) for every
// particle (fluid_only: every fluid particle) in the 27 cells around p.
template <class F>
QDEMSPH_HD void sph_for_each_near(const CellGrid& g, const std::int64_t* start, Vec3 p,
                                  bool fluid_only, F&& f) {
  const int cx = g.coord(p.x, 0), cy = g.coord(p.y, 1), cz = g.coord(p.z, 2);
  const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx + 1 < g.n[0] ? cx + 1 : g.n[0] - 1;
  for (int z = cz - 1; z <= cz + 1; ++z) {
    if (z < 0 || z >= g.n[2]) continue;
    for (int y = cy - 1; y <= cy + 1; ++y) {
      if (y < 0 || y >= g.n[1]) continue;
      const std::int64_t row = g.key(0, y, z);
      if (fluid_only) {
        for (std::int64_t c = row + x0; c <= row + x1; ++c)
          for (std::int64_t j = start[2 * c]; j < start[2 * c + 1]; ++j) f(j);
      } else {
        for (std::int64_t j = start[2 * (row + x0)]; j < start[2 * (row + x1 + 1)]; ++j) f(j);
      }
    }
  }
}

template <class Exec>
class SphStage final : public FluidStage {
  static constexpr Space S = Exec::space;

 public:
  explicit SphStage(const FluidSetup& f)
      : P_(f.params), n_(f.size()), nf_(f.n_fluid), wall_volume_(f.dx * f.dx * f.dx) {
    x_.assign(f.x);
    v_.assign(f.v);
    a_.resize(n_);
    rho_.assign(f.rho);
    p_.assign(f.p);
    drho_.resize(n_);
    m_.assign(f.m);
    type_.assign(f.type);
    gid_.assign(f.gid);
    grid_ = CellGrid::cover(f.lo, f.hi, P_.kernel.support());
    start_.resize(2 * grid_.count() + 1);
    compute();
  }

  void kick(double h) override {
    const auto a = a_.cview();
    const auto type = type_.cview();
    const auto v = v_.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] == kSphFluid) v.set(i, v[i] + h * a[i]);
        });
  }

  void drift(double h) override {
    const auto v = v_.cview();
    const auto type = type_.cview();
    const auto x = x_.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] == kSphFluid) x.set(i, x[i] + h * v[i]);
        });
    pending_dt_ += h;
  }

  void compute() override {
    sort();
    const SphParams P = P_;
    const CellGrid g = grid_;
    const std::int64_t* start = start_.cview().p;
    const auto x = x_.cview(), v = v_.cview();
    const auto type = type_.cview();
    const auto m = m_.view();
    const double wall_volume = wall_volume_;
    const auto rho = rho_.view();
    const auto p = p_.view();
    const auto drho = drho_.view();
    // Density rate at the drifted positions and half-step velocities (continuity + delta-SPH),
    // then rho_{n+1} = rho_n + dt drho: the pressure is taken at the same time as the positions
    // (a density lagging half a step behind the positions makes the acoustic modes grow).
    const double ddt = pending_dt_;
    pending_dt_ = 0;
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] != kSphFluid) {
            drho[i] = 0.0;
            return;
          }
          const PairState si{x[i], v[i], rho[i], 0.0, m[i]};
          double dr = 0;
          const double s2 = P.kernel.support2;
          sph_for_each_near(g, start, si.x, false, [&](std::int64_t j) {
            const Vec3 xj = x[j];
            if (j == i || norm2(si.x - xj) >= s2) return;  // most candidates: no further loads
            const PairState sj{xj, v[j], rho[j], 0.0, m[j]};
            dr += sph_continuity(P, si, sj);
            if (type[j] == kSphFluid) dr += sph_density_diffusion(P, si, sj);
          });
          drho[i] = dr;
        });
    // Equation of state (fluid). Walls keep the density Adami gives them below.
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] != kSphFluid) return;
          rho[i] += ddt * drho[i];
          p[i] = P.eos.pressure(rho[i]);
        });
    // Wall pressure and density by extrapolation from the fluid (fixed walls: a_w = 0).
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] == kSphFluid) return;
          const Vec3 xi = x[i];
          AdamiSum s;
          sph_for_each_near(g, start, xi, true, [&](std::int64_t j) {
            adami_add(s, P.kernel, xi, x[j], p[j], rho[j]);
          });
          const double pw = adami_pressure(s, P.gravity, Vec3{});
          p[i] = pw;
          rho[i] = P.eos.density(pw);
          m[i] = rho[i] * wall_volume;  // a wall particle keeps its volume dx^3
        });
    // Pair sums: acceleration of fluid particles.
    const auto a = a_.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] != kSphFluid) {
            a.set(i, Vec3{});
            return;
          }
          const PairState si{x[i], v[i], rho[i], p[i], m[i]};
          Vec3 f{};
          const double s2 = P.kernel.support2;
          sph_for_each_near(g, start, si.x, false, [&](std::int64_t j) {
            const Vec3 xj = x[j];
            if (j == i || norm2(si.x - xj) >= s2) return;
            const PairState sj{xj, v[j], rho[j], p[j], m[j]};
            f += sph_pair_force(P, si, sj, type[j] == kSphFluid || P.wall_viscosity);
          });
          a.set(i, P.gravity + f / si.m);
        });
  }

  FluidStats stats() override {
    const auto v = v_.cview(), a = a_.cview();
    const auto m = m_.cview(), rho = rho_.cview();
    const auto type = type_.cview();
    const double rho0 = P_.eos.rho0;
    FluidStats s;
    s.kinetic = reduce_sum(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          return type[i] == kSphFluid ? 0.5 * m[i] * norm2(v[i]) : 0.0;
        });
    for (int c = 0; c < 3; ++c)
      s.momentum[c] = reduce_sum(
          Exec{}, n_,
          QDEMSPH_LAMBDA(std::int64_t i) { return type[i] == kSphFluid ? m[i] * v[i][c] : 0.0; });
    s.v_max = reduce_max(
        Exec{}, n_,
        QDEMSPH_LAMBDA(std::int64_t i) { return type[i] == kSphFluid ? norm(v[i]) : 0.0; }, 0.0);
    s.a_max = reduce_max(
        Exec{}, n_,
        QDEMSPH_LAMBDA(std::int64_t i) { return type[i] == kSphFluid ? norm(a[i]) : 0.0; }, 0.0);
    s.rho_dev = reduce_max(
        Exec{}, n_,
        QDEMSPH_LAMBDA(std::int64_t i) {
          return type[i] == kSphFluid ? fabs(rho[i] / rho0 - 1.0) : 0.0;
        },
        0.0);
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
    const double r = reduce_max(
        Exec{}, n_,
        QDEMSPH_LAMBDA(std::int64_t i) {
          const double s = x.x[i] + x.y[i] + x.z[i] + v.x[i] + v.y[i] + v.z[i] + rho[i];
          return is_finite(s) ? 0.0 : static_cast<double>(gid[i] + 1);
        },
        0.0);
    return static_cast<std::int64_t>(r) - 1;
  }

  FluidHost download() override {
    FluidHost h;
    h.x = x_.to_host();
    h.v = v_.to_host();
    h.rho = rho_.to_host();
    h.p = p_.to_host();
    h.type = type_.to_host();
    h.gid = gid_.to_host();
    return h;
  }

  FluidState save_state() override {
    FluidState s;
    s.x = x_.to_host();
    s.v = v_.to_host();
    s.a = a_.to_host();
    s.rho = rho_.to_host();
    s.p = p_.to_host();
    s.m = m_.to_host();
    s.type = type_.to_host();
    s.gid = gid_.to_host();
    return s;
  }

  void load_state(const FluidState& s) override {
    const auto n = static_cast<std::size_t>(n_);
    if (s.x.size() != n || s.v.size() != n || s.a.size() != n || s.rho.size() != n ||
        s.p.size() != n || s.m.size() != n || s.type.size() != n || s.gid.size() != n)
      throw InputError("fluid state does not fit the scene (particle count)");
    x_.assign(s.x);
    v_.assign(s.v);
    a_.assign(s.a);
    rho_.assign(s.rho);
    p_.assign(s.p);
    m_.assign(s.m);
    type_.assign(s.type);
    gid_.assign(s.gid);
    pending_dt_ = 0;
  }

  std::int64_t size() const override { return n_; }
  std::int64_t n_fluid() const override { return nf_; }
  const SphParams& params() const override { return P_; }
  std::size_t device_bytes() const override {
    return x_.bytes() + v_.bytes() + a_.bytes() + rho_.bytes() + p_.bytes() + drho_.bytes() +
           m_.bytes() + type_.bytes() + gid_.bytes() + tmp3_.bytes() + tmpd_.bytes() +
           tmpu_.bytes() + tmpt_.bytes() + keys_.bytes() + start_.bytes() + order_.bytes() +
           scratch_.bytes();
  }

  // Public only because nvcc's extended lambdas need an accessible enclosing function.
  // Stable sort by (cell, type) (sort_by_key, neighbor/cell_grid.hpp), then every per-particle
  // array gathered into the new order.
  void sort() {
    if (keys_.size() != n_) keys_.resize(n_);
    const auto k = keys_.view();
    const auto x = x_.cview();
    const auto type = type_.cview();
    const CellGrid g = grid_;
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
          k[i] = 2 * g.key_of(x[i]) + (type[i] == kSphFluid ? 0 : 1);
        });
    if (order_.size() != n_) order_.resize(n_);
    sort_by_key(Exec{}, keys_.cview(), 2 * grid_.count(), start_.view(), order_.view(), scratch_);
    const auto ord = order_.cview();
    permute3(x_, ord);
    permute3(v_, ord);
    permute3(a_, ord);
    permute(rho_, tmpd_, ord);
    permute(p_, tmpd_, ord);
    permute(drho_, tmpd_, ord);
    permute(m_, tmpd_, ord);
    permute(type_, tmpt_, ord);
    permute(gid_, tmpu_, ord);
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
  void permute3(Vec3Buffer& b, View<const std::int64_t> ord) {
    if (tmp3_.size() != n_) tmp3_.resize(n_);
    const auto src = b.cview();
    const auto dst = tmp3_.view();
    for_each(
        Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst.set(i, src[ord[i]]); });
    std::swap(b, tmp3_);
  }

 private:
  SphParams P_;
  std::int64_t n_ = 0, nf_ = 0;
  double pending_dt_ = 0;
  double wall_volume_ =
      0;  // dx^3  // time drifted since the last compute(): the density update's dt
  Vec3Buffer x_{S}, v_{S}, a_{S}, tmp3_{S};
  Buffer<double> rho_{S}, p_{S}, drho_{S}, m_{S}, tmpd_{S};
  Buffer<std::uint8_t> type_{S}, tmpt_{S};
  Buffer<std::uint64_t> gid_{S}, tmpu_{S};
  CellGrid grid_;
  Buffer<std::int64_t> keys_{S}, start_{S}, order_{S}, scratch_{S};
};

}  // namespace qdemsph
