// Explicit dynamics against known answers (BENCHMARKS.md section 3): exact momentum
// conservation of a free body, energy conservation of undamped vibration over 100 periods,
// the Kelvin-Voigt damping ratio zeta = eta omega / (2E) from the logarithmic decrement,
// stability at 0.9 x the dt estimate and a detected blow-up well above it, and the static
// cantilever converging toward the 3D answer under refinement.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/error.hpp"
#include "integrate/stepper.hpp"
#include "scene_fixture.hpp"

namespace qdemsph {
namespace {

using testing::make_problem;

// A clamped 1 x 0.1 x 0.1 beam; `extra` adds YAML (loads, overrides of the defaults).
std::string beam(const std::string& law, double viscosity, const std::string& cells,
                 const std::string& extra = "", const std::string& size = "[1, 0.1, 0.1]") {
  return "run: {mode: dynamic, end_time: 1.0}\n"
         "materials: {m: {law: " +
         law + ", E: 1.0e7, nu: 0.3, density: 1000, viscosity: " + std::to_string(viscosity) +
         "}}\n"
         "bodies: [{name: beam, material: m, mesh: {type: box, size: " +
         size + ", cells: " + cells +
         "}}]\n"
         "constraints: [{type: fixed, body: beam, region: {x: [-1.0e-9, 1.0e-9]}}]\n" +
         extra;
}

Vec3 momentum(const Model& m, const HostFields& h) {
  Vec3 p{0, 0, 0};
  for (std::size_t i = 0; i < h.v.size(); ++i) p += m.mass[i] * h.v[i];
  return p;
}

Vec3 angular_momentum(const Model& m, const HostFields& h) {
  Vec3 l{0, 0, 0};
  for (std::size_t i = 0; i < h.v.size(); ++i) l += m.mass[i] * cross(h.x[i], h.v[i]);
  return l;
}

TEST(Dynamics, FreeBodyConservesMomentumExactly) {
  auto pb = make_problem(R"(
run: {mode: dynamic, end_time: 1.0}
materials: {m: {law: svk, E: 1.0e6, nu: 0.3, density: 1000, viscosity: 20}}
bodies: [{name: b, material: m, mesh: {type: box, size: [0.3, 0.2, 0.1], cells: [3, 2, 1]},
          velocity: [1, -2, 0.5], angular_velocity: [3, 1, -8]}]
)");
  const HostFields h0 = pb.backend->download(false);
  const Vec3 p0 = momentum(pb.model, h0), l0 = angular_momentum(pb.model, h0);
  Stepper st(pb.model, *pb.backend, 0.9 * pb.model.dt_critical);
  for (int n = 0; n < 5000; ++n) st.step();
  const HostFields h = pb.backend->download(false);
  EXPECT_LT(norm(momentum(pb.model, h) - p0), 1e-13 * norm(p0));
  EXPECT_LT(norm(angular_momentum(pb.model, h) - l0), 1e-11 * norm(l0));
}

// Tip deflection (z) history of a beam released from rest with an initial velocity field.
TEST(Dynamics, UndampedVibrationConservesEnergyOver100Periods) {
  auto pb = make_problem(beam("svk", 0, "[10, 1, 1]"));
  for (std::size_t i = 0; i < pb.model.X.size(); ++i)
    if (pb.model.inv_mass[i] > 0) pb.model.v[i] = {0, 0, 0.05 * std::pow(pb.model.X[i].x, 2)};
  pb.backend->upload(pb.model);
  Stepper st(pb.model, *pb.backend, 0.5 * pb.model.dt_critical);
  const double e0 = pb.backend->energies().total();
  // First bending mode of this mesh: ~18 rad/s (period ~0.34 s); run 100 periods.
  const double end = 100 * 0.345;
  double drift = 0;
  while (st.time() < end) {
    for (int k = 0; k < 500; ++k) st.step();
    drift = std::max(drift, std::abs(pb.backend->energies().total() - e0) / e0);
  }
  std::printf("energy drift over %.1f s (%ld steps): %.3e\n", st.time(), (long)st.steps(), drift);
  EXPECT_LT(drift, 1e-3);
}

// Free decay after releasing a static tip load: successive maxima of the tip deflection
// give zeta (log decrement) and omega; stiffness-proportional Kelvin-Voigt damping
// predicts zeta = eta omega / (2 E) for each mode. The section is 0.2 x 0.1 so the two
// bending modes are well apart: with a square section they are degenerate, the mesh's
// asymmetry couples them and energy beats between y and z, which a decrement misreads.
TEST(Dynamics, KelvinVoigtLogDecrementMatchesTheory) {
  const double E = 1e7, eta = 2e4;
  auto pb =
      make_problem(beam("linear", eta, "[10, 2, 1]",
                        "loads: [{type: traction, body: beam, region: {x: [0.999999, 1.000001]},"
                        " traction: [0, 0, -100], preload: true}]\n",
                        "[1, 0.2, 0.1]"));
  Stepper st(pb.model, *pb.backend, 0.5 * pb.model.dt_critical);
  ASSERT_TRUE(st.relax(1e-8, 1000000, true).converged);
  std::vector<std::int64_t> tip;
  for (std::int64_t i = 0; i < pb.model.n_vertices(); ++i)
    if (pb.model.X[i].x > 0.999999) tip.push_back(i);
  auto tip_z = [&] {
    const HostFields h = pb.backend->download(false);
    double s = 0;
    for (auto i : tip) s += h.x[i].z - pb.model.X[i].z;
    return s / tip.size();
  };
  std::vector<double> t, w;
  while (st.time() < 2.0) {
    st.step();
    t.push_back(st.time());
    w.push_back(tip_z());
  }
  std::vector<double> pt, pa;  // maxima of -w (deflection is negative at release)
  for (std::size_t k = 1; k + 1 < w.size(); ++k)
    if (-w[k] > -w[k - 1] && -w[k] >= -w[k + 1] && -w[k] > 0) {
      pt.push_back(t[k]);
      pa.push_back(-w[k]);
    }
  ASSERT_GE(pa.size(), 4u);
  const int n = static_cast<int>(pa.size()) - 1;
  const double delta = std::log(pa[0] / pa[n]) / n;
  const double zeta = delta / std::sqrt(4 * M_PI * M_PI + delta * delta);
  const double omega_d = 2 * M_PI * n / (pt[n] - pt[0]);
  const double omega = omega_d / std::sqrt(1 - zeta * zeta);
  const double expect = eta * omega / (2 * E);
  std::printf("log decrement: zeta %.5f, eta omega/(2E) %.5f (omega %.3f rad/s)\n", zeta, expect,
              omega);
  EXPECT_NEAR(zeta, expect, 0.05 * expect);
}

TEST(Dynamics, StableAtNineTenthsOfTheEstimate) {
  auto pb = make_problem(beam("svk", 0, "[10, 1, 1]"));
  for (std::size_t i = 0; i < pb.model.X.size(); ++i)
    if (pb.model.inv_mass[i] > 0) pb.model.v[i] = {0.01, -0.02, 0.05 * pb.model.X[i].x};
  pb.backend->upload(pb.model);
  Stepper st(pb.model, *pb.backend, 0.9 * pb.model.dt_critical);
  const double e0 = pb.backend->energies().total();
  for (int n = 0; n < 50000; ++n) st.step();
  EXPECT_LT(std::abs(pb.backend->energies().total() - e0) / e0, 1e-2);
}

TEST(Dynamics, BlowUpAboveTheLimitIsDetectedAndNamed) {
  auto pb = make_problem(beam("svk", 0, "[10, 1, 1]"));
  for (std::size_t i = 0; i < pb.model.X.size(); ++i)
    if (pb.model.inv_mass[i] > 0) pb.model.v[i] = {0, 0, 0.05 * pb.model.X[i].x};
  pb.backend->upload(pb.model);
  Stepper st(pb.model, *pb.backend, 3.0 * pb.model.dt_critical);
  try {
    for (int n = 0; n < 100000; ++n) st.step();
    FAIL() << "no blow-up detected at 3 x the stability limit";
  } catch (const SimulationError& e) {
    const std::string msg = e.what();
    std::printf("detected: %s\n", msg.c_str());
    EXPECT_NE(msg.find("body 'beam'"), std::string::npos);
    EXPECT_NE(msg.find("stability limit"), std::string::npos);
  }
}

TEST(Dynamics, FixedDtAboveTheLimitIsAnInputError) {
  auto pb = make_problem(beam("svk", 0, "[4, 1, 1]"));
  EXPECT_THROW(choose_dt(pb.model, 1.01 * pb.model.dt_critical, 0.5), InputError);
  EXPECT_DOUBLE_EQ(choose_dt(pb.model, std::nullopt, 0.5), 0.5 * pb.model.dt_critical);
}

// Linear law, static, P = 1 N shear on the tip: refinement converges toward the 3D answer
// (linear tets are too stiff in bending; BENCHMARKS.md section 1).
TEST(Statics, CantileverTipDeflectionConvergesUnderRefinement) {
  const double E = 1e7, nu = 0.3, L = 1, b = 0.1, P = 1;
  const double I = b * b * b * b / 12, eb = P * L * L * L / (3 * E * I);
  const double k = 10 * (1 + nu) / (12 + 11 * nu), G = E / (2 * (1 + nu));
  const double timo = eb + P * L / (k * G * b * b);
  std::vector<double> tip;
  for (const char* cells : {"[5, 1, 1]", "[10, 1, 1]", "[20, 2, 2]"}) {
    auto pb =
        make_problem(beam("linear", 0, cells,
                          "loads: [{type: traction, body: beam, region: {x: [0.999999, 1.000001]},"
                          " traction: [0, 0, -100]}]\n"));
    Stepper st(pb.model, *pb.backend, 0.5 * pb.model.dt_critical);
    const RelaxResult r = st.relax(1e-8, 2000000, false);
    ASSERT_TRUE(r.converged);
    const HostFields h = pb.backend->download(false);
    double w = 0;
    int n = 0;
    for (std::int64_t i = 0; i < pb.model.n_vertices(); ++i)
      if (pb.model.X[i].x > 0.999999) {
        w += h.x[i].z - pb.model.X[i].z;
        ++n;
      }
    tip.push_back(-w / n);
    std::printf("cells %-10s tip %.5e  /EB %.4f  /Timoshenko %.4f  (%ld DR steps)\n", cells,
                tip.back(), tip.back() / eb, tip.back() / timo, (long)r.iterations);
  }
  for (std::size_t k = 1; k < tip.size(); ++k) EXPECT_GT(tip[k], tip[k - 1]);
  EXPECT_LT(tip.back(), timo);
  EXPECT_LT(timo - tip[2], 0.7 * (timo - tip[1]));  // error shrinks under refinement
}

}  // namespace
}  // namespace qdemsph
