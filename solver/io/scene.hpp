// The validated, typed form of a scene file (see docs/scene-format.md). Parsing and all
// input validation live in scene_yaml.cpp; everything downstream trusts these values.
#pragma once

#include <array>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

enum class MaterialLaw { Linear, StVenantKirchhoff };
enum class RunMode { Dynamic, Static };

struct MaterialSpec {
  std::string name;
  MaterialLaw law = MaterialLaw::StVenantKirchhoff;
  double E = 0, nu = 0, density = 0;
  double viscosity = 0;  // Kelvin-Voigt eta [Pa s], acting like E: sigma_v = (eta/E) C : D
};

// Axis-aligned selection of vertices: each present axis range must contain the coordinate.
// Coordinates are reference (undeformed) positions.
struct Region {
  std::array<double, 2> range[3] = {{-std::numeric_limits<double>::infinity(),
                                     std::numeric_limits<double>::infinity()},
                                    {-std::numeric_limits<double>::infinity(),
                                     std::numeric_limits<double>::infinity()},
                                    {-std::numeric_limits<double>::infinity(),
                                     std::numeric_limits<double>::infinity()}};
  bool contains(Vec3 p) const {
    for (int a = 0; a < 3; ++a)
      if (p[a] < range[a][0] || p[a] > range[a][1]) return false;
    return true;
  }
};

struct MeshSpec {
  enum class Kind { Box, Gmsh } kind = Kind::Box;
  // box: origin + size, cells per axis; each hex split into 12 tets around a centre vertex
  Vec3 origin{0, 0, 0};
  Vec3 size{1, 1, 1};
  std::array<int, 3> cells{1, 1, 1};
  std::filesystem::path file;  // gmsh: absolute path (resolved against the scene's folder)
  double scale = 1.0;          // gmsh: coordinates multiplied by this
  Vec3 translate{0, 0, 0};     // gmsh: added after scaling
};

struct BodySpec {
  std::string name;
  MeshSpec mesh;
  int material = 0;  // index into Scene::materials
  Vec3 velocity{0, 0, 0};
  Vec3 angular_velocity{0, 0, 0};  // about the body's centre of mass [rad/s]
  bool fixed = false;              // a fixed body is never integrated
};

struct ConstraintSpec {
  enum class Kind { Fixed, Velocity } kind = Kind::Fixed;
  int body = 0;
  Region region;
  Vec3 velocity{0, 0, 0};  // Velocity: prescribed vertex velocity
};

struct LoadSpec {
  enum class Kind { Traction, Point } kind = Kind::Traction;
  int body = 0;
  Region region;       // traction: surface triangles with all 3 vertices inside
  Vec3 traction{0, 0, 0};  // force per reference area [Pa]
  Vec3 point{0, 0, 0};     // point: applied at the vertex nearest to this position
  Vec3 force{0, 0, 0};     // point: force [N]
  bool preload = false;    // applied only in the initial static solve, then released
};

struct ProbeSpec {
  enum class Kind { Displacement, CentreOfMass } kind = Kind::Displacement;
  std::string name;
  int body = 0;
  Region region;  // displacement: region-averaged over vertices
};

struct RunSpec {
  RunMode mode = RunMode::Dynamic;
  double end_time = 1.0;
  std::optional<double> dt;  // fixed dt; must not exceed the stability limit
  double dt_safety = 0.5;    // dt = dt_safety * stability limit when dt is not given
  double static_tolerance = 1e-8;  // max |residual force| / max |applied force|; the floor is
                                   // ~1e-9, set by round-off in absolute positions
  long static_max_steps = 1000000;
  std::string backend = "cpu";
  int threads = 0;  // 0: OpenMP default
};

struct OutputSpec {
  std::filesystem::path dir = "out";  // relative to the working directory
  double fields_every = 0;   // simulated seconds between field snapshots; 0: first and last only
  double probes_every = 0;   // simulated seconds between probe rows; 0: every 100 steps
};

struct Scene {
  std::filesystem::path file;  // where it was read from
  std::string name;
  RunSpec run;
  Vec3 gravity{0, 0, 0};
  double mass_damping = 0;  // alpha: f -= alpha m v  [1/s]
  std::vector<MaterialSpec> materials;
  std::vector<BodySpec> bodies;
  std::vector<ConstraintSpec> constraints;
  std::vector<LoadSpec> loads;
  std::vector<ProbeSpec> probes;
  OutputSpec output;
};

}  // namespace qdemsph
