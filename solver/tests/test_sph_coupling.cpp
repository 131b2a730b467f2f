// QDEM-SPH coupling: boundary markers embedded in the bodies' tets (placement, interpolation,
// force gather), exact momentum conservation of fluid + bodies in coupled steps (with and
// without solid sub-steps), the fluid's weight carried by a body used as the tank floor, and the
// kernel-support check against the contact cell width.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "core/gpu_info.hpp"
#include "integrate/stepper.hpp"
#include "scene_fixture.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/sph_stage.hpp"

namespace qdemsph {
namespace {

using testing::make_problem;

TEST(SolidMarkers, BoxGetsThreeLayersEmbeddedInItsTets) {
  const auto pb = make_problem(R"(
run: {end_time: 0.01}
materials: {rubber: {E: 1.0e6, nu: 0.3, density: 1000}}
bodies:
  - {name: cube, material: rubber, mesh: {type: box, origin: [0.1, 0, 0], size: [0.1, 0.1, 0.1], cells: [2, 2, 2]}}
)");
  const double dx = 0.01, support = 0.026;
  const SolidMarkers m = build_solid_markers(pb.model, dx, support);
  // 10^3 lattice points; the 4^3 core is deeper than 2h below every face.
  ASSERT_EQ(m.size(), 1000 - 64);
  for (std::int64_t k = 0; k < m.size(); ++k) {
    EXPECT_NEAR(m.volume[k], 1e-6, 1e-15);
    double ws = 0;
    Vec3 x{};
    for (int c = 0; c < 4; ++c) {
      ws += m.w[k][c];
      EXPECT_GE(m.w[k][c], -1e-9);
      x += m.w[k][c] * pb.model.X[m.tv[k][c]];
    }
    EXPECT_NEAR(ws, 1.0, 1e-12);
    EXPECT_NEAR(norm(x - m.x[k]), 0.0, 1e-12) << "marker " << k;
    // First layer dx/2 inside the faces, the lattice at cell centres.
    for (int a = 0; a < 3; ++a) {
      const double o = (m.x[k][a] - (a == 0 ? 0.1 : 0.0)) / dx - 0.5;
      EXPECT_NEAR(o, std::round(o), 1e-9);
    }
  }
  // The gather lists every (marker, corner) once.
  std::int64_t entries = 0;
  for (std::size_t j = 0; j + 1 < m.offset.size(); ++j) entries += m.offset[j + 1] - m.offset[j];
  EXPECT_EQ(entries, 4 * m.size());
}

constexpr const char* kCubeScene = R"(
run: {end_time: 0.01}
materials: {rubber: {E: 2.0e5, nu: 0.3, density: 800}}
bodies:
  - {name: cube, material: rubber, mesh: {type: box, origin: [0.083, 0.0, 0.0], size: [0.06, 0.06, 0.06], cells: [2, 2, 2]}, velocity: [-0.3, 0.1, 0.05]}
)";

// A fluid block with random velocities beside the cube of kCubeScene (no gravity, no walls).
FluidSetup cube_fluid(const Model& model) {
  FluidSpec spec;
  spec.present = true;
  spec.spacing = 0.01;
  spec.sound_speed = 5.0;
  spec.viscosity = 0.1;
  spec.hydrostatic_init = false;
  spec.blocks.push_back({{0, 0, 0}, {0.08, 0.06, 0.06}, 3});
  FluidSetup f = build_fluid(spec, Vec3{0, 0, 0});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uv(-0.2, 0.2);
  for (std::int64_t i = 0; i < f.n_fluid; ++i) f.v[i] = {0.4 + uv(rng), uv(rng), uv(rng)};
  add_solid_markers(f, model);
  EXPECT_GT(f.n_marker, 0);
  return f;
}

// Fluid + cube momentum stays constant to round-off through coupled steps.
double momentum_drift(int substeps, double* scale) {
  auto pb = make_problem(kCubeScene);
  const FluidSetup f = cube_fluid(pb.model);
  const SolidViews sv = pb.backend->solid_views();
  SphStage<HostExec> st(f, &sv);
  const double dt_f = 0.2 * f.params.kernel.h / 6.0;
  const double dt = std::min(dt_f, substeps * 0.5 * pb.model.dt_critical);
  Stepper stepper(pb.model, *pb.backend, dt);
  stepper.attach_fluid(&st, substeps);
  auto total = [&] {
    const HostFields h = pb.backend->download(false);
    Vec3 p = st.stats().momentum;
    double s = 0;
    for (std::int64_t i = 0; i < pb.model.n_free_vertices; ++i) {
      p += pb.model.mass[i] * h.v[i];
      s += pb.model.mass[i] * norm(h.v[i]);
    }
    const FluidHost fh = st.download();
    for (std::size_t i = 0; i < fh.x.size(); ++i)
      if (fh.type[i] == kSphFluid) s += 1000 * 1e-6 * norm(fh.v[i]);
    return std::make_pair(p, s);
  };
  const auto [p0, s0] = total();
  *scale = s0;
  double worst = 0;
  for (int k = 0; k < 40; ++k) {
    stepper.step();
    worst = std::max(worst, norm(total().first - p0));
  }
  // The fluid did push the cube: the coupling is not idle.
  EXPECT_GT(norm(st.stats().force_on_bodies), 0.0);
  return worst;
}

TEST(SphCoupling, MomentumOfFluidAndBodyIsConservedToRoundOff) {
  for (int k : {1, 3}) {
    double scale = 0;
    const double d = momentum_drift(k, &scale);
    EXPECT_LE(d, 1e-13 * scale) << "substeps " << k << ": drift " << d << " of " << scale;
    std::printf("solid substeps %d: max |P(t) - P(0)| = %.3e kg m/s (sum |m v| = %.3e)\n", k, d,
                scale);
  }
}

// The coupled step on CUDA against the CPU: fluid particles (by id) and body vertices after 20
// steps with 3 solid sub-steps each (skipped without a GPU).
TEST(SphCoupling, CudaMatchesCpu) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device: " << gpu_summary(gpu_info());
  std::vector<Vec3> fx[2], bx[2];
  const char* backends[2] = {"cpu", "cuda"};
  for (int b = 0; b < 2; ++b) {
    auto pb = make_problem(kCubeScene, "test.yaml", backends[b]);
    const FluidSetup f = cube_fluid(pb.model);
    const SolidViews sv = pb.backend->solid_views();
    auto st = make_fluid_stage(backends[b], f, &sv);
    const double dt = std::min(0.2 * f.params.kernel.h / 6.0, 3 * 0.5 * pb.model.dt_critical);
    Stepper stepper(pb.model, *pb.backend, dt);
    stepper.attach_fluid(st.get(), 3);
    for (int k = 0; k < 20; ++k) stepper.step();
    const FluidHost h = st->download();
    fx[b].resize(h.x.size());
    for (std::size_t i = 0; i < h.x.size(); ++i) fx[b][h.gid[i]] = h.x[i];
    bx[b] = pb.backend->download(false).x;
  }
  double df = 0, db = 0;
  for (std::size_t i = 0; i < fx[0].size(); ++i) df = std::max(df, norm(fx[0][i] - fx[1][i]));
  for (std::size_t i = 0; i < bx[0].size(); ++i) db = std::max(db, norm(bx[0][i] - bx[1][i]));
  std::printf("[cuda-vs-cpu] sph_coupling fluid max_abs=%.3e m body max_abs=%.3e m\n", df, db);
  EXPECT_LT(df, 1e-10);
  EXPECT_LT(db, 1e-10);
}

// Water column on a fixed QDEM floor (side walls of wall particles): at the hydrostatic start
// the fluid's force on the floor body carries the water's weight.
TEST(SphCoupling, FixedBodyFloorCarriesTheWeight) {
  auto pb = make_problem(R"(
run: {end_time: 0.01}
gravity: [0, -9.81, 0]
materials: {concrete: {E: 3.0e10, nu: 0.2, density: 2400}}
bodies:
  - {name: floor, material: concrete, fixed: true, mesh: {type: box, origin: [-0.06, -0.06, -0.06], size: [0.32, 0.06, 0.2], cells: [8, 2, 5]}}
)");
  FluidSpec spec;
  spec.present = true;
  spec.spacing = 0.02;
  spec.viscosity = 0.02;
  spec.blocks.push_back({{0, 0, 0}, {0.2, 0.2, 0.08}, 3});
  spec.walls.push_back({{-0.06, 0, -0.06}, {0, 0.26, 0.14}, 3});
  spec.walls.push_back({{0.2, 0, -0.06}, {0.26, 0.26, 0.14}, 3});
  spec.walls.push_back({{0, 0, -0.06}, {0.2, 0.26, 0}, 3});
  spec.walls.push_back({{0, 0, 0.08}, {0.2, 0.26, 0.14}, 3});
  const Vec3 g{0, -9.81, 0};
  FluidSetup f = build_fluid(spec, g);
  add_solid_markers(f, pb.model);
  double weight = 0;
  for (std::int64_t i = 0; i < f.n_fluid; ++i) weight += f.m[i] * 9.81;
  const SolidViews sv = pb.backend->solid_views();
  SphStage<HostExec> st(f, &sv);
  const Vec3 F = st.stats().force_on_bodies;
  std::printf("force on the floor %.4f N, water weight %.4f N\n", -F.y, weight);
  EXPECT_NEAR(-F.y, weight, 0.03 * weight);
  EXPECT_NEAR(F.x, 0.0, 1e-3 * weight);
}

TEST(SphCoupling, KernelWiderThanTheContactCellIsRefused) {
  const auto pb = make_problem(R"(
run: {end_time: 0.01}
materials: {rubber: {E: 1.0e6, nu: 0.3, density: 1000}}
bodies:
  - {name: plate, material: rubber, mesh: {type: box, size: [0.1, 0.1, 0.01], cells: [20, 20, 2]}}
)");
  FluidSpec spec;
  spec.present = true;
  spec.spacing = 0.02;
  spec.sound_speed = 5.0;
  spec.blocks.push_back({{0, 0, 0.02}, {0.1, 0.1, 0.1}, 3});
  FluidSetup f = build_fluid(spec, Vec3{});
  try {
    add_solid_markers(f, pb.model);
    FAIL() << "2h = 0.052 m exceeds the plate's contact cell";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("contact cell width"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace qdemsph
