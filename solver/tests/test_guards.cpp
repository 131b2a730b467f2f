// Run-time guards beyond NaN and inverted tets (issue 11): the current stability limit of
// the deformed tets (Backend::critical_tet against a host computation), contacts crossed
// beyond contact.max_penetration, and a fluid step above the fluid's stability limits.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "integrate/stepper.hpp"
#include "physics/element.hpp"
#include "scene_fixture.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/sph_stage.hpp"

namespace qdemsph {
namespace {

using testing::make_problem;

// A 0.1 m cube clamped at z = 0 whose top is pushed down at `speed` (the hard_guards case).
std::string crushed_cube(double speed) {
  return R"(
run: {end_time: 1}
materials: {soft: {law: svk, E: 1.0e6, nu: 0.3, density: 1000}}
bodies:
  - {name: cube, material: soft, mesh: {type: box, size: [0.1, 0.1, 0.1], cells: [2, 2, 2]}}
constraints:
  - {type: fixed, body: cube, region: {z: [-1.0e-9, 1.0e-9]}}
  - {type: velocity, body: cube, region: {z: [0.099999999, 0.100000001]}, velocity: [0, 0, )" +
         std::to_string(-speed) + R"(]}
)";
}

double host_critical_dt(const Model& m, const std::vector<Vec3>& x, std::int64_t* tet) {
  double best = INFINITY;
  for (std::int64_t t = 0; t < m.n_free_tets; ++t) {
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = x[m.tets[t][k]];
    const double dt = tet_critical_dt(m.materials[m.tet_material[t]], min_altitude(p));
    if (dt < best) {
      best = dt;
      *tet = t;
    }
  }
  return best;
}

TEST(Guards, CriticalTetMatchesTheHostAtRestAndDeformed) {
  auto pb = make_problem(crushed_cube(2.0));
  CriticalTet c = pb.backend->critical_tet(true);
  EXPECT_EQ(c.dt, pb.model.dt_critical);  // no contact: the model's limit is the tets'
  EXPECT_EQ(c.tet, pb.model.dt_critical_tet);
  Stepper st(pb.model, *pb.backend, 0.5 * pb.model.dt_critical);
  for (int n = 0; n < 20; ++n) st.step();
  std::int64_t t = -1;
  const double ref = host_critical_dt(pb.model, pb.backend->download(false).x, &t);
  c = pb.backend->critical_tet(true);
  EXPECT_EQ(c.dt, ref);
  EXPECT_EQ(c.tet, t);
  EXPECT_LT(c.dt, pb.model.dt_critical);  // the squeezed tets are thinner
  EXPECT_EQ(pb.backend->critical_tet(false).dt, c.dt);
}

TEST(Guards, CrushedTetStopsAtItsStabilityLimitBeforeItInverts) {
  auto pb = make_problem(crushed_cube(0.2));
  Stepper st(pb.model, *pb.backend, 0.9 * pb.model.dt_critical);
  try {
    for (int n = 0; n < 100000; ++n) st.step();
    FAIL() << "the crushed cube ran on";
  } catch (const SimulationError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("exceeds the stability limit"), std::string::npos) << msg;
    EXPECT_NE(msg.find("body 'cube'"), std::string::npos) << msg;
    std::int64_t t = -1;
    const double lim = host_critical_dt(pb.model, pb.backend->download(false).x, &t);
    EXPECT_LT(lim, st.dt()) << msg;
    EXPECT_NE(msg.find(describe_tet(pb.model, t)), std::string::npos) << msg;
  }
}

// A small cube thrown at a fixed block with a contact ~1e4 x too soft sinks into it.
std::string soft_impact(const std::string& contact_extra) {
  return R"(
run: {end_time: 1}
materials: {steel: {law: svk, E: 1.0e7, nu: 0.3, density: 1000}}
bodies:
  - {name: block, material: steel, fixed: true,
     mesh: {type: box, origin: [-0.1, -0.1, -0.1], size: [0.2, 0.2, 0.1], cells: [4, 4, 2]}}
  - {name: cube, material: steel, velocity: [0, 0, -5],
     mesh: {type: box, origin: [-0.025, -0.025, 0.002], size: [0.05, 0.05, 0.05], cells: [2, 2, 2]}}
contact: {d_dem: 0.001, stiffness_factor: 1.0e-5)" +
         contact_extra + R"(}
)";
}

TEST(Guards, ContactCrossedBeyondTheBoundStops) {
  auto pb = make_problem(soft_impact(""));
  const ContactModel& c = pb.model.contact;
  const double bound = 0.5 * std::min(c.body_h[0], c.body_h[1]);
  Stepper st(pb.model, *pb.backend, choose_dt(pb.model, std::nullopt, 0.5));
  try {
    for (int n = 0; n < 200000; ++n) st.step();
    FAIL() << "no penetration detected";
  } catch (const SimulationError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("body 'cube' and body 'block'"), std::string::npos) << msg;
    EXPECT_NE(msg.find(fmt::format("{:.3e} m (contact.max_penetration)", bound)), std::string::npos)
        << msg;
    // Caught within the check interval: the cube is 5 m/s x 10 steps past the bound at most.
    const auto x = pb.backend->download(false).x;
    double zmin = INFINITY;
    for (const BodyRange& b : pb.model.bodies)
      if (b.name == "cube")
        for (std::int64_t i = b.v_begin; i < b.v_end; ++i) zmin = std::min(zmin, x[i].z);
    EXPECT_LT(zmin, -bound);
    EXPECT_GT(zmin, -bound - 10 * 5.0 * st.dt() - 1e-12);
  }
}

TEST(Guards, ALooserBoundLetsTheSameImpactRun) {
  auto pb = make_problem(soft_impact(", max_penetration: 1.0"));
  Stepper st(pb.model, *pb.backend, choose_dt(pb.model, std::nullopt, 0.5));
  EXPECT_NO_THROW(for (int n = 0; n < 400; ++n) st.step());
}

TEST(Guards, FluidFasterThanItsStabilityLimitStops) {
  // A fluid block in free fall with a sound speed chosen for its resting height: the fall
  // speed soon dominates the CFL limit.
  FluidSpec spec;
  spec.present = true;
  spec.spacing = 0.01;
  spec.sound_speed = 1.0;
  spec.blocks.push_back({{0, 0, 0}, {0.04, 0.04, 0.04}, 3});
  const Vec3 g{0, 0, -9.81};
  const FluidSetup f = build_fluid(spec, g);
  SphStage<HostExec> fluid(f);
  Model empty;
  empty.gravity = g;
  auto be = make_backend("cpu");
  be->upload(empty);
  const double h = f.params.kernel.h, dt0 = 0.25 * h / (1.0 + std::sqrt(2 * 9.81 * 0.04));
  Stepper st(empty, *be, dt0);
  st.attach_fluid(&fluid);
  try {
    for (int n = 0; n < 100000; ++n) st.step();
    FAIL() << "the falling fluid ran on";
  } catch (const SimulationError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("exceeds 2 x the fluid's stability limit"), std::string::npos) << msg;
    EXPECT_NE(msg.find("SPH particle"), std::string::npos) << msg;
    // CFL: 0.25 h / (c + v) < dt0 / 2 once the fall speed v passes 2 (c + sqrt(2 g H)) - c;
    // the block also spreads (its pressure is not balanced), so its fastest particle gets
    // there a little before the free fall does.
    const double v_trip = 2 * (1.0 + std::sqrt(2 * 9.81 * 0.04)) - 1.0;
    const double t_trip = v_trip / 9.81;
    EXPECT_GT(st.time(), 0.9 * t_trip) << msg;
    // within one interval of the step-limit guard
    EXPECT_LT(st.time(), t_trip + (10 * Stepper::kDtGuardChecks + 1) * dt0) << msg;
  }
}

}  // namespace
}  // namespace qdemsph
