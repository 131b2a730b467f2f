// Two-way QDEM-SPH coupling, written once over an execution space (the SPH stage owns one when
// the scene has bodies and fluid). Markers (sph/solid_markers.hpp) are boundary particles of the
// SPH stage embedded in the bodies' tets.
//
// place(): x_m = sum_c w_c x_{v_c} from the body's vertices; the marker's velocity is its
//   displacement over the fluid step, v_m = (x_m^{n+1} - x_m^n) / H (the body's mean velocity
//   over the step, the same half-step velocity the fluid's continuity equation uses). With H = 0
//   (the first evaluation) v_m interpolates the vertex velocities.
//   The Adami pressure of a marker uses gravity but not the body's acceleration: with a light
//   body (the elastic gate: water's added mass ~6 x its own) the acceleration term feeds the
//   body's response back into the wall pressure within one fluid step and the coupling blows
//   up (3.5 x the hydrostatic force after 5 ms); without it the fluid's reaction reaches the
//   body through the continuity equation and the force falls to m / (m + m_added) of the
//   hydrostatic one at the release, as added-mass theory says.
// apply(): the fluid's force on each marker F_m (the exact negative of the marker's pair forces
//   on the fluid, sph_stage.hpp) is gathered to the vertices, F_v = sum_m w_mv F_m, in a fixed
//   order (vertex -> marker CSR, no atomics), and handed to the body as its coupling force fc.
//
// Time integration with sub-cycling (integrate/stepper.cpp): the body takes k steps of H/k
// during one fluid step H with fc = F^n held constant, then apply() at t_{n+1} adds the
// velocity correction v += (H/2) (F^{n+1} - F^n) / m and sets f += F^{n+1} - F^n, fc = F^{n+1}.
// The body's coupling impulse over the step is H F^n + (H/2)(F^{n+1} - F^n) = (H/2)(F^n +
// F^{n+1}), exactly minus the fluid's (its two half kicks), so fluid + body momentum is conserved
// to round-off; with k = 1 the scheme is the shared velocity Verlet (Fourey et al. 2017, J.
// Fluids Struct. 70, conservative sub-cycling of an SPH-FE coupling).
//
// Distributed (docs/parallel.md, item 8): the SolidViews are whole-model arrays with a SolidSync;
// place() pulls the coupled vertices' x, v first, the stage sums the marker forces over the
// ranks, and apply() pushes the owned vertices' f, v, fc after gathering them as one rank does.
//
// Data: marker topology tv[c * nm + k], w[c * nm + k] (SoA); per-vertex CSR over coupled vertices.
#pragma once

#include <cstdint>

#include "core/error.hpp"
#include "core/memory.hpp"
#include "integrate/backend.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/solid_markers.hpp"

namespace qdemsph {

template <class Exec>
class SolidCoupling {
  static constexpr Space S = Exec::space;

 public:
  SolidCoupling(const SolidMarkers& m, std::uint64_t gid0, const SolidViews& solid)
      : nm_(m.size()), gid0_(gid0), solid_(solid) {
    if (solid.space != S)
      throw InputError("the fluid and the bodies must run on the same backend to be coupled");
    std::vector<std::int32_t> tv(4 * nm_);
    std::vector<double> w(4 * nm_);
    for (std::int64_t k = 0; k < nm_; ++k)
      for (int c = 0; c < 4; ++c) {
        tv[c * nm_ + k] = m.tv[k][c];
        w[c * nm_ + k] = m.w[k][c];
      }
    tv_.assign(tv);
    w_.assign(w);
    vol_.assign(m.volume);
    force_.resize(nm_);
    nv_ = static_cast<std::int64_t>(m.vertices.size());
    cv_.assign(m.vertices);
    off_.assign(m.offset);
    em_.assign(m.entry_marker);
    ew_.assign(m.entry_weight);
    if (solid.sync) vertices_ = m.vertices;
  }

  std::int64_t size() const { return nm_; }
  std::uint64_t gid0() const { return gid0_; }
  View<const double> volume() const { return vol_.cview(); }
  Vec3View force() { return force_.view(); }

  // Markers are the stage's particles of type kSphSolid among [0, n) (marker index = gid - gid0).
  void place(Vec3View x, Vec3View v, View<const std::uint64_t> gid, View<const std::uint8_t> type,
             std::int64_t n, double H) {
    if (solid_.sync) solid_.sync->pull(vertices_);
    const std::int64_t nm = nm_;
    const std::uint64_t g0 = gid0_;
    const auto tv = tv_.cview();
    const auto w = w_.cview();
    const Vec3CView xs = solid_.x;
    const Vec3CView vs{solid_.v.x, solid_.v.y, solid_.v.z, solid_.v.n};
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t i) {
          if (type[i] != kSphSolid) return;
          const std::int64_t k = static_cast<std::int64_t>(gid[i] - g0);
          Vec3 xn{}, vn{};
          for (int c = 0; c < 4; ++c) {
            const std::int32_t vi = tv[c * nm + k];
            const double wc = w[c * nm + k];
            xn += wc * xs[vi];
            vn += wc * vs[vi];
          }
          v.set(i, H > 0 ? (xn - x[i]) / H : vn);
          x.set(i, xn);
        });
  }

  // Gathers the marker forces to the vertices and hands them to the body (header comment).
  void apply(double H) {
    const auto off = off_.cview();
    const auto cv = cv_.cview();
    const auto em = em_.cview();
    const auto ew = ew_.cview();
    const Vec3CView F = force_.cview();
    const SolidViews s = solid_;
    const double hh = 0.5 * H;
    for_each(
        Exec{}, nv_, QDEMSPH_LAMBDA(std::int64_t j) {
          Vec3 fn{};
          for (std::int64_t e = off[j]; e < off[j + 1]; ++e) fn += ew[e] * F[em[e]];
          const std::int32_t vi = cv[j];
          const Vec3 d = fn - s.fc[vi];
          s.fc.set(vi, fn);
          s.f.set(vi, s.f[vi] + d);
          const double im = s.inv_mass[vi];
          if (im > 0) s.v.set(vi, s.v[vi] + unheld((hh * im) * d, s.held[vi]));
        });
    if (solid_.sync) solid_.sync->push(vertices_);
  }

  // Total fluid force on the bodies [N] (sum over markers).
  Vec3 total_force() const {
    const Vec3CView F = force_.cview();
    Vec3 t;
    const double* c[3] = {F.x, F.y, F.z};
    for (int a = 0; a < 3; ++a) {
      const double* p = c[a];
      t[a] = reduce_sum(
          Exec{}, nm_, QDEMSPH_LAMBDA(std::int64_t k) { return p[k]; });
    }
    return t;
  }

  std::size_t bytes() const {
    return tv_.bytes() + w_.bytes() + vol_.bytes() + force_.bytes() + cv_.bytes() + off_.bytes() +
           em_.bytes() + ew_.bytes();
  }

 private:
  std::int64_t nm_ = 0, nv_ = 0;
  std::uint64_t gid0_ = 0;
  SolidViews solid_;
  Buffer<std::int32_t> tv_{S}, cv_{S}, em_{S};
  Buffer<double> w_{S}, vol_{S}, ew_{S};
  Buffer<std::int64_t> off_{S};
  Vec3Buffer force_{S};
  std::vector<std::int32_t> vertices_;  // distributed: the coupled vertices (host copy of cv_)
};

}  // namespace qdemsph
