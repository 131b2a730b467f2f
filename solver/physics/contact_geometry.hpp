// Narrow-phase geometry of polygon contact (METHOD.md section 3, report Figs. 4-5), as pure
// host/device functions over plain values.
//
// Point-face: vertex A against triangle V0 V1 V2 with unit normal n = e1 x e2 / |e1 x e2|
// (e1 = V1-V0, e2 = V2-V0). Solve u e1 + v e2 + s n = A - V0 by Cramer's rule (the report's
// u V0V1 + v V0V2 - t AC = A - V0 with AC = -s n); C = A - s n is the closest point on the
// plane, s the signed distance (> 0 on the outward side). Inside when u >= 0, v >= 0,
// u + v <= 1; the barycentric weights (1-u-v, u, v) are the area ratios A_i / A of eq. 8.
//
// Edge-edge: segments P(s) = a0 + s d1, Q(t) = b0 + t d2. Closest points from the 2x2 system
//   [d1.d1  -d1.d2] [s]   [-d1.r]
//   [d1.d2  -d2.d2] [t] = [-d2.r],   r = a0 - b0,
// whose determinant is -|d1 x d2|^2. Nearly parallel edges (sin angle < kParallelSin) and
// closest points at an endpoint (vertex-edge, vertex-vertex) are *not* edge-edge contacts:
// point-face covers them, so one touch is never counted twice and nothing divides by ~0.
// The normal is d1 x d2, oriented from body 2 to body 1 by the edges' outward normals (the
// sums of their two faces' unit normals): robust when the edges are coplanar, the distance is
// zero or the edges have crossed. Only when those normals cannot decide (|n . (o2 - o1)| <
// 1e-3) does the direction from Q to P decide.
// ~60 flops (point-face), ~80 flops (edge-edge); no branches that can produce NaN.
#pragma once

#include "core/vec.hpp"

namespace qdemsph {

inline constexpr double kParallelSin = 1e-3;   // edge pairs closer to parallel are skipped
inline constexpr double kEdgeInterior = 1e-6;  // closest point must be this far from an end

struct PointFace {
  bool inside = false;      // projection falls inside the (non-degenerate) triangle
  double s = 0;             // signed distance of A above the plane (along n)
  double w[3] = {0, 0, 0};  // barycentric (area-ratio) weights of V0, V1, V2
  Vec3 n;                   // unit outward normal of the triangle
  Vec3 c;                   // closest point on the plane, sum w_i V_i
};

QDEMSPH_HD PointFace point_face(Vec3 a, Vec3 v0, Vec3 v1, Vec3 v2) {
  PointFace r;
  const Vec3 e1 = v1 - v0, e2 = v2 - v0, q = a - v0;
  const Vec3 m = cross(e1, e2);
  const double mm = norm(m);
  const double scale = norm2(e1) + norm2(e2);
  if (!(mm > 1e-14 * scale)) return r;  // degenerate triangle (or NaN input)
  r.n = m / mm;
  // Cramer's rule on [e1 e2 n] (u v s)^T = q; det = (e1 x e2) . n = |e1 x e2|.
  const double inv = 1.0 / mm;
  const double u = dot(cross(q, e2), r.n) * inv;
  const double v = dot(cross(e1, q), r.n) * inv;
  r.s = dot(q, r.n);
  r.w[0] = 1.0 - u - v;
  r.w[1] = u;
  r.w[2] = v;
  r.c = a - r.s * r.n;
  r.inside = u >= 0 && v >= 0 && u + v <= 1;
  return r;
}

// Whether the points q[0..2] all lie farther than `gap` from the plane through p with unit
// normal n, on one side (false for a zero n or NaN). Every point of the triangle they span, and
// of its edges, is then farther than `gap` from every point of that plane.
QDEMSPH_HD bool beyond_plane(Vec3 p, Vec3 n, const Vec3* q, double gap) {
  const double s0 = dot(q[0] - p, n), s1 = dot(q[1] - p, n), s2 = dot(q[2] - p, n);
  return (s0 > gap && s1 > gap && s2 > gap) || (s0 < -gap && s1 < -gap && s2 < -gap);
}

struct EdgeEdge {
  bool valid = false;   // non-parallel, closest points strictly inside both segments
  double s = 0, t = 0;  // segment parameters of the closest points
  double d = 0;         // signed distance along n: (P - Q) . n
  Vec3 n;               // unit normal, from edge 2's body towards edge 1's body
  Vec3 p, q;            // closest points on edge 1 and edge 2
};

// out1, out2: outward normals of edge 1 and edge 2 (sum of the adjacent faces' unit normals).
QDEMSPH_HD EdgeEdge edge_edge(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1, Vec3 out1, Vec3 out2) {
  EdgeEdge r;
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, w = a0 - b0;
  const double a = dot(d1, d1), e = dot(d2, d2), b = dot(d1, d2);
  const Vec3 m = cross(d1, d2);
  const double mm2 = norm2(m);  // = a e - b^2, computed without cancellation
  if (!(mm2 > kParallelSin * kParallelSin * a * e)) return r;  // (nearly) parallel or NaN
  const double c = dot(d1, w), f = dot(d2, w);
  const double s = (b * f - c * e) / mm2;
  const double t = (a * f - b * c) / mm2;
  if (!(s > kEdgeInterior && s < 1 - kEdgeInterior && t > kEdgeInterior && t < 1 - kEdgeInterior))
    return r;
  r.s = s;
  r.t = t;
  r.p = a0 + s * d1;
  r.q = b0 + t * d2;
  Vec3 n = m / sqrt(mm2);
  double sg = dot(n, out2 - out1);
  if (fabs(sg) < 1e-3) sg = dot(n, r.p - r.q);
  if (sg < 0) n = -n;
  r.n = n;
  r.d = dot(r.p - r.q, n);
  r.valid = true;
  return r;
}

}  // namespace qdemsph
