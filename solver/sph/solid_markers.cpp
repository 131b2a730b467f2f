#include "sph/solid_markers.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.hpp"
#include "model/model.hpp"

namespace qdemsph {
namespace {

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5): the
// distance from a lattice point to a surface triangle.
double point_triangle_distance(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return norm(p - a);
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return norm(p - b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return norm(p - (a + (d1 / (d1 - d3)) * ab));
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return norm(p - c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return norm(p - (a + (d2 / (d2 - d6)) * ac));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return norm(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)));
  const double den = 1.0 / (va + vb + vc);
  return norm(p - (a + (vb * den) * ab + (vc * den) * ac));
}

// The body's lattice: n[a] points per axis at lo + (i + 1/2) pitch[a].
struct Lattice {
  Vec3 lo{}, pitch{};
  std::array<int, 3> n{};
  std::int64_t index(int i, int j, int k) const {
    return (static_cast<std::int64_t>(k) * n[1] + j) * n[0] + i;
  }
  Vec3 point(int i, int j, int k) const {
    return {lo.x + (i + 0.5) * pitch.x, lo.y + (j + 0.5) * pitch.y, lo.z + (k + 0.5) * pitch.z};
  }
  // Index range of the points inside [a, b] along axis ax.
  std::array<int, 2> range(double a, double b, int ax) const {
    const int i0 = static_cast<int>(std::ceil((a - lo[ax]) / pitch[ax] - 0.5));
    const int i1 = static_cast<int>(std::floor((b - lo[ax]) / pitch[ax] - 0.5));
    return {std::max(i0, 0), std::min(i1, n[ax] - 1)};
  }
};

}  // namespace

SolidMarkers build_solid_markers(const Model& model, double dx, double support) {
  SolidMarkers out;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodyRange& body = model.bodies[b];
    Vec3 lo = model.X[body.v_begin], hi = lo;
    for (std::int64_t i = body.v_begin; i < body.v_end; ++i)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], model.X[i][a]);
        hi[a] = std::max(hi[a], model.X[i][a]);
      }
    Lattice L;
    L.lo = lo;
    for (int a = 0; a < 3; ++a) {
      L.n[a] = std::max(1, static_cast<int>(std::lround((hi[a] - lo[a]) / dx)));
      L.pitch[a] = (hi[a] - lo[a]) / L.n[a];
      // One layer of markers cannot hold the fluid: its kernel misses most of the wall, the
      // fluid beside it accelerates into the body and the pressure spikes (a 5 mm gate at
      // dx = 5 mm was thrown open at 8 m/s).
      if (L.n[a] < 2)
        throw InputError(fmt::format(
            "body '{}' is {:.4g} m thick along {}: one fluid boundary marker layer at "
            "fluid.spacing = {:.4g} m, which does not hold the fluid back; use a spacing of at "
            "most half the body's thickness ({:.4g} m)",
            body.name, hi[a] - lo[a], "xyz"[a], dx, 0.5 * (hi[a] - lo[a])));
    }
    const std::int64_t np = static_cast<std::int64_t>(L.n[0]) * L.n[1] * L.n[2];
    // Embed every lattice point in the first tet that contains it (barycentric >= -tol).
    std::vector<std::int32_t> tet(np, -1);
    std::vector<std::array<double, 4>> bary(np);
    for (std::int64_t t = body.t_begin; t < body.t_end; ++t) {
      const auto& tv = model.tets[t];
      Vec3 tlo = model.X[tv[0]], thi = tlo;
      for (int c = 1; c < 4; ++c)
        for (int a = 0; a < 3; ++a) {
          tlo[a] = std::min(tlo[a], model.X[tv[c]][a]);
          thi[a] = std::max(thi[a], model.X[tv[c]][a]);
        }
      const double tol = 1e-9;
      const auto ri = L.range(tlo.x - tol * dx, thi.x + tol * dx, 0);
      const auto rj = L.range(tlo.y - tol * dx, thi.y + tol * dx, 1);
      const auto rk = L.range(tlo.z - tol * dx, thi.z + tol * dx, 2);
      for (int k = rk[0]; k <= rk[1]; ++k)
        for (int j = rj[0]; j <= rj[1]; ++j)
          for (int i = ri[0]; i <= ri[1]; ++i) {
            const std::int64_t q = L.index(i, j, k);
            if (tet[q] >= 0) continue;
            const Vec3 l = model.dX_inv[t] * (L.point(i, j, k) - model.X[tv[0]]);
            const double l0 = 1.0 - l.x - l.y - l.z;
            if (l0 < -tol || l.x < -tol || l.y < -tol || l.z < -tol) continue;
            tet[q] = static_cast<std::int32_t>(t);
            bary[q] = {l0, l.x, l.y, l.z};
          }
    }
    // Depth below the surface: the distance to the nearest surface triangle of the body.
    std::vector<double> depth(np, std::numeric_limits<double>::infinity());
    for (std::size_t s = 0; s < model.surface.size(); ++s) {
      if (model.surface_body[s] != static_cast<std::int32_t>(b)) continue;
      const auto& tri = model.surface[s].v;
      const Vec3 p0 = model.X[tri[0]], p1 = model.X[tri[1]], p2 = model.X[tri[2]];
      std::array<int, 2> r[3];
      for (int a = 0; a < 3; ++a)
        r[a] = L.range(std::min({p0[a], p1[a], p2[a]}) - support,
                       std::max({p0[a], p1[a], p2[a]}) + support, a);
      for (int k = r[2][0]; k <= r[2][1]; ++k)
        for (int j = r[1][0]; j <= r[1][1]; ++j)
          for (int i = r[0][0]; i <= r[0][1]; ++i) {
            const std::int64_t q = L.index(i, j, k);
            if (tet[q] < 0) continue;
            depth[q] = std::min(depth[q], point_triangle_distance(L.point(i, j, k), p0, p1, p2));
          }
    }
    const std::int64_t before = out.size();
    const double vol = L.pitch.x * L.pitch.y * L.pitch.z;
    for (int k = 0; k < L.n[2]; ++k)
      for (int j = 0; j < L.n[1]; ++j)
        for (int i = 0; i < L.n[0]; ++i) {
          const std::int64_t q = L.index(i, j, k);
          if (tet[q] < 0 || !(depth[q] < support)) continue;
          out.x.push_back(L.point(i, j, k));
          const auto& tv = model.tets[tet[q]];
          out.tv.push_back({tv[0], tv[1], tv[2], tv[3]});
          out.w.push_back(bary[q]);
          out.volume.push_back(vol);
          out.body.push_back(static_cast<std::int32_t>(b));
        }
    if (out.size() == before)
      throw InputError(fmt::format(
          "body '{}': no fluid boundary marker inside it at the fluid spacing {:.4g} m (the body "
          "is too thin or not a closed volume); refine fluid.spacing",
          body.name, dx));
  }
  // Vertex -> (marker, weight) CSR, entries in increasing marker order.
  const std::int64_t nv = model.n_vertices();
  std::vector<std::int64_t> count(nv + 1, 0);
  for (const auto& tv : out.tv)
    for (int c = 0; c < 4; ++c) ++count[tv[c] + 1];
  std::vector<std::int64_t> slot(nv, -1);
  out.offset.push_back(0);
  for (std::int64_t v = 0; v < nv; ++v)
    if (count[v + 1] > 0) {
      slot[v] = static_cast<std::int64_t>(out.vertices.size());
      out.vertices.push_back(static_cast<std::int32_t>(v));
      out.offset.push_back(out.offset.back() + count[v + 1]);
    }
  out.entry_marker.resize(out.offset.back());
  out.entry_weight.resize(out.offset.back());
  std::vector<std::int64_t> fill(out.offset.begin(), out.offset.end() - 1);
  for (std::int64_t k = 0; k < out.size(); ++k)
    for (int c = 0; c < 4; ++c) {
      const std::int64_t e = fill[slot[out.tv[k][c]]]++;
      out.entry_marker[e] = static_cast<std::int32_t>(k);
      out.entry_weight[e] = out.w[k][c];
    }
  return out;
}

double contact_cell_width(const Model& model) {
  const std::size_t nb = model.bodies.size();
  std::vector<double> hsum(nb, 0.0);
  std::vector<std::int64_t> hcnt(nb, 0);
  double rmax = 0;
  for (std::size_t s = 0; s < model.surface.size(); ++s) {
    const auto& tri = model.surface[s].v;
    const Vec3 p[3] = {model.X[tri[0]], model.X[tri[1]], model.X[tri[2]]};
    const Vec3 c = (p[0] + p[1] + p[2]) / 3.0;
    for (int k = 0; k < 3; ++k) {
      rmax = std::max(rmax, norm(p[k] - c));
      hsum[model.surface_body[s]] += 0.5 * norm(p[(k + 1) % 3] - p[k]);  // shared edges: 1/2
      hcnt[model.surface_body[s]] += 1;
    }
  }
  double d_dem = model.contact.enabled ? model.contact.d_dem : 0;
  if (!model.contact.enabled) {
    double hmin = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < nb; ++b)
      if (hcnt[b]) hmin = std::min(hmin, 2 * hsum[b] / hcnt[b]);
    d_dem = std::isfinite(hmin) ? 0.1 * hmin : 0.0;
  }
  const double skin =
      model.contact.enabled && model.contact.skin >= 0 ? model.contact.skin : d_dem + 0.25 * rmax;
  return 2 * rmax + d_dem + skin;
}

void check_kernel_within_contact_cell(const Model& model, double support, double dx,
                                      double smoothing) {
  if (model.bodies.empty()) return;
  const double L = contact_cell_width(model);
  if (support > L)
    throw InputError(fmt::format(
        "fluid: the SPH kernel support 2h = 2 x {:.4g} x {:.4g} m = {:.4g} m exceeds the contact "
        "cell width {:.4g} m of the bodies' surface (2 max r + D_DEM + skin, METHOD.md eq. 9-10); "
        "the fluid and the contact search share cells and halo widths (METHOD.md section 5): use "
        "a finer fluid (fluid.spacing, fluid.smoothing), coarser surface elements, or a larger "
        "contact.skin",
        smoothing, dx, support, L));
}

}  // namespace qdemsph
