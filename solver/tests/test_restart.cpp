// Checkpoint/restart (integrate/restart.hpp, io/checkpoint_h5.hpp): 2N steps equal N steps,
// a checkpoint written to disk, a fresh model/backend/stepper restored from it, and N more
// steps, bit for bit, for an element-only scene, a contact scene (sliding on a wall plus an
// impact with friction: point-face, edge-edge and wall history) and an SPH scene. A checkpoint
// of another scene is refused with a message naming what differs; the series keeps the last K.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>

#include "contact/contact_record.hpp"
#include "core/error.hpp"
#include "integrate/restart.hpp"
#include "integrate/stepper.hpp"
#include "io/checkpoint_h5.hpp"
#include "scene_fixture.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;
using testing::make_problem;
using testing::scratch_dir;

// A scene's whole simulation: model, backend, optional fluid, stepper.
struct Sim {
  testing::Problem p;
  std::optional<FluidSetup> fluid_setup;
  std::unique_ptr<FluidStage> fluid;
  double dt = 0;
  std::unique_ptr<Stepper> st;

  explicit Sim(const std::string& yaml) : p(make_problem(yaml)) {
    dt = choose_dt(p.model, p.scene.run.dt, p.scene.run.dt_safety);
    if (p.scene.fluid.present) {
      fluid_setup = build_fluid(p.scene.fluid, p.scene.gravity);
      fluid = make_fluid_stage("cpu", *fluid_setup);
    }
    st = std::make_unique<Stepper>(p.model, *p.backend, dt);
    if (fluid) st->attach_fluid(fluid.get());
  }
  void steps(int n) {
    for (int k = 0; k < n; ++k) st->step();
  }
  FluidSetup* setup() { return fluid_setup ? &*fluid_setup : nullptr; }
  Checkpoint capture() {
    return capture_checkpoint(p.scene, p.model, dt, *p.backend, fluid.get(), setup(), *st);
  }
  void restore(const Checkpoint& c) {
    restore_checkpoint(c, "test.h5", p.scene, p.model, dt, *p.backend, fluid.get(), setup(), *st);
  }
};

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Runs 2N steps straight and N + checkpoint file + restart + N; everything must be identical.
// Returns the checkpoint (to look at what it held).
Checkpoint expect_bit_identical_restart(const std::string& yaml, int n, const std::string& name) {
  Sim straight(yaml);
  straight.steps(2 * n);

  const fs::path file = scratch_dir("restart") / (name + ".h5");
  {
    Sim first(yaml);
    first.steps(n);
    write_checkpoint(file, first.capture());
  }
  const Checkpoint c = read_checkpoint(file);
  Sim second(yaml);
  second.restore(c);
  second.steps(n);

  EXPECT_EQ(second.st->steps(), straight.st->steps());
  EXPECT_EQ(second.st->time(), straight.st->time());
  const BackendState a = straight.p.backend->save_state(), b = second.p.backend->save_state();
  EXPECT_TRUE(same_bits(a.x, b.x)) << name << ": positions differ";
  EXPECT_TRUE(same_bits(a.v, b.v)) << name << ": velocities differ";
  EXPECT_TRUE(same_bits(a.f, b.f)) << name << ": forces differ";
  EXPECT_TRUE(same_bits(a.diss_v, b.diss_v)) << name;
  EXPECT_TRUE(same_bits(a.diss_t, b.diss_t)) << name;
  EXPECT_EQ(a.contact.has_value(), b.contact.has_value());
  if (a.contact && b.contact) {
    EXPECT_EQ(a.contact->k1, b.contact->k1) << name;
    EXPECT_EQ(a.contact->k2, b.contact->k2) << name;
    EXPECT_EQ(a.contact->active, b.contact->active) << name;
    EXPECT_TRUE(same_bits(a.contact->xi, b.contact->xi)) << name << ": tangential springs differ";
    EXPECT_TRUE(same_bits(a.contact->h, b.contact->h)) << name << ": non-potential forces differ";
    EXPECT_TRUE(same_bits(a.contact->energy, b.contact->energy)) << name;
    EXPECT_TRUE(same_bits(a.contact->energy_t, b.contact->energy_t)) << name;
    EXPECT_EQ(a.contact->v, b.contact->v) << name;
    EXPECT_EQ(a.contact->dissipated, b.contact->dissipated) << name;
    EXPECT_EQ(a.contact->rebuilds, b.contact->rebuilds) << name;
    EXPECT_EQ(a.contact->max_overlap_ever, b.contact->max_overlap_ever) << name;
  }
  const Energies ea = straight.p.backend->energies(), eb = second.p.backend->energies();
  EXPECT_EQ(ea.total(), eb.total()) << name;
  EXPECT_EQ(ea.dissipated, eb.dissipated) << name;
  EXPECT_EQ(ea.contact, eb.contact) << name;
  EXPECT_EQ(ea.contact_dissipated, eb.contact_dissipated) << name;
  if (straight.fluid) {
    const FluidState fa = straight.fluid->save_state(), fb = second.fluid->save_state();
    EXPECT_EQ(fa.gid, fb.gid) << name << ": particle order differs";
    EXPECT_TRUE(same_bits(fa.x, fb.x)) << name << ": fluid positions differ";
    EXPECT_TRUE(same_bits(fa.v, fb.v)) << name << ": fluid velocities differ";
    EXPECT_TRUE(same_bits(fa.rho, fb.rho)) << name << ": fluid densities differ";
  }
  return c;
}

const char* kBeam = R"(
run: {end_time: 1}
gravity: [0, 0, -9.81]
damping: {mass: 2.0}
materials: {rubber: {E: 1.0e6, nu: 0.3, density: 1000, viscosity: 20}}
bodies: [{name: beam, material: rubber, mesh: {type: box, size: [0.4, 0.05, 0.05], cells: [8, 1, 1]}}]
constraints: [{type: fixed, body: beam, region: {x: [0, 0]}}]
loads: [{type: point, body: beam, at: [0.4, 0.025, 0.05], force: [0, 0, -2]}]
)";

// Cube a slides on the floor (friction) into cube b, spinning: wall, point-face and edge-edge
// contacts with tangential history.
const char* kSlideImpact = R"(
run: {end_time: 1}
gravity: [0, 0, -9.81]
materials: {rubber: {E: 1.0e6, nu: 0.3, density: 1000}}
contact: {mu: 0.5, restitution: 0.5, d_dem: 0.001}
walls: [{point: [0, 0, 0], normal: [0, 0, 1], mu: 0.4}]
bodies:
  - {name: a, material: rubber, mesh: {type: box, origin: [0, 0, 0.000999], size: [0.05, 0.05, 0.05], cells: [2, 2, 2]},
     velocity: [2.0, 0.4, 0], angular_velocity: [0, 0, 5]}
  - {name: b, material: rubber, mesh: {type: box, origin: [0.052, 0.01, 0.000999], size: [0.05, 0.05, 0.05], cells: [2, 2, 2]}}
)";

const char* kDam = R"(
run: {end_time: 1, dt: 2.0e-4}
gravity: [0, 0, -9.81]
fluid:
  spacing: 0.02
  blocks: [{min: [0, 0, 0], max: [0.12, 0.06, 0.08]}]
  tanks: [{min: [0, 0, 0], max: [0.24, 0.06, 0.12], thickness_layers: 2}]
)";

TEST(Restart, ElementSceneContinuesBitIdentically) {
  const Checkpoint c = expect_bit_identical_restart(kBeam, 300, "beam");
  EXPECT_FALSE(c.solid.contact.has_value());
  EXPECT_GT(c.solid.diss_t[0], 0.0);  // the viscous accumulator is part of the state
}

TEST(Restart, ContactSceneContinuesBitIdentically) {
  Sim probe(kSlideImpact);
  const double dt = probe.dt;
  // Restart in the middle of the impact (a arrives after ~1 ms) with wall contacts too.
  const int n = static_cast<int>(0.0015 / dt) + 1;
  const Checkpoint c = expect_bit_identical_restart(kSlideImpact, n, "slide_impact");
  ASSERT_TRUE(c.solid.contact.has_value());
  int by_type[3] = {0, 0, 0};
  for (const GlobalContactKey& k : c.contact_keys) ++by_type[k.type];
  EXPECT_GT(by_type[kWall], 0) << "no wall contact at the checkpoint";
  EXPECT_GT(by_type[kPointFace] + by_type[kEdgeEdge], 0) << "no body contact at the checkpoint";
  EXPECT_FALSE(c.solid.contact->ref_centroid.empty());
}

TEST(Restart, SphSceneContinuesBitIdentically) {
  const Checkpoint c = expect_bit_identical_restart(kDam, 40, "dam");
  ASSERT_TRUE(c.fluid.has_value());
  EXPECT_GT(c.fluid->gid.size(), 300u);
}

TEST(Restart, ChangedSceneIsRefusedNamingTheDifference) {
  Sim a(kBeam);
  a.steps(5);
  const Checkpoint c = a.capture();
  auto error_of = [&c](const std::string& yaml) -> std::string {
    Sim b(yaml);
    try {
      b.restore(c);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  };
  std::string beam = kBeam;
  auto edit = [&beam](const std::string& from, const std::string& to) {
    std::string s = beam;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  const std::string e1 = error_of(edit("E: 1.0e6", "E: 2.0e6"));
  EXPECT_NE(e1.find("does not match scene"), std::string::npos) << e1;
  EXPECT_NE(e1.find("material 'rubber': checkpoint has law svk, E 1000000"), std::string::npos)
      << e1;
  EXPECT_NE(e1.find("the scene has law svk, E 2000000"), std::string::npos) << e1;
  const std::string e2 = error_of(edit("cells: [8, 1, 1]", "cells: [9, 1, 1]"));
  EXPECT_NE(e2.find("vertices: checkpoint has "), std::string::npos) << e2;
  EXPECT_NE(e2.find("body 'beam'"), std::string::npos) << e2;
  const std::string e3 = error_of(edit("force: [0, 0, -2]", "force: [0, 0, -3]"));
  EXPECT_NE(e3.find("loads: checkpoint has fnv1a:"), std::string::npos) << e3;
  EXPECT_EQ(error_of(kBeam), "(no error)");
}

TEST(Restart, SeriesKeepsTheLastKAndRemovesStaleTemporaries) {
  const fs::path dir = scratch_dir("restart_series");
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "checkpoint_0000000003.h5.tmp") << "a write a killed run left";
  Sim a(kBeam);
  CheckpointSeries series(dir, 2);
  EXPECT_FALSE(fs::exists(dir / "checkpoint_0000000003.h5.tmp"));
  for (int k = 0; k < 4; ++k) {
    a.steps(3);
    series.write(a.capture());
  }
  const auto files = list_checkpoints(dir);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].filename(), "checkpoint_0000000009.h5");
  EXPECT_EQ(files[1].filename(), "checkpoint_0000000012.h5");
  EXPECT_EQ(read_checkpoint(files[1]).step, 12);
}

TEST(Restart, DamagedOrForeignFilesAreInputErrors) {
  const fs::path dir = scratch_dir("restart_bad");
  std::ofstream(dir / "text.h5") << "not hdf5";
  EXPECT_THROW(read_checkpoint(dir / "text.h5"), InputError);
  EXPECT_THROW(read_checkpoint(dir / "missing.h5"), InputError);
  // A checkpoint cut short (as by a disk filling up) is refused, not read partly.
  Sim a(kBeam);
  write_checkpoint(dir / "good.h5", a.capture());
  std::ifstream in(dir / "good.h5", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir / "cut.h5", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  try {
    read_checkpoint(dir / "cut.h5");
    FAIL() << "a truncated checkpoint was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.h5"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace qdemsph
