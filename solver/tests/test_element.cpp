// The QDEM element against known answers: nodal forces are -dE/dx (finite differences),
// sum to zero, vanish under rigid translation and (St. Venant-Kirchhoff) under a 90-degree
// rigid rotation; the viscous stress vanishes for a rigid spin; the stability estimate is
// l_min / c_p for an elastic tet.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "physics/element.hpp"

namespace qdemsph {
namespace {

const Vec3 kRef[4] = {{0, 0, 0}, {1.0, 0.1, 0.0}, {0.2, 0.9, 0.1}, {0.1, 0.2, 1.1}};

struct Tet {
  Mat3 dX_inv;
  double V0;
};

Tet reference() { return {inverse(edge_matrix(kRef)), det(edge_matrix(kRef)) / 6.0}; }

double energy(const Material& m, const Vec3 x[4]) {
  const Tet t = reference();
  const Mat3 F = edge_matrix(x) * t.dX_inv;
  return t.V0 * material_stress(m, F, Mat3{}).energy_density;
}

Material law(int l, double visc = 0) { return make_material(l, 1e6, 0.3, 1000, visc); }

void deformed(Vec3 x[4], double amp, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  for (int k = 0; k < 4; ++k) x[k] = kRef[k] + Vec3{u(rng), u(rng), u(rng)};
}

class ElementLaw : public ::testing::TestWithParam<int> {};

TEST_P(ElementLaw, ForcesAreMinusEnergyGradient) {
  const Material m = law(GetParam());
  const Tet t = reference();
  Vec3 x[4], v[4] = {};
  deformed(x, 0.15, 7);
  const ElementForces e = tet_forces(m, x, v, t.dX_inv, t.V0);
  const double h = 1e-6;
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) {
      Vec3 xp[4], xm[4];
      for (int j = 0; j < 4; ++j) xp[j] = xm[j] = x[j];
      xp[k][a] += h;
      xm[k][a] -= h;
      const double fd = -(energy(m, xp) - energy(m, xm)) / (2 * h);
      EXPECT_NEAR(e.f[k][a], fd, 1e-6 * std::abs(fd) + 1e-3) << "vertex " << k << " axis " << a;
    }
}

TEST_P(ElementLaw, ForcesSumToZeroAndVanishUnderTranslation) {
  const Material m = law(GetParam(), 5.0);
  const Tet t = reference();
  Vec3 x[4], v[4];
  deformed(x, 0.1, 3);
  deformed(v, 0.5, 4);
  const ElementForces e = tet_forces(m, x, v, t.dX_inv, t.V0);
  Vec3 s = e.f[0] + e.f[1] + e.f[2] + e.f[3];
  EXPECT_LT(norm(s), 1e-10 * norm(e.f[0]));
  const Vec3 shift{3.0, -2.0, 7.5}, vel{1.0, 2.0, -3.0};
  for (int k = 0; k < 4; ++k) {
    x[k] = kRef[k] + shift;
    v[k] = vel;
  }
  const ElementForces r = tet_forces(m, x, v, t.dX_inv, t.V0);
  for (int k = 0; k < 4; ++k) EXPECT_LT(norm(r.f[k]), 1e-9) << "vertex " << k;
}

INSTANTIATE_TEST_SUITE_P(Laws, ElementLaw, ::testing::Values(0, 1),
                         [](const auto& info) { return info.param == 0 ? "Linear" : "SVK"; });

// Rotation by 90 degrees about z: x' = (-y, x, z).
Vec3 rot90(Vec3 p) { return {-p.y, p.x, p.z}; }

TEST(Element, SvkGivesZeroForceUnderRigidRotation) {
  const Material m = law(1);
  const Tet t = reference();
  Vec3 x[4], v[4];
  for (int k = 0; k < 4; ++k) {
    x[k] = rot90(kRef[k]);
    v[k] = cross(Vec3{0, 0, 2.0}, x[k]);  // rigid spin: no rate of deformation
  }
  const ElementForces e = tet_forces(law(1, 10.0), x, v, t.dX_inv, t.V0);
  for (int k = 0; k < 4; ++k) EXPECT_LT(norm(e.f[k]), 1e-9) << "vertex " << k;
  EXPECT_NEAR(e.stress.energy_density, 0.0, 1e-9);
  EXPECT_NEAR(e.stress.dissipation, 0.0, 1e-9);
  (void)m;
}

TEST(Element, LinearLawIsNotRotationInvariant) {
  // Documents why SVK is the default for dynamic scenes: the small-strain law sees a
  // 90-degree rotation as a strain of order one.
  const Tet t = reference();
  Vec3 x[4], v[4] = {};
  for (int k = 0; k < 4; ++k) x[k] = rot90(kRef[k]);
  const ElementForces e = tet_forces(law(0), x, v, t.dX_inv, t.V0);
  EXPECT_GT(norm(e.f[1]), 1e3);
}

TEST(Element, CriticalTimeStepIsAltitudeOverWaveSpeed) {
  const Material m = law(1);
  const Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  // Largest face: the slanted one, area sqrt(3)/2; V = 1/6; altitude = 3V/A = 1/sqrt(3).
  EXPECT_NEAR(min_altitude(p), 1 / std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(tet_critical_dt(m, 1.0), 1.0 / p_wave_speed(m), 1e-15);
  EXPECT_LT(tet_critical_dt(law(1, 1e3), 1.0), tet_critical_dt(m, 1.0));
}

TEST(Element, VonMisesOfUniaxialStressIsTheStress) {
  Mat3 s;
  s.m[0][0] = 5.0;
  EXPECT_DOUBLE_EQ(von_mises(s), 5.0);
  Mat3 shear;
  shear.m[0][1] = shear.m[1][0] = 1.0;
  EXPECT_DOUBLE_EQ(von_mises(shear), std::sqrt(3.0));
}

}  // namespace
}  // namespace qdemsph
