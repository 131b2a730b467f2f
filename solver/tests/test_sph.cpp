// SPH physics and the fluid stage: kernel normalisation and gradient (finite differences), the
// Tait equation of state, the hydrostatic initial state in a tank (pressure and force balance,
// Adami wall pressure) and exact momentum conservation of the pair forces.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "io/scene_yaml.hpp"
#include "physics/sph_boundary.hpp"
#include "physics/sph_eos.hpp"
#include "physics/sph_kernel.hpp"
#include "physics/sph_pair.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/sph_stage.hpp"

namespace qdemsph {
namespace {

TEST(SphKernel, IntegratesToOne) {
  const WendlandC2 k = WendlandC2::make(0.37);
  // 4 pi int_0^{2h} W r^2 dr by Simpson's rule.
  const int n = 2000;
  const double R = k.support(), dr = R / n;
  double s = 0;
  for (int i = 0; i <= n; ++i) {
    const double r = i * dr;
    const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    s += w * k.w(r * r) * r * r;
  }
  EXPECT_NEAR(4 * M_PI * s * dr / 3, 1.0, 1e-10);
  EXPECT_EQ(k.w(R * R * 1.0000001), 0.0);
  EXPECT_EQ(k.f(R * R), 0.0);
}

TEST(SphKernel, GradientMatchesFiniteDifferences) {
  const WendlandC2 k = WendlandC2::make(0.1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  for (int t = 0; t < 200; ++t) {
    const Vec3 r{u(rng), u(rng), u(rng)};
    const Vec3 g = k.grad(r);
    const double e = 1e-6;
    for (int a = 0; a < 3; ++a) {
      Vec3 p = r, m = r;
      p[a] += e;
      m[a] -= e;
      const double fd = (k.w(norm2(p)) - k.w(norm2(m))) / (2 * e);
      EXPECT_NEAR(g[a], fd, 1e-6 * k.aD / k.h + 1e-7 * std::fabs(fd)) << "component " << a;
    }
    // Odd in r exactly: the pair forces rely on it.
    const Vec3 gm = k.grad(-r);
    EXPECT_EQ(gm.x, -g.x);
    EXPECT_EQ(gm.y, -g.y);
    EXPECT_EQ(gm.z, -g.z);
  }
}

TEST(SphEos, TaitPressureInverseAndSoundSpeed) {
  const TaitEos e = TaitEos::make(1000, 20, -1e300);  // no tension cut-off
  EXPECT_EQ(e.pressure(1000), 0.0);
  const TaitEos cut = TaitEos::make(1000, 20);  // default cut-off p >= 0: density floor rho0
  EXPECT_EQ(cut.rho_min, 1000.0);
  EXPECT_EQ(cut.pressure(990), 0.0);
  EXPECT_NEAR(TaitEos::make(1000, 20, -500).rho_min, e.density(-500), 1e-12);
  EXPECT_EQ(cut.next_density(1000, 2000, 1e-3), 1002.0);   // rho + dt drho/dt
  EXPECT_EQ(cut.next_density(1000, -2000, 1e-3), 1000.0);  // floored at rho_min
  EXPECT_NEAR(e.B, 20.0 * 20.0 * 1000 / 7, 1e-9);
  for (double rho : {990.0, 1000.0, 1003.0, 1010.0}) {
    EXPECT_NEAR(e.density(e.pressure(rho)), rho, 1e-9);
    const double h = 1e-4;
    const double c2 = (e.pressure(rho + h) - e.pressure(rho - h)) / (2 * h);
    EXPECT_NEAR(std::sqrt(c2), e.sound_speed(rho), 1e-6 * e.c0);
  }
}

FluidSpec tank_spec() {
  FluidSpec s;
  s.present = true;
  s.spacing = 0.02;
  s.viscosity = 0.02;
  s.blocks.push_back({{0, 0, 0}, {0.2, 0.2, 0.08}, 3});
  s.tanks.push_back({{0, 0, 0}, {0.2, 0.25, 0.08}, 3});
  return s;
}

TEST(SphSetup, HydrostaticColumnPressureAndBalance) {
  const Vec3 g{0, -9.81, 0};
  const FluidSetup f = build_fluid(tank_spec(), g);
  const double rho0 = 1000, H = 0.2;
  EXPECT_NEAR(f.params.eos.c0, 10 * std::sqrt(2 * 9.81 * H), 1e-12);
  ASSERT_EQ(f.n_fluid, 10 * 10 * 4);
  for (std::int64_t i = 0; i < f.n_fluid; ++i) {
    EXPECT_NEAR(f.p[i], rho0 * 9.81 * (H - f.x[i].y), 1e-9);
    EXPECT_NEAR(f.m[i] / f.rho[i], std::pow(0.02, 3), 1e-15);
  }
  // The initial state is an equilibrium: the discrete pressure gradient (with the Adami walls)
  // balances gravity in the interior to the kernel's discretisation error.
  SphStage<HostExec> st(f);
  const FluidHost h = st.download();
  st.kick(0.0);  // no-op; stats below read the accelerations of compute()
  double worst = 0;
  int n = 0;
  for (std::size_t i = 0; i < h.x.size(); ++i) {
    if (h.type[i] != kSphFluid) continue;
    ++n;
  }
  EXPECT_EQ(n, f.n_fluid);
  const FluidStats s = st.stats();
  worst = s.a_max;
  EXPECT_LT(worst, 0.35 * 9.81) << "initial |a| max (free surface and corners included)";
  // Bottom wall (first layer below the fluid, away from the side walls): Adami pressure
  // rho g (H + dx/2) within 3 %.
  double pw = 0;
  int nw = 0;
  for (std::size_t i = 0; i < h.x.size(); ++i)
    if (h.type[i] == kSphWall && std::fabs(h.x[i].y + 0.01) < 1e-9 && h.x[i].x > 0.05 &&
        h.x[i].x < 0.15 && h.x[i].z > 0 && h.x[i].z < 0.08) {
      pw += h.p[i];
      ++nw;
    }
  ASSERT_GT(nw, 0);
  EXPECT_NEAR(pw / nw, rho0 * 9.81 * (H + 0.01), 0.03 * rho0 * 9.81 * H);
}

TEST(SphPair, ForcesAreExactlyAntisymmetricAndConserveMomentum) {
  SphParams P;
  P.kernel = WendlandC2::make(0.013);
  P.eos = TaitEos::make(1000, 15, -1e300);
  P.alpha = 0.05;
  P.gravity = {0, -9.81, 0};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 0.03), uv(-1, 1), ur(990, 1015);
  const int n = 60;
  std::vector<PairState> s(n);
  for (auto& q : s) {
    q.x = {u(rng), u(rng), u(rng)};
    q.v = {uv(rng), uv(rng), uv(rng)};
    q.rho = ur(rng);
    q.m = 1000 * 1e-6 * (1 + 0.1 * uv(rng));
    q.pr = P.eos.pressure(q.rho) / (q.rho * q.rho);
  }
  for (SphViscosity vt : {SphViscosity::Artificial, SphViscosity::Laminar}) {
    P.visc_type = vt;
    P.nu = 1e-3;
    Vec3 total{}, scale{};
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (i == j) continue;
        const Vec3 fij = sph_pair_force(P, s[i], s[j], true);
        const Vec3 fji = sph_pair_force(P, s[j], s[i], true);
        ASSERT_EQ(fij.x, -fji.x);
        ASSERT_EQ(fij.y, -fji.y);
        ASSERT_EQ(fij.z, -fji.z);
        total += fij;
        scale += Vec3{std::fabs(fij.x), std::fabs(fij.y), std::fabs(fij.z)};
      }
    EXPECT_LE(norm(total), 1e-14 * norm(scale));
  }
}

TEST(SphPair, BoundaryForceOnlyPushesAndDryWallsStandForAir) {
  SphParams P;
  P.kernel = WendlandC2::make(0.013);
  P.eos = TaitEos::make(1000, 15, -1e300);  // tension allowed (fluid.min_pressure < 0)
  P.alpha = 0.05;
  const double m = 1000 * 1e-6;
  const PairState wall = pair_state({0, 0, 0}, {0, 0, 0}, 1001, P.eos.pressure(1001), m);
  const PairState fluid =
      pair_state({0.008, 0.003, 0}, {0, 0, 0}, 1000.5, P.eos.pressure(1000.5), m);
  // Same as the fluid-fluid form for a wet wall and fluid under pressure.
  const Vec3 a = sph_boundary_force(P, fluid, wall, true);
  const Vec3 b = sph_pair_force(P, fluid, wall, true);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_GT(a.x, 0.0) << "the wall pushes the fluid away";
  // Fluid in tension next to a wet wall: pushed by the wall's pressure only, never pulled in.
  const PairState tense = pair_state(fluid.x, fluid.v, 995, P.eos.pressure(995), m);
  ASSERT_LT(tense.pr, 0.0);
  EXPECT_GT(sph_boundary_force(P, tense, wall, false).x, 0.0);
  EXPECT_LT(sph_pair_force(P, tense, wall, false).x, 0.0) << "the plain form would pull it in";
  // A dry wall particle (p = 0): no pressure force; viscosity only.
  const PairState dry = pair_state(wall.x, wall.v, 1000, 0.0, m);
  const Vec3 d = sph_boundary_force(P, fluid, dry, false);
  EXPECT_EQ(d.x, 0.0);
  EXPECT_EQ(d.y, 0.0);
  PairState moving = fluid;
  moving.v = {-1, 0, 0};  // approaching: artificial viscosity acts
  EXPECT_GT(sph_boundary_force(P, moving, dry, true).x, 0.0);
}

// A hydrostatic column closed in by five wall slabs, as given or turned as a whole by `rot`
// about the origin: each box keeps its size, its min corner is turned and the box turned
// about it (`rotate`), gravity is turned. Returns (pressure, velocity after kick(1) from
// rest = acceleration) per particle gid.
std::pair<std::vector<double>, std::vector<Vec3>> closed_column(const RotationSpec& rot) {
  FluidSpec s;
  s.present = true;
  s.spacing = 0.02;
  s.viscosity = 0.02;
  auto box = [&](Vec3 lo, Vec3 hi) {
    FluidBoxSpec b{lo, hi, 3, {}};
    if (rot.none()) return b;
    b.min = rot.apply(lo, Vec3{});
    b.max = b.min + (hi - lo);
    b.rotate = rot;
    return b;
  };
  s.blocks.push_back(box({0, 0, 0}, {0.2, 0.2, 0.08}));
  s.walls = {box({-0.06, -0.06, -0.06}, {0.26, 0, 0.14}), box({-0.06, 0, -0.06}, {0, 0.3, 0.14}),
             box({0.2, 0, -0.06}, {0.26, 0.3, 0.14}), box({0, 0, -0.06}, {0.2, 0.3, 0}),
             box({0, 0, 0.08}, {0.2, 0.3, 0.14})};
  const Vec3 g = rot.none() ? Vec3{0, -9.81, 0} : rot.apply(Vec3{0, -9.81, 0}, Vec3{});
  SphStage<HostExec> st(build_fluid(s, g));
  const FluidHost h0 = st.download();
  st.kick(1.0);
  const FluidHost h = st.download();
  std::vector<double> p(h.x.size());
  std::vector<Vec3> a(h.x.size());
  for (std::size_t i = 0; i < h.x.size(); ++i) {
    p[h0.gid[i]] = h0.p[i];
    a[h.gid[i]] = h.v[i];
  }
  return {p, a};
}

TEST(SphSetup, TurnedSceneIsTheTurnedSolution) {
  // Turned fluid blocks and wall boxes (rotate about their min corner): the same column turned
  // by 30 deg about (1, 2, 3) with gravity has the same hydrostatic start (depth along
  // gravity to the block's top face) and, particle by particle, the turned accelerations
  // (Adami wall pressures included), to round-off.
  const auto [p0, a0] = closed_column({});
  const RotationSpec rot{{1, 2, 3}, 30};
  const auto [p1, a1] = closed_column(rot);
  ASSERT_EQ(p0.size(), p1.size());
  double dp = 0, da = 0, amax = 0;
  for (std::size_t i = 0; i < p0.size(); ++i) {
    dp = std::max(dp, std::fabs(p1[i] - p0[i]));
    da = std::max(da, norm(a1[i] - rot.apply(a0[i], Vec3{})));
    amax = std::max(amax, norm(a0[i]));
  }
  EXPECT_GT(amax, 0.1);  // the free surface and corners do accelerate (0.48 m/s^2)
  std::printf("turned column: max |dp| %.2e Pa, max |da| %.2e m/s^2 (largest |a| %.3f)\n", dp, da,
              amax);
  EXPECT_LT(dp, 1e-9) << "initial pressure [Pa]";
  EXPECT_LT(da, 1e-9) << "acceleration [m/s^2]";
}

// Accelerations of the fluid particles of a hydrostatic tank periodic in z over `layers`
// spacings (no z walls), keyed by the particle's (x, y) lattice cell: v after kick(1) from rest.
std::map<std::pair<long, long>, std::vector<Vec3>> periodic_tank_accelerations(int layers) {
  FluidSpec s = tank_spec();
  const double L = layers * s.spacing;
  s.blocks[0].max.z = L;
  s.tanks[0].max.z = L;
  s.periodic_z = std::array<double, 2>{0.0, L};
  SphStage<HostExec> st(build_fluid(s, Vec3{0, -9.81, 0}));
  st.kick(1.0);
  const FluidHost h = st.download();
  std::map<std::pair<long, long>, std::vector<Vec3>> a;
  for (std::size_t i = 0; i < h.x.size(); ++i)
    if (h.type[i] == kSphFluid)
      a[{std::lround(h.x[i].x / s.spacing - 0.5), std::lround(h.x[i].y / s.spacing - 0.5)}]
          .push_back(h.v[i]);
  return a;
}

TEST(SphStage, PeriodicZSlabIsTheSameForAnyNumberOfLayers) {
  // Periodic in z every layer of a hydrostatic tank is equivalent: 1 and 2 layers (a period
  // below the kernel support 2h = 2.6 dx: several images of one particle are neighbours) must
  // give the 5-layer slab's accelerations, with no z component, to round-off.
  const auto a5 = periodic_tank_accelerations(5);
  ASSERT_EQ(a5.size(), 100u);
  for (int layers : {1, 2}) {
    const auto a = periodic_tank_accelerations(layers);
    ASSERT_EQ(a.size(), a5.size());
    double worst = 0, worst_z = 0;
    for (const auto& [cell, acc] : a) {
      ASSERT_EQ(acc.size(), static_cast<std::size_t>(layers));
      const Vec3 ref = a5.at(cell)[0];
      for (const Vec3& ai : acc) {
        worst = std::max(worst, norm(ai - ref));
        worst_z = std::max(worst_z, std::fabs(ai.z));
      }
    }
    EXPECT_LT(worst, 1e-9) << layers << " layers: largest difference from 5 layers [m/s^2]";
    EXPECT_LT(worst_z, 1e-9) << layers << " layers: largest |a_z| [m/s^2]";
  }
}

// A free fluid block (no walls, no gravity) with random velocities (z ones scaled by vz): the
// stage's total momentum stays constant to round-off over 50 steps (re-sorting included).
// Returns the final particles.
FluidHost expect_cloud_conserves_momentum(const FluidSpec& spec, double amp, double vz,
                                          unsigned seed) {
  FluidSetup f = build_fluid(spec, Vec3{0, 0, 0});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uv(-amp, amp);
  for (std::int64_t i = 0; i < f.size(); ++i) f.v[i] = {uv(rng), uv(rng), vz * uv(rng)};
  SphStage<HostExec> st(f);
  const Vec3 p0 = st.stats().momentum;
  double mref = 0;
  for (std::int64_t i = 0; i < f.size(); ++i) mref += f.m[i] * norm(f.v[i]);
  const double dt = 0.2 * f.params.kernel.h / 6.0;
  for (int k = 0; k < 50; ++k) {
    st.kick(0.5 * dt);
    st.drift(dt);
    st.compute();
    st.kick(0.5 * dt);
  }
  const Vec3 p1 = st.stats().momentum;
  EXPECT_LE(norm(p1 - p0), 1e-12 * mref) << "momentum drift " << norm(p1 - p0) << " of " << mref;
  EXPECT_EQ(st.find_non_finite(), -1);
  return st.download();
}

FluidSpec cloud_spec(Vec3 size) {
  FluidSpec spec;
  spec.present = true;
  spec.spacing = 0.01;
  spec.sound_speed = 5.0;
  spec.viscosity = 0.1;
  spec.hydrostatic_init = false;
  spec.blocks.push_back({{0, 0, 0}, size, 3});
  return spec;
}

TEST(SphStage, FluidOnlyCloudConservesMomentum) {
  expect_cloud_conserves_momentum(cloud_spec({0.08, 0.08, 0.08}), 0.2, 1.0, 11);
}

TEST(SphStage, PeriodicZCloudConservesMomentumAndStaysInThePeriod) {
  // A 3-layer periodic slab: particles cross z0 and z1 and are wrapped, pair forces across the
  // period stay antisymmetric.
  FluidSpec spec = cloud_spec({0.06, 0.06, 0.03});
  spec.periodic_z = std::array<double, 2>{0.0, 0.03};
  for (const Vec3& x : expect_cloud_conserves_momentum(spec, 0.5, 4.0, 5).x) {
    EXPECT_GE(x.z, 0.0);
    EXPECT_LT(x.z, 0.03);
  }
}

}  // namespace
}  // namespace qdemsph

namespace qdemsph {
namespace {

TEST(SphScene, FluidOnlySceneParses) {
  const Scene s = parse_scene(R"(
run: {end_time: 0.1}
gravity: [0, -9.81, 0]
fluid:
  spacing: 0.02
  sound_speed: auto
  viscosity_type: laminar
  viscosity: 1.0e-6
  blocks: [{min: [0, 0, 0], max: [0.2, 0.1, 0.04]}]
  tanks: [{min: [0, 0, 0], max: [0.4, 0.2, 0.04], thickness_layers: 3}]
)",
                              "fluid.yaml", {});
  ASSERT_TRUE(s.fluid.present);
  EXPECT_TRUE(s.bodies.empty());
  EXPECT_FALSE(s.fluid.sound_speed.has_value());
  EXPECT_EQ(s.fluid.viscosity_type, "laminar");
  ASSERT_EQ(s.fluid.tanks.size(), 1u);
  EXPECT_EQ(s.fluid.tanks[0].thickness_layers, 3);
  try {
    parse_scene(
        "run: {end_time: 0.1}\nfluid: {spacing: 0.02, blocks: [{min: [0, 0, 0], max: [0, 1, "
        "1]}]}\n",
        "bad.yaml", {});
    FAIL() << "a block with max.x <= min.x must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fluid.blocks.0.max.0"), std::string::npos) << e.what();
  }
  const std::string base =
      "run: {end_time: 0.1}\ngravity: [0, -9.81, 0]\nfluid: {spacing: 0.02, blocks: [{min: [0, 0, "
      "0], "
      "max: [0.2, 0.1, 0.04]}], ";
  EXPECT_EQ(parse_scene(base + "periodic_z: [0, 0.04]}\n", "p.yaml", {}).fluid.periodic_z->at(1),
            0.04);
  for (const auto& [bad, expect] : std::vector<std::pair<std::string, std::string>>{
           {"periodic_z: [0, 0.05]}",
            "fluid.periodic_z: z1 - z0 must be a whole number of spacings"},
           {"periodic_z: [0, 0.02]}", "fluid.blocks.0: must lie within fluid.periodic_z in z"},
           {"periodic_z: [0.04, 0]}", "fluid.periodic_z.1: must be > z0"}}) {
    try {
      parse_scene(base + bad + "\n", "bad.yaml", {});
      FAIL() << bad << " must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace qdemsph
