#include "model/overlap.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "model/model.hpp"

namespace qdemsph {

namespace {

struct Box {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  void add(Vec3 p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  bool meets(const Box& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z &&
           b.lo.z <= hi.z;
  }
  bool contains(Vec3 p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
};

// Depth of p inside tet (a, b, c, d): the smallest distance to its four face planes when p
// is inside all of them, else <= 0.
double depth_inside(Vec3 p, const Vec3 t[4]) {
  static constexpr int face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  double d = INFINITY;
  for (int f = 0; f < 4; ++f) {
    const Vec3 a = t[face[f][0]], b = t[face[f][1]], c = t[face[f][2]];
    Vec3 n = cross(b - a, c - a);
    const double nn = norm(n);
    if (!(nn > 0)) return 0;
    n = n / nn;
    // Oriented towards the opposite vertex f.
    const double s = dot(t[f] - a, n) > 0 ? 1.0 : -1.0;
    d = std::min(d, s * dot(p - a, n));
  }
  return d;
}

}  // namespace

void check_initial_overlap(const Model& m) {
  const std::size_t nb = m.bodies.size();
  if (nb < 2) return;
  std::vector<Box> box(nb);
  for (std::size_t b = 0; b < nb; ++b)
    for (std::int64_t i = m.bodies[b].v_begin; i < m.bodies[b].v_end; ++i) box[b].add(m.x[i]);
  // Points of each body's surface: its vertices (each once) and its triangles' centroids
  // (structured meshes can cross with every vertex on an edge or face of the other body).
  struct SurfacePoint {
    Vec3 p;
    std::int64_t id;  // vertex index, or -1 - triangle index
  };
  std::vector<std::vector<SurfacePoint>> surf(nb);
  {
    std::vector<std::uint8_t> seen(m.x.size(), 0);
    for (std::size_t s = 0; s < m.surface.size(); ++s) {
      const auto& tv = m.surface[s].v;
      auto& pts = surf[m.surface_body[s]];
      pts.push_back(
          {(m.x[tv[0]] + m.x[tv[1]] + m.x[tv[2]]) / 3.0, -1 - static_cast<std::int64_t>(s)});
      for (std::int32_t v : tv)
        if (!seen[v]) {
          seen[v] = 1;
          pts.push_back({m.x[v], v});
        }
    }
  }
  auto describe = [&](const SurfacePoint& q, std::size_t body) {
    if (q.id >= 0) return fmt::format("vertex {}", q.id - m.bodies[body].v_begin);
    std::int64_t k = 0;  // the triangle's index among the body's surface triangles
    for (std::int64_t s = 0; s < -1 - q.id; ++s) k += m.surface_body[s] == static_cast<int>(body);
    return fmt::format("the centroid of surface triangle {}", k);
  };
  for (std::size_t a = 0; a < nb; ++a)
    for (std::size_t b = 0; b < nb; ++b) {
      if (a == b || (m.bodies[a].fixed && m.bodies[b].fixed) || !box[a].meets(box[b])) continue;
      // Vertices of a inside tets of b: b's tets in the common box, binned on a grid.
      Box common{{std::max(box[a].lo.x, box[b].lo.x), std::max(box[a].lo.y, box[b].lo.y),
                  std::max(box[a].lo.z, box[b].lo.z)},
                 {std::min(box[a].hi.x, box[b].hi.x), std::min(box[a].hi.y, box[b].hi.y),
                  std::min(box[a].hi.z, box[b].hi.z)}};
      std::vector<std::int64_t> tets;
      std::vector<Box> tbox;
      double size = 0;
      for (std::int64_t t = m.bodies[b].t_begin; t < m.bodies[b].t_end; ++t) {
        Box tb;
        for (int k = 0; k < 4; ++k) tb.add(m.x[m.tets[t][k]]);
        if (!tb.meets(common)) continue;
        tets.push_back(t);
        tbox.push_back(tb);
        size = std::max({size, tb.hi.x - tb.lo.x, tb.hi.y - tb.lo.y, tb.hi.z - tb.lo.z});
      }
      if (tets.empty() || !(size > 0)) continue;
      auto cell = [&](double v, double lo) {
        return static_cast<long>(std::floor((v - lo) / size));
      };
      auto key = [](long i, long j, long k) {
        return (static_cast<std::uint64_t>(i & 0x1fffff) << 42) |
               (static_cast<std::uint64_t>(j & 0x1fffff) << 21) |
               static_cast<std::uint64_t>(k & 0x1fffff);
      };
      std::unordered_map<std::uint64_t, std::vector<std::size_t>> grid;
      for (std::size_t q = 0; q < tets.size(); ++q) {
        const Box& tb = tbox[q];
        for (long i = cell(tb.lo.x, common.lo.x); i <= cell(tb.hi.x, common.lo.x); ++i)
          for (long j = cell(tb.lo.y, common.lo.y); j <= cell(tb.hi.y, common.lo.y); ++j)
            for (long k = cell(tb.lo.z, common.lo.z); k <= cell(tb.hi.z, common.lo.z); ++k)
              grid[key(i, j, k)].push_back(q);
      }
      for (const SurfacePoint& sp : surf[a]) {
        const Vec3 p = sp.p;
        if (!common.contains(p)) continue;
        const auto it =
            grid.find(key(cell(p.x, common.lo.x), cell(p.y, common.lo.y), cell(p.z, common.lo.z)));
        if (it == grid.end()) continue;
        for (std::size_t q : it->second) {
          if (!tbox[q].contains(p)) continue;
          Vec3 t[4];
          for (int k = 0; k < 4; ++k) t[k] = m.x[m.tets[tets[q]][k]];
          const double d = depth_inside(p, t);
          // Beyond round-off of the tet's size: a vertex on the other body's surface touches.
          if (d > 1e-9 * size)
            throw InputError(fmt::format(
                "bodies '{}' and '{}' overlap at the start: {} of body '{}' at ({:.6g}, {:.6g}, "
                "{:.6g}) lies {:.3e} m inside tet {} of body '{}'; move them apart (they may "
                "touch, not intersect)",
                m.bodies[a].name, m.bodies[b].name, describe(sp, a), m.bodies[a].name, p.x, p.y,
                p.z, d, tets[q] - m.bodies[b].t_begin, m.bodies[b].name));
        }
      }
    }
}

}  // namespace qdemsph
