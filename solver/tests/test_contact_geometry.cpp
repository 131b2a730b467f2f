// Narrow-phase geometry and the contact law against hand-computed cases (METHOD.md section 3).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "physics/contact_geometry.hpp"
#include "physics/contact_law.hpp"

using namespace qdemsph;

namespace {
bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
}  // namespace

TEST(PointFace, HandComputedInside) {
  // Right triangle in z = 0; A above the point (0.25, 0.5).
  const PointFace r = point_face({0.25, 0.5, 0.3}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  EXPECT_TRUE(r.inside);
  EXPECT_NEAR(r.s, 0.3, 1e-15);
  EXPECT_NEAR(r.n.z, 1.0, 1e-15);
  // Barycentric = area ratios: w1 = u = 0.25, w2 = v = 0.5, w0 = 0.25.
  EXPECT_NEAR(r.w[0], 0.25, 1e-15);
  EXPECT_NEAR(r.w[1], 0.25, 1e-15);
  EXPECT_NEAR(r.w[2], 0.5, 1e-15);
  EXPECT_NEAR(r.c.x, 0.25, 1e-15);
  EXPECT_NEAR(r.c.y, 0.5, 1e-15);
  EXPECT_NEAR(r.c.z, 0.0, 1e-15);
}

TEST(PointFace, BelowOutsideAndDegenerate) {
  const PointFace below = point_face({0.2, 0.2, -0.1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  EXPECT_TRUE(below.inside);
  EXPECT_NEAR(below.s, -0.1, 1e-15);
  EXPECT_FALSE(point_face({0.8, 0.8, 0.1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}).inside);
  EXPECT_FALSE(point_face({-0.1, 0.5, 0.1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}).inside);
  // Degenerate (collinear) triangle: no contact, nothing NaN.
  const PointFace d = point_face({0.5, 0, 0.1}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_FALSE(d.inside);
  EXPECT_TRUE(std::isfinite(d.s));
}

TEST(PointFace, VertexOnEdgeAndVertexOnVertex) {
  // On the edge V1 V2 (u + v = 1) and on the vertex V0: inside (closed triangle), finite.
  const PointFace e = point_face({0.5, 0.5, 0.0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  EXPECT_TRUE(e.inside);
  EXPECT_NEAR(e.w[0], 0.0, 1e-15);
  const PointFace v = point_face({0, 0, 0.01}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  EXPECT_TRUE(v.inside);
  EXPECT_NEAR(v.w[0], 1.0, 1e-15);
}

TEST(BeyondPlane, AllThreePointsOnOneSideFartherThanTheGap) {
  const Vec3 p{0, 0, 1}, n{0, 0, 1};  // the plane z = 1
  const Vec3 above[3] = {{0, 0, 1.2}, {5, -3, 1.3}, {-2, 7, 1.25}};
  EXPECT_TRUE(beyond_plane(p, n, above, 0.1));
  EXPECT_FALSE(beyond_plane(p, n, above, 0.2));  // one point is only 0.2 away
  const Vec3 below[3] = {{0, 0, 0.7}, {1, 1, 0.5}, {2, 0, 0.6}};
  EXPECT_TRUE(beyond_plane(p, n, below, 0.25));
  EXPECT_FALSE(beyond_plane(p, n, below, 0.35));  // one point is only 0.3 away
  const Vec3 straddling[3] = {{0, 0, 1.5}, {1, 1, 0.5}, {2, 0, 1.5}};
  EXPECT_FALSE(beyond_plane(p, n, straddling, 0.1));
  EXPECT_FALSE(beyond_plane(p, Vec3{}, above, 0.1));  // a degenerate triangle's zero normal
  const Vec3 nan[3] = {{0, 0, std::nan("")}, {0, 0, 2}, {0, 0, 2}};
  EXPECT_FALSE(beyond_plane(p, n, nan, 0.1));
}

TEST(EdgeEdge, HandComputedCrossing) {
  // Edge 1 along x at z = 0.1, edge 2 along y at z = 0: crossing at (0.25, 0.75).
  const EdgeEdge r =
      edge_edge({0, 0.75, 0.1}, {1, 0.75, 0.1}, {0.25, 0, 0}, {0.25, 1, 0}, {0, 0, -1}, {0, 0, 1});
  ASSERT_TRUE(r.valid);
  EXPECT_NEAR(r.s, 0.25, 1e-15);
  EXPECT_NEAR(r.t, 0.75, 1e-15);
  EXPECT_NEAR(r.d, 0.1, 1e-15);
  EXPECT_NEAR(r.n.z, 1.0, 1e-15);  // from body 2 (below, outward +z) to body 1
  EXPECT_NEAR(r.p.x, 0.25, 1e-15);
  EXPECT_NEAR(r.q.y, 0.75, 1e-15);
}

TEST(EdgeEdge, CoplanarCrossingUsesFaceNormals) {
  // Zero distance: the normal comes from d1 x d2, oriented by the owning faces' normals.
  const EdgeEdge r =
      edge_edge({0, 0.5, 0}, {1, 0.5, 0}, {0.5, 0, 0}, {0.5, 1, 0}, {0, 0, -1}, {0, 0, 1});
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.d, 0.0);
  EXPECT_NEAR(r.n.z, 1.0, 1e-15);
  EXPECT_TRUE(finite(r.n));
}

TEST(EdgeEdge, ParallelAndEndpointCasesAreNotEdgeContacts) {
  // Parallel (overlapping, coincident and offset): no contact, no NaN.
  for (double off : {0.0, 0.05, 1e-300}) {
    const EdgeEdge r =
        edge_edge({0, 0, off}, {1, 0, off}, {0.5, 0, 0}, {1.5, 0, 0}, {0, 0, -1}, {0, 0, 1});
    EXPECT_FALSE(r.valid);
    EXPECT_TRUE(std::isfinite(r.d));
  }
  // Nearly parallel (1e-6 rad) is treated as parallel.
  EXPECT_FALSE(
      edge_edge({0, 0, 0.01}, {1, 1e-6, 0.01}, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0, 0, 1}).valid);
  // Vertex on edge: closest point at an endpoint of edge 1 -> covered by point-face.
  EXPECT_FALSE(
      edge_edge({0.5, 0, 0.0}, {0.5, 1, 1}, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0, 0, 1}).valid);
  // Vertex on vertex.
  EXPECT_FALSE(edge_edge({0, 0, 0}, {0, 1, 1}, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0, 0, 1}).valid);
  // Degenerate (zero-length) edge.
  EXPECT_FALSE(edge_edge({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0, 0, 1}).valid);
}

TEST(EdgeEdge, RandomSkewMatchesBruteForceMinimum) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  int checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 a0{U(rng), U(rng), U(rng)}, a1{U(rng), U(rng), U(rng)};
    const Vec3 b0{U(rng), U(rng), U(rng)}, b1{U(rng), U(rng), U(rng)};
    const EdgeEdge r = edge_edge(a0, a1, b0, b1, {0, 0, 1}, {0, 0, -1});
    if (!r.valid) continue;
    ++checked;
    // The closest points minimise |P(s) - Q(t)| over the unit square: check neighbours.
    const double d0 = norm(r.p - r.q);
    EXPECT_NEAR(std::fabs(r.d), d0, 1e-12);
    for (double ds : {-1e-4, 1e-4})
      for (double dt : {-1e-4, 1e-4}) {
        const Vec3 p = a0 + (r.s + ds) * (a1 - a0), q = b0 + (r.t + dt) * (b1 - b0);
        EXPECT_GE(norm(p - q), d0 - 1e-14);
      }
  }
  EXPECT_GT(checked, 100);
}

TEST(Distribution, ForcesSumAndMomentsBalance) {
  // Point-face: +F on A, -w_i F on V_i. The triangle's forces are statically equivalent to
  // -F at C: same resultant and the same moment about any point.
  const Vec3 V[3] = {{0.1, -0.2, 0.05}, {1.3, 0.1, -0.1}, {0.2, 0.9, 0.2}};
  const Vec3 A{0.5, 0.3, 0.4};
  const PointFace pf = point_face(A, V[0], V[1], V[2]);
  ASSERT_TRUE(pf.inside);
  const Vec3 F{0.3, -1.2, 2.5};
  Vec3 sum = F, mom{}, o{0.7, -3, 2};
  for (int i = 0; i < 3; ++i) {
    sum += -pf.w[i] * F;
    mom += cross(V[i] - o, -pf.w[i] * F);
  }
  EXPECT_LT(norm(sum), 1e-15);
  const Vec3 mom_c = cross(pf.c - o, -F);
  EXPECT_LT(norm(mom - mom_c), 1e-14);
  // Edge-edge: segment ratios; each side's forces equal +-F applied at P and Q.
  const Vec3 a0{0, 0.3, 0.1}, a1{1, 0.4, 0.12}, b0{0.3, -0.5, 0}, b1{0.35, 1.2, -0.02};
  const EdgeEdge ee = edge_edge(a0, a1, b0, b1, {0, 0, -1}, {0, 0, 1});
  ASSERT_TRUE(ee.valid);
  const Vec3 f1 = (1 - ee.s) * F, f2 = ee.s * F, g1 = -(1 - ee.t) * F, g2 = -ee.t * F;
  EXPECT_LT(norm(f1 + f2 + g1 + g2), 1e-15);
  const Vec3 m1 = cross(a0 - o, f1) + cross(a1 - o, f2), m2 = cross(b0 - o, g1) + cross(b1 - o, g2);
  EXPECT_LT(norm(m1 - cross(ee.p - o, F)), 1e-14);
  EXPECT_LT(norm(m2 - cross(ee.q - o, -F)), 1e-14);
}

TEST(ContactLaw, NormalSpringDashpotAndRestitution) {
  EXPECT_NEAR(damping_ratio_from_restitution(1.0), 0.0, 0);
  const double z = damping_ratio_from_restitution(0.5);
  // Integrate a 1-DOF collision with the law: the rebound speed ratio must be e.
  ContactLaw law{1e4, 0, z, 0};
  const double m = 0.1, dt = 1e-6;
  double x = 0.0, v = -1.0;  // x: gap - D_DEM (negative = overlap)
  for (int k = 0; k < 200000 && !(x > 0 && v > 0); ++k) {
    const double delta = -x;
    double f = 0;
    if (delta > 0) f = contact_force(law, {0, 0, 1}, delta, {0, 0, v}, {}, dt, m).f.z;
    v += dt * f / m;
    x += dt * v;
  }
  // The linear dashpot gives exactly e when tension is allowed; with no tension (the force
  // is clipped at zero near the end of the contact) the rebound is slightly livelier.
  EXPECT_GT(v, 0.5);
  EXPECT_LT(v, 0.6);
}

TEST(ContactLaw, CoulombLimitAndStick) {
  ContactLaw law{1e4, 2e3, 0.0, 0.4};
  // Sliding: |F_t| = mu F_n, opposing the tangential velocity.
  ContactForce r = contact_force(law, {0, 0, 1}, 1e-3, {2.0, 0, 0}, {0.01, 0, 0}, 1e-4, 1.0);
  EXPECT_NEAR(r.fn, 10.0, 1e-12);
  EXPECT_NEAR(r.f.x, -4.0, 1e-12);
  EXPECT_NEAR(r.xi.x, 2e-3, 1e-15);  // spring holds exactly mu F_n / k_t
  // Sticking: small spring, force = -k_t xi.
  r = contact_force(law, {0, 0, 1}, 1e-3, {0, 0, 0}, {1e-4, 0, 0}, 1e-4, 1.0);
  EXPECT_NEAR(r.f.x, -0.2, 1e-12);
  // Separating: no tension.
  r = contact_force(law, {0, 0, 1}, -1e-3, {0, 0, 0}, {}, 1e-4, 1.0);
  EXPECT_EQ(r.fn, 0.0);
  EXPECT_EQ(norm(r.f), 0.0);
  // A spring left in the old tangent plane is rotated into the new one, keeping its length.
  r = contact_force(ContactLaw{1e4, 2e3, 0, 10}, {0, 0, 1}, 1e-3, {}, {3e-4, 0, 4e-4}, 1e-4, 1.0);
  EXPECT_NEAR(r.xi.z, 0.0, 1e-18);
  EXPECT_NEAR(norm(r.xi), 5e-4, 1e-15);
}
