// WCSPH fluid stage written once over an execution space (HostExec, CudaExec).
//
// Data (SoA, n = fluid + wall particles, kept sorted by cell: re-sorted at every compute() by a
// counting sort, so the 27-cell neighbour ranges are contiguous and memory access is local):
//   x, v, a (Vec3 buffers), rho, p, drho, m (double), type (uint8: fluid / wall), gid (uint64).
// Wall particles are fixed; their p and rho come from the fluid by Adami extrapolation.
//
// Per pair evaluation (fluid-fluid): ~150 flops, reads 2 x 9 doubles; per particle and step
// ~3 passes over ~75 neighbours (Wendland C2 at h = 1.3 dx, support 2h).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/error_flag.hpp"
#include "core/memory.hpp"
#include "neighbor/cell_grid.hpp"
#include "physics/sph_boundary.hpp"
#include "physics/sph_pair.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph {

template <class Exec>
class SphStage final : public FluidStage {
  static constexpr Space S = Exec::space;

 public:
  explicit SphStage(const FluidSetup& f) : P_(f.params), n_(f.size()), nf_(f.n_fluid) {
    x_.assign(f.x);
    v_.assign(f.v);
    a_.resize(n_);
    rho_.assign(f.rho);
    p_.assign(f.p);
    drho_.resize(n_);
    m_.assign(f.m);
    type_.assign(f.type);
    gid_.assign(f.gid);
    cells_.set_grid(CellGrid::cover(f.lo, f.hi, P_.kernel.support()));
    compute();
  }

  void kick(double h) override {
    const auto a = a_.cview();
    const auto type = type_.cview();
    const auto v = v_.view();
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      if (type[i] == kSphFluid) v.set(i, v[i] + h * a[i]);
    });
  }

  void drift(double h) override {
    const auto v = v_.cview();
    const auto type = type_.cview();
    const auto x = x_.view();
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      if (type[i] == kSphFluid) x.set(i, x[i] + h * v[i]);
    });
    pending_dt_ += h;
  }

  void compute() override {
    sort();
    const SphParams P = P_;
    const CellGrid g = cells_.grid();
    const std::int64_t* start = cells_.start().p;
    const auto x = x_.cview(), v = v_.cview();
    const auto type = type_.cview();
    const auto m = m_.cview();
    const auto rho = rho_.view();
    const auto p = p_.view();
    const auto drho = drho_.view();
    // Density rate at the drifted positions and half-step velocities (continuity + delta-SPH),
    // then rho_{n+1} = rho_n + dt drho: the pressure is taken at the same time as the positions
    // (a density lagging half a step behind the positions makes the acoustic modes grow).
    const double ddt = pending_dt_;
    pending_dt_ = 0;
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      if (type[i] != kSphFluid) {
        drho[i] = 0.0;
        return;
      }
      const PairState si{x[i], v[i], rho[i], 0.0, m[i]};
      double dr = 0;
      for_each_near(g, start, si.x, [&](std::int64_t j) {
        if (j == i) return;
        const PairState sj{x[j], v[j], rho[j], 0.0, m[j]};
        dr += sph_continuity(P, si, sj);
        if (type[j] == kSphFluid) dr += sph_density_diffusion(P, si, sj);
      });
      drho[i] = dr;
    });
    // Equation of state (fluid). Walls keep the density Adami gives them below.
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      if (type[i] != kSphFluid) return;
      rho[i] += ddt * drho[i];
      p[i] = P.eos.pressure(rho[i]);
    });
    // Wall pressure and density by extrapolation from the fluid (fixed walls: a_w = 0).
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      if (type[i] == kSphFluid) return;
      const Vec3 xi = x[i];
      AdamiSum s;
      for_each_near(g, start, xi, [&](std::int64_t j) {
        if (type[j] == kSphFluid) adami_add(s, P.kernel, xi, x[j], p[j], rho[j]);
      });
      const double pw = adami_pressure(s, P.gravity, Vec3{});
      p[i] = pw;
      rho[i] = P.eos.density(pw);
    });
    // Pair sums: acceleration of fluid particles.
    const auto a = a_.view();
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      if (type[i] != kSphFluid) {
        a.set(i, Vec3{});
        return;
      }
      const PairState si{x[i], v[i], rho[i], p[i], m[i]};
      Vec3 f{};
      for_each_near(g, start, si.x, [&](std::int64_t j) {
        if (j == i) return;
        const PairState sj{x[j], v[j], rho[j], p[j], m[j]};
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
    s.kinetic = reduce_sum(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      return type[i] == kSphFluid ? 0.5 * m[i] * norm2(v[i]) : 0.0;
    });
    for (int c = 0; c < 3; ++c)
      s.momentum[c] = reduce_sum(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
        return type[i] == kSphFluid ? m[i] * v[i][c] : 0.0;
      });
    s.v_max = reduce_max(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      return type[i] == kSphFluid ? norm(v[i]) : 0.0;
    }, 0.0);
    s.a_max = reduce_max(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      return type[i] == kSphFluid ? norm(a[i]) : 0.0;
    }, 0.0);
    s.rho_dev = reduce_max(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      return type[i] == kSphFluid ? fabs(rho[i] / rho0 - 1.0) : 0.0;
    }, 0.0);
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
    const double r = reduce_max(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) {
      const double s = x.x[i] + x.y[i] + x.z[i] + v.x[i] + v.y[i] + v.z[i] + rho[i];
      return is_finite(s) ? 0.0 : static_cast<double>(gid[i] + 1);
    }, 0.0);
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

  std::int64_t size() const override { return n_; }
  std::int64_t n_fluid() const override { return nf_; }
  const SphParams& params() const override { return P_; }
  std::size_t device_bytes() const override {
    return x_.bytes() + v_.bytes() + a_.bytes() + rho_.bytes() + p_.bytes() + drho_.bytes() +
           m_.bytes() + type_.bytes() + gid_.bytes() + tmp3_.bytes() + tmpd_.bytes() +
           tmpu_.bytes() + tmpt_.bytes() + cells_.bytes();
  }

 private:
  // Counting sort by cell, then every per-particle array gathered into the new order.
  void sort() {
    cells_.build(x_.cview());
    const auto ord = cells_.order();
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
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst[i] = src[ord[i]]; });
    b.swap(tmp);
  }
  void permute3(Vec3Buffer& b, View<const std::int64_t> ord) {
    if (tmp3_.size() != n_) tmp3_.resize(n_);
    const auto src = b.cview();
    const auto dst = tmp3_.view();
    for_each(Exec{}, n_, QDEMSPH_LAMBDA(std::int64_t i) { dst.set(i, src[ord[i]]); });
    std::swap(b, tmp3_);
  }

  SphParams P_;
  std::int64_t n_ = 0, nf_ = 0;
  double pending_dt_ = 0;  // time drifted since the last compute(): the density update's dt
  Vec3Buffer x_{S}, v_{S}, a_{S}, tmp3_{S};
  Buffer<double> rho_{S}, p_{S}, drho_{S}, m_{S}, tmpd_{S};
  Buffer<std::uint8_t> type_{S}, tmpt_{S};
  Buffer<std::uint64_t> gid_{S}, tmpu_{S};
  CellList<Exec> cells_;
};

}  // namespace qdemsph
