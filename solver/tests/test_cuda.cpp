// The CUDA backend against the CPU backend, stage by stage, on one model that exercises
// every branch: two free bodies (SVK and linear law, both viscoelastic), a fixed body
// (stored last, never integrated), fixed and velocity constraints, traction and point loads,
// a preload, gravity and mass damping, with a perturbed initial state so every force term
// is non-zero. Each test runs the same calls on both backends and compares what the host
// sees; the measured differences are printed as "[cuda-vs-cpu] name max_rel=..." lines that
// ci/gpu_session.sh collects. All tests SKIP when no GPU is visible (CI, build machines).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "core/gpu_info.hpp"
#include "core/memory.hpp"
#include "integrate/backend.hpp"
#include "integrate/stepper.hpp"
#include "io/scene_yaml.hpp"
#include "model/model.hpp"

namespace qdemsph {
namespace {

#define SKIP_WITHOUT_GPU() \
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device: " << gpu_summary(gpu_info())

constexpr const char* kScene = R"(
name: cuda_check
run: {mode: dynamic, end_time: 1.0}
gravity: [0, 0, -9.81]
damping: {mass: 0.5}
materials:
  rubber: {law: svk, E: 1.0e7, nu: 0.3, density: 1000, viscosity: 100}
  steel: {law: linear, E: 2.0e8, nu: 0.25, density: 2000, viscosity: 10}
bodies:
  - name: beam
    material: rubber
    mesh: {type: box, origin: [0, 0, 0], size: [1.0, 0.1, 0.1], cells: [20, 3, 3]}
    velocity: [0.1, 0, 0.2]
    angular_velocity: [0, 1.0, 0]
  - name: block
    material: steel
    mesh: {type: box, origin: [0, 0.5, 0], size: [0.2, 0.2, 0.2], cells: [3, 3, 3]}
  - name: floor
    material: steel
    fixed: true
    mesh: {type: box, origin: [0, 0, -0.5], size: [1, 1, 0.1], cells: [2, 2, 1]}
constraints:
  - {type: fixed, body: beam, region: {x: [0, 0]}}
  - {type: velocity, body: block, region: {z: [0, 0]}, velocity: [0, 0, 0.01]}
loads:
  - {type: traction, body: beam, region: {x: [1, 1]}, traction: [0, 0, -2.0e3]}
  - {type: traction, body: beam, region: {x: [1, 1]}, traction: [0, 1.0e3, 0], preload: true}
  - {type: point, body: block, at: [0.2, 0.7, 0.2], force: [1, 0, 0]}
)";

// The scene's model with a small smooth-plus-random perturbation of positions and velocities
// on free, unconstrained vertices (the same numbers for both backends).
Model test_model() {
  Model m = build_model(parse_scene(kScene, "test_cuda.yaml"));
  // Element and integration stages only: the contact stage joins this comparison when it
  // runs on CUDA (the bodies here do not touch during these tests).
  m.contact.enabled = false;
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::int64_t i = 0; i < m.n_free_vertices; ++i) {
    if (!(m.inv_mass[i] > 0)) continue;
    const Vec3 X = m.X[i];
    m.x[i] = X + Vec3{1e-3 * X.x * X.z + 1e-5 * u(rng), 1e-5 * u(rng),
                      -2e-3 * X.x * X.x + 1e-5 * u(rng)};
    m.v[i] = m.v[i] + Vec3{0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng)};
  }
  return m;
}

struct Pair {
  std::unique_ptr<Backend> cpu, gpu;
};

Pair make_pair(const Model& m) {
  Pair p{make_host_backend(), make_cuda_backend()};
  p.cpu->upload(m);
  p.gpu->upload(m);
  return p;
}

// max |a - b| / max |b| over all vertices (0 when both are zero).
double rel_diff(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0, s = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    d = std::max(d, norm(a[i] - b[i]));
    s = std::max(s, norm(b[i]));
  }
  return s > 0 ? d / s : d;
}

double rel_diff(double a, double b, double scale) {
  return scale > 0 ? std::fabs(a - b) / scale : std::fabs(a - b);
}

std::vector<Vec3> displacement(const std::vector<Vec3>& x, const Model& m) {
  std::vector<Vec3> u(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) u[i] = x[i] - m.X[i];
  return u;
}

void report(const std::string& name, double rel) {
  std::printf("[cuda-vs-cpu] %s max_rel=%.3e\n", name.c_str(), rel);
  std::fflush(stdout);
}

// Forces are read back through kick from v: v' = v + h f / m, so (v' - v) / h = f / m.
std::vector<Vec3> accel(Backend& be, double h) {
  const auto v0 = be.download(false).v;
  be.kick(h);
  auto v1 = be.download(false).v;
  for (std::size_t i = 0; i < v1.size(); ++i) v1[i] = (v1[i] - v0[i]) / h;
  return v1;
}

TEST(Cuda, DeviceIsReported) {
  SKIP_WITHOUT_GPU();
  const GpuInfo g = gpu_info();
  EXPECT_TRUE(g.available);
  EXPECT_GT(g.total_bytes, 0u);
  EXPECT_GT(g.sm_count, 0);
  std::printf("[cuda] %s\n", gpu_summary(g).c_str());
}

TEST(Cuda, BuffersRoundTripAndZero) {
  SKIP_WITHOUT_GPU();
  std::vector<double> h(100003);
  for (std::size_t i = 0; i < h.size(); ++i) h[i] = std::sin(0.1 * i);
  Buffer<double> d(Space::Cuda);
  d.assign(h);
  EXPECT_EQ(d.to_host(), h);
  d.zero();
  for (double v : d.to_host()) ASSERT_EQ(v, 0.0);
  Vec3Buffer vb(Space::Cuda);
  std::vector<Vec3> hv = {{1, 2, 3}, {4, 5, 6}};
  vb.assign(hv);
  const auto back = vb.to_host();
  EXPECT_EQ(back[1].y, 5.0);
}

TEST(Cuda, ElementForcesMatchCpu) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  for (bool preload : {false, true}) {
    Pair p = make_pair(m);
    p.cpu->use_preload(preload);
    p.gpu->use_preload(preload);
    p.cpu->compute_forces(1e-5, m.mass_damping);
    p.gpu->compute_forces(1e-5, m.mass_damping);
    EXPECT_EQ(p.cpu->take_inverted_tet(), -1);
    EXPECT_EQ(p.gpu->take_inverted_tet(), -1);
    const double d = rel_diff(accel(*p.gpu, 1e-3), accel(*p.cpu, 1e-3));
    report(preload ? "element_forces_preload" : "element_forces", d);
    EXPECT_LT(d, 1e-10);
  }
}

TEST(Cuda, StaticStatsMatchCpu) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  Pair p = make_pair(m);
  for (Backend* be : {p.cpu.get(), p.gpu.get()}) {
    be->compute_forces(0.0, 0.0);
    be->mark_relax_start();
    be->damped_step(2e-5, 10.0);
    be->compute_forces(0.0, 0.0);
  }
  const StaticStats c = p.cpu->static_stats(), g = p.gpu->static_stats();
  const double dr = rel_diff(g.residual_max, c.residual_max, c.residual_max);
  const double dn = rel_diff(g.rayleigh_num, c.rayleigh_num, std::fabs(c.rayleigh_num));
  const double dd = rel_diff(g.rayleigh_den, c.rayleigh_den, c.rayleigh_den);
  report("static_stats.residual_max", dr);
  report("static_stats.rayleigh_num", dn);
  report("static_stats.rayleigh_den", dd);
  EXPECT_LT(dr, 1e-10);
  EXPECT_LT(dn, 1e-10);
  EXPECT_LT(dd, 1e-12);
  EXPECT_GT(c.residual_max, 0.0);
  // Reductions on the GPU are deterministic: the same bits on a second call.
  const StaticStats g2 = p.gpu->static_stats();
  EXPECT_EQ(g2.residual_max, g.residual_max);
  EXPECT_EQ(g2.rayleigh_num, g.rayleigh_num);
  EXPECT_EQ(g2.rayleigh_den, g.rayleigh_den);
}

TEST(Cuda, IntegrationMatchesCpu) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  Pair p = make_pair(m);
  double worst = 0;
  for (Backend* be : {p.cpu.get(), p.gpu.get()}) {
    be->compute_forces(1e-5, m.mass_damping);
    be->kick(2e-5);
    be->drift(4e-5);
    be->damped_step(3e-5, 50.0);
  }
  auto c = p.cpu->download(false), g = p.gpu->download(false);
  const double dx = rel_diff(displacement(g.x, m), displacement(c.x, m));
  const double dv = rel_diff(g.v, c.v);
  report("integration.x", dx);
  report("integration.v", dv);
  worst = std::max(dx, dv);
  EXPECT_LT(worst, 1e-10);
  p.cpu->zero_velocity();
  p.gpu->zero_velocity();
  c = p.cpu->download(false);
  g = p.gpu->download(false);
  EXPECT_EQ(rel_diff(g.v, c.v), 0.0);
  for (std::int64_t i = 0; i < m.n_free_vertices; ++i)
    if (m.inv_mass[i] > 0) ASSERT_EQ(norm(g.v[i]), 0.0) << i;
  // Velocity-constrained vertices keep their prescribed velocity; fixed bodies never move.
  for (std::int64_t i = 0; i < m.n_vertices(); ++i)
    if (!(m.inv_mass[i] > 0)) ASSERT_EQ(norm(g.v[i] - m.v[i]), 0.0) << i;
  for (std::int64_t i = m.n_free_vertices; i < m.n_vertices(); ++i)
    ASSERT_EQ(norm(g.x[i] - m.x[i]), 0.0) << i;
}

TEST(Cuda, EnergiesMatchCpu) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  Pair p = make_pair(m);
  for (Backend* be : {p.cpu.get(), p.gpu.get()}) {
    be->compute_forces(1e-5, m.mass_damping);
    for (int s = 0; s < 20; ++s) {
      be->kick(0.5e-5);
      be->drift(1e-5);
      be->compute_forces(1e-5, m.mass_damping);
      be->kick(0.5e-5);
    }
  }
  const Energies c = p.cpu->energies(), g = p.gpu->energies();
  const double scale =
      std::fabs(c.kinetic) + std::fabs(c.strain) + std::fabs(c.potential) + std::fabs(c.dissipated);
  const double dk = rel_diff(g.kinetic, c.kinetic, scale);
  const double ds = rel_diff(g.strain, c.strain, scale);
  const double dp = rel_diff(g.potential, c.potential, scale);
  const double dd = rel_diff(g.dissipated, c.dissipated, scale);
  report("energies.kinetic", dk);
  report("energies.strain", ds);
  report("energies.potential", dp);
  report("energies.dissipated", dd);
  EXPECT_GT(c.strain, 0.0);
  EXPECT_GT(c.dissipated, 0.0);
  EXPECT_LT(std::max({dk, ds, dp, dd}), 1e-10);
  const Energies g2 = p.gpu->energies();
  EXPECT_EQ(g2.total(), g.total());
}

TEST(Cuda, DownloadWithStressMatchesCpu) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  Pair p = make_pair(m);
  const HostFields c = p.cpu->download(true), g = p.gpu->download(true);
  ASSERT_EQ(g.stress.size(), c.stress.size());
  ASSERT_EQ(g.von_mises.size(), static_cast<std::size_t>(m.n_tets()));
  double d = 0, s = 0, dvm = 0, svm = 0;
  for (std::size_t t = 0; t < c.stress.size(); ++t) {
    for (int k = 0; k < 6; ++k) {
      d = std::max(d, std::fabs(g.stress[t][k] - c.stress[t][k]));
      s = std::max(s, std::fabs(c.stress[t][k]));
    }
    dvm = std::max(dvm, std::fabs(g.von_mises[t] - c.von_mises[t]));
    svm = std::max(svm, std::fabs(c.von_mises[t]));
  }
  report("download.stress", d / s);
  report("download.von_mises", dvm / svm);
  EXPECT_GT(s, 0.0);
  EXPECT_LT(d / s, 1e-10);
  EXPECT_LT(dvm / svm, 1e-10);
  EXPECT_EQ(rel_diff(g.x, c.x), 0.0);
  EXPECT_EQ(rel_diff(g.v, c.v), 0.0);
  EXPECT_EQ(p.gpu->device_bytes(), p.cpu->device_bytes());
}

TEST(Cuda, FlagsNameTheSameOffender) {
  SKIP_WITHOUT_GPU();
  Model m = test_model();
  // Invert a tet of the beam: reflect its 4th vertex through the centroid of the face
  // opposite, which flips the sign of det F.
  const std::int64_t t = 37;
  const auto tv = m.tets[t];
  const Vec3 c = (m.x[tv[0]] + m.x[tv[1]] + m.x[tv[2]]) / 3.0;
  m.x[tv[3]] = 2.0 * c - m.x[tv[3]];
  Pair p = make_pair(m);
  p.cpu->compute_forces(0.0, 0.0);
  p.gpu->compute_forces(0.0, 0.0);
  const std::int64_t tc = p.cpu->take_inverted_tet(), tg = p.gpu->take_inverted_tet();
  EXPECT_GE(tc, 0);
  EXPECT_GE(tg, 0);
  EXPECT_EQ(p.gpu->take_inverted_tet(), -1);  // taking clears the flag
  // A non-finite velocity on one vertex: both report it (the largest offender index).
  Model n = test_model();
  n.v[123].y = std::nan("");
  n.x[77].x = INFINITY;
  Pair q = make_pair(n);
  EXPECT_EQ(q.cpu->find_non_finite(), 123);
  EXPECT_EQ(q.gpu->find_non_finite(), 123);
  Pair r = make_pair(test_model());
  EXPECT_EQ(r.gpu->find_non_finite(), -1);
}

TEST(Cuda, ElementOnlyRunOf1000StepsAgreesToRoundOff) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  Pair p = make_pair(m);
  const double dt = 0.5 * m.dt_critical;
  Stepper sc(m, *p.cpu, dt), sg(m, *p.gpu, dt);
  for (int n = 0; n < 1000; ++n) {
    sc.step();
    sg.step();
  }
  const HostFields c = p.cpu->download(false), g = p.gpu->download(false);
  const double dx = rel_diff(displacement(g.x, m), displacement(c.x, m));
  const double dv = rel_diff(g.v, c.v);
  const Energies ec = p.cpu->energies(), eg = p.gpu->energies();
  const double scale = std::fabs(ec.kinetic) + std::fabs(ec.strain) + std::fabs(ec.potential) +
                       std::fabs(ec.dissipated);
  const double de = rel_diff(eg.total(), ec.total(), scale);
  report("run1000.displacement", dx);
  report("run1000.velocity", dv);
  report("run1000.energy_total", de);
  EXPECT_LT(dx, 1e-9);
  EXPECT_LT(dv, 1e-8);
  EXPECT_LT(de, 1e-9);
}

TEST(Cuda, DynamicRelaxationMatchesCpu) {
  SKIP_WITHOUT_GPU();
  const Model m = test_model();
  Pair p = make_pair(m);
  const double dt = 0.5 * m.dt_critical;
  Stepper sc(m, *p.cpu, dt), sg(m, *p.gpu, dt);
  const RelaxResult rc = sc.relax(1e-6, 200000, true), rg = sg.relax(1e-6, 200000, true);
  EXPECT_TRUE(rc.converged);
  EXPECT_TRUE(rg.converged);
  const double dx = rel_diff(displacement(p.gpu->download(false).x, m),
                             displacement(p.cpu->download(false).x, m));
  report("relax.displacement", dx);
  std::printf("[cuda-vs-cpu] relax.iterations cpu=%lld gpu=%lld\n",
              static_cast<long long>(rc.iterations), static_cast<long long>(rg.iterations));
  EXPECT_LT(dx, 1e-5);  // both stop at residual <= 1e-6 of the load, not at the same step
}

}  // namespace
}  // namespace qdemsph
