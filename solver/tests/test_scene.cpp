// Scene parsing: good scenes parse to the expected values; every file of the bad-scene corpus
// (tests/data/scenes/bad, first line "# expect: <substring>") fails with an InputError whose
// message contains that substring and names the file; overrides edit the tree before
// validation and report their own mistakes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/scene_yaml.hpp"
#include "model/model.hpp"

#ifndef QDEMSPH_TEST_DATA
#error "QDEMSPH_TEST_DATA must be the absolute path of solver/tests/data"
#endif

namespace qdemsph {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(QDEMSPH_TEST_DATA) / "scenes";

std::string error_of(const fs::path& file, const std::vector<std::string>& overrides = {}) {
  try {
    build_model(load_scene(file, overrides));  // the model's checks too (e.g. overlaps)
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneCorpus, EveryBadSceneIsRejectedWithItsMessage) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(kScenes / "bad")) {
    if (entry.path().extension() != ".yaml") continue;
    ++count;
    std::ifstream in(entry.path());
    std::string first;
    std::getline(in, first);
    const std::string tag = "# expect: ";
    ASSERT_EQ(first.rfind(tag, 0), 0u) << entry.path() << " lacks the '# expect: ' first line";
    const std::string expect = first.substr(tag.size());
    const std::string msg = error_of(entry.path());
    SCOPED_TRACE(entry.path().filename().string());
    EXPECT_NE(msg.find(expect), std::string::npos) << "message: " << msg;
    // FILE first, so editors and terminals can jump to it.
    EXPECT_EQ(msg.rfind(entry.path().string(), 0), 0u) << "message: " << msg;
  }
  EXPECT_GE(count, 40);
}

TEST(Scene, FullSceneParsesEveryKey) {
  const Scene s = load_scene(kScenes / "good" / "full.yaml");
  EXPECT_EQ(s.name, "full_cantilever");
  EXPECT_EQ(s.run.mode, RunMode::Static);
  EXPECT_EQ(s.run.end_time, 2.5);
  ASSERT_TRUE(s.run.dt.has_value());
  EXPECT_EQ(*s.run.dt, 1e-6);
  EXPECT_EQ(s.run.dt_safety, 0.25);
  EXPECT_EQ(s.run.backend, "cuda");
  EXPECT_EQ(s.run.threads, 4);
  EXPECT_EQ(s.run.static_tolerance, 1e-10);
  EXPECT_EQ(s.run.static_max_steps, 200000);
  EXPECT_EQ(s.gravity.z, -9.81);
  EXPECT_EQ(s.mass_damping, 0.5);

  ASSERT_EQ(s.materials.size(), 2u);  // file order
  EXPECT_EQ(s.materials[0].name, "steel");
  EXPECT_EQ(s.materials[0].law, MaterialLaw::Linear);
  EXPECT_EQ(s.materials[0].E, 2.1e11);
  EXPECT_EQ(s.materials[0].nu, 0.29);
  EXPECT_EQ(s.materials[0].density, 7850);
  EXPECT_EQ(s.materials[1].law, MaterialLaw::StVenantKirchhoff);
  EXPECT_EQ(s.materials[1].viscosity, 20);

  ASSERT_EQ(s.bodies.size(), 2u);
  const BodySpec& beam = s.bodies[0];
  EXPECT_EQ(beam.name, "beam");
  EXPECT_EQ(beam.material, 1);
  EXPECT_EQ(beam.mesh.kind, MeshSpec::Kind::Box);
  EXPECT_EQ(beam.mesh.origin.y, -0.05);
  EXPECT_EQ(beam.mesh.size.x, 1.0);
  EXPECT_EQ(beam.mesh.cells, (std::array<int, 3>{20, 2, 2}));
  EXPECT_EQ(beam.velocity.z, 3.0);
  EXPECT_EQ(beam.angular_velocity.z, 0.5);
  EXPECT_FALSE(beam.fixed);
  const BodySpec& base = s.bodies[1];
  EXPECT_EQ(base.material, 0);
  EXPECT_EQ(base.mesh.kind, MeshSpec::Kind::Gmsh);
  EXPECT_TRUE(base.mesh.file.is_absolute());
  EXPECT_EQ(base.mesh.file, (kScenes / "good" / "meshes" / "tet.msh").lexically_normal());
  EXPECT_EQ(base.mesh.scale, 0.001);
  EXPECT_EQ(base.mesh.translate.z, -1.0);
  EXPECT_TRUE(base.fixed);

  ASSERT_EQ(s.constraints.size(), 2u);
  EXPECT_EQ(s.constraints[0].kind, ConstraintSpec::Kind::Fixed);
  EXPECT_EQ(s.constraints[0].region.range[0][0], 0.0);
  EXPECT_EQ(s.constraints[0].region.range[0][1], 0.0);
  EXPECT_TRUE(std::isinf(s.constraints[0].region.range[1][0]));  // absent axis: unbounded
  EXPECT_EQ(s.constraints[1].kind, ConstraintSpec::Kind::Velocity);
  EXPECT_EQ(s.constraints[1].velocity.z, -0.1);
  EXPECT_EQ(s.constraints[1].region.range[2][0], -1.0);

  ASSERT_EQ(s.loads.size(), 2u);
  EXPECT_EQ(s.loads[0].kind, LoadSpec::Kind::Traction);
  EXPECT_EQ(s.loads[0].traction.z, -1000.0);
  EXPECT_TRUE(s.loads[0].preload);
  EXPECT_EQ(s.loads[1].kind, LoadSpec::Kind::Point);
  EXPECT_EQ(s.loads[1].point.x, 1.0);
  EXPECT_EQ(s.loads[1].force.z, -5.0);
  EXPECT_FALSE(s.loads[1].preload);

  ASSERT_EQ(s.probes.size(), 2u);
  EXPECT_EQ(s.probes[0].name, "tip");
  EXPECT_EQ(s.probes[0].kind, ProbeSpec::Kind::Displacement);
  EXPECT_EQ(s.probes[0].region.range[1][1], 0.05);
  EXPECT_EQ(s.probes[1].kind, ProbeSpec::Kind::CentreOfMass);
  EXPECT_EQ(s.probes[1].body, 0);

  EXPECT_EQ(s.output.dir, fs::path("out/full"));
  EXPECT_EQ(s.output.fields_every, 0.01);
  EXPECT_EQ(s.output.probes_every, 0.001);

  EXPECT_EQ(s.parallel.curve, "peano");
  EXPECT_EQ(s.parallel.rebalance_threshold, 0.05);
  EXPECT_EQ(s.parallel.rebalance_every, 50);
  EXPECT_EQ(s.parallel.max_cell_cost, 0.01);
}

TEST(Scene, MinimalSceneTakesDefaults) {
  const Scene s = load_scene(kScenes / "good" / "minimal.yaml");
  EXPECT_EQ(s.name, "minimal");  // file stem
  EXPECT_EQ(s.run.mode, RunMode::Dynamic);
  EXPECT_EQ(s.run.end_time, 0.5);
  EXPECT_FALSE(s.run.dt.has_value());
  EXPECT_EQ(s.run.dt_safety, 0.5);
  EXPECT_EQ(s.run.backend, "cpu");
  EXPECT_EQ(s.materials[0].law, MaterialLaw::StVenantKirchhoff);
  EXPECT_EQ(s.bodies[0].mesh.origin.x, 0.0);
  EXPECT_EQ(s.gravity.z, 0.0);
  EXPECT_TRUE(s.constraints.empty() && s.loads.empty() && s.probes.empty());
  EXPECT_EQ(s.output.dir, fs::path("out/minimal"));
}

TEST(Scene, EveryGoodSceneParses) {
  for (const auto& entry : fs::directory_iterator(kScenes / "good")) {
    if (entry.path().extension() == ".yaml") {
      EXPECT_NO_THROW(load_scene(entry.path())) << entry.path();
    }
  }
}

TEST(Scene, ErrorsNameFileLineAndKeyPath) {
  const fs::path f = kScenes / "bad" / "E_zero.yaml";
  EXPECT_EQ(error_of(f), f.string() + ":7: materials.rubber.E: must be > 0 (got 0)");
}

TEST(SceneOverrides, EditTheTreeBeforeValidation) {
  const fs::path f = kScenes / "good" / "minimal.yaml";
  const Scene s = load_scene(f, {"bodies.0.mesh.cells=[40,4,4]", "run.end_time=0.25",
                                 "run.static.tolerance=1e-3", "gravity=[0,0,-9.81]",
                                 "bodies.1={name: b2, material: rubber, mesh: {type: box, "
                                 "size: [1,1,1], cells: [1,1,1]}}",
                                 "materials.rubber.law=linear"});
  EXPECT_EQ(s.bodies[0].mesh.cells, (std::array<int, 3>{40, 4, 4}));
  EXPECT_EQ(s.run.end_time, 0.25);
  EXPECT_EQ(s.run.static_tolerance, 1e-3);
  EXPECT_EQ(s.gravity.z, -9.81);
  ASSERT_EQ(s.bodies.size(), 2u);  // index == size appends
  EXPECT_EQ(s.bodies[1].name, "b2");
  EXPECT_EQ(s.materials[0].law, MaterialLaw::Linear);
  // A bad override fixes a bad file.
  EXPECT_NO_THROW(load_scene(kScenes / "bad" / "E_zero.yaml", {"materials.rubber.E=1e6"}));
}

TEST(SceneOverrides, MistakesAreReported) {
  const fs::path f = kScenes / "good" / "minimal.yaml";
  EXPECT_NE(error_of(f, {"run.end_time"}).find("expected key.path=value"), std::string::npos);
  EXPECT_NE(error_of(f, {"run..dt=1"}).find("empty component"), std::string::npos);
  EXPECT_NE(error_of(f, {"bodies.x.name=a"}).find("bodies.x: a list is indexed by a number"),
            std::string::npos);
  EXPECT_NE(error_of(f, {"bodies.5.name=a"}).find("index out of range (list has 1 items)"),
            std::string::npos);
  EXPECT_NE(error_of(f, {"run.end_time.x=1"}).find("run.end_time: is a single value"),
            std::string::npos);
  EXPECT_NE(error_of(f, {"run.end_time=[1"}).find("value is not valid YAML"), std::string::npos);
  // Values set by an override are validated like the file's, and the message names the override.
  EXPECT_EQ(error_of(f, {"run.dt=-1"}),
            f.string() + ": override 'run.dt=-1': run.dt: must be > 0 (got -1)");
  EXPECT_NE(error_of(f, {"run.end_tme=1"}).find("unknown key; did you mean 'end_time'?"),
            std::string::npos);
  // Maps an override creates on its way down are blamed on it too.
  EXPECT_NE(
      error_of(f, {"materials.steel.E=1"})
          .find("override 'materials.steel.E=1': materials.steel.nu: required key is missing"),
      std::string::npos);
  EXPECT_NE(error_of(f, {"name.x=1"}).find("override 'name.x=1': name: expected a string"),
            std::string::npos);
}

TEST(Scene, MissingSceneFile) {
  EXPECT_NE(error_of(kScenes / "nope.yaml").find("scene file does not exist"), std::string::npos);
}

TEST(Scene, ParseFromTextResolvesMeshesAgainstTheNamedFile) {
  const std::string text =
      "run: {end_time: 1}\nmaterials: {m: {E: 1, nu: 0, density: 1}}\n"
      "bodies: [{name: b, material: m, mesh: {type: gmsh, file: meshes/tet.msh}}]\n";
  const Scene s = parse_scene(text, kScenes / "good" / "inline.yaml");
  EXPECT_EQ(s.bodies[0].mesh.file.filename(), "tet.msh");
  EXPECT_THROW(parse_scene(text, kScenes / "bad" / "inline.yaml"), InputError);
}

TEST(Scene, BoxRotatesAboutItsOriginCorner) {
  // A 1 x 2 x 3 box at origin (1, 0, 0) tipped 90 degrees about +y: its z edge turns to +x.
  const Model m = build_model(parse_scene(
      "run: {end_time: 1}\nmaterials: {m: {E: 1, nu: 0, density: 1}}\n"
      "bodies: [{name: b, material: m, mesh: {type: box, origin: [1, 0, 0], size: [1, 2, 3], "
      "cells: [1, 1, 1], rotate: {axis: [0, 2, 0], angle: 90}}}]\n",
      kScenes / "good" / "inline.yaml"));
  Vec3 lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
  for (const Vec3& p : m.X)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  EXPECT_NEAR(lo.x, 1, 1e-12);
  EXPECT_NEAR(hi.x, 4, 1e-12);
  EXPECT_NEAR(lo.y, 0, 1e-12);
  EXPECT_NEAR(hi.y, 2, 1e-12);
  EXPECT_NEAR(lo.z, -1, 1e-12);
  EXPECT_NEAR(hi.z, 0, 1e-12);
  EXPECT_NE(error_of(kScenes / "good" / "minimal.yaml",
                     {"bodies.0.mesh.rotate={axis: [0, 0, 0], angle: 1}"})
                .find("rotate.axis: must not be the zero vector"),
            std::string::npos);
}

}  // namespace
}  // namespace qdemsph
