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
  std::array<double, 2> range[3] = {
      {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()},
      {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()},
      {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()}};
  bool contains(Vec3 p) const {
    for (int a = 0; a < 3; ++a)
      if (p[a] < range[a][0] || p[a] > range[a][1]) return false;
    return true;
  }
};

// `rotate: {axis, angle}`: a right-handed rotation by `angle` degrees about `axis` through a
// pivot the owner names (a box mesh's origin corner, a fluid box's min corner, a shogi piece's
// base centre).
struct RotationSpec {
  Vec3 axis{1, 0, 0};
  double angle = 0;  // degrees
  bool none() const { return angle == 0; }
  RotationSpec inverse() const { return {axis, -angle}; }
  Vec3 apply(Vec3 p, Vec3 pivot) const {  // Rodrigues' formula
    const Vec3 k = axis / norm(axis), r = p - pivot;
    const double a = angle * 3.14159265358979323846 / 180.0, c = std::cos(a), sn = std::sin(a);
    return pivot + c * r + sn * cross(k, r) + ((1 - c) * dot(k, r)) * k;
  }
};

struct MeshSpec {
  enum class Kind { Box, Gmsh, Shogi } kind = Kind::Box;
  // box: origin + size, cells per axis; each hex split into 12 tets around a centre vertex
  Vec3 origin{0, 0, 0};
  Vec3 size{1, 1, 1};
  std::array<int, 3> cells{1, 1, 1};
  std::filesystem::path file;  // gmsh: absolute path (resolved against the scene's folder)
  double scale = 1.0;          // gmsh: coordinates multiplied by this
  Vec3 translate{0, 0, 0};     // gmsh: added after scaling; shogi: after rotating
  // shogi: a piece of the preset `piece` (king, rook, gold, knight, lance, pawn), target edge
  // length mesh_size (0: about 2,500 tets), rotated about the axis through the base centre,
  // then translated.
  std::string piece = "king";
  double mesh_size = 0;
  // box and shogi: rotation through the box's origin corner or the piece's base centre.
  RotationSpec rotate;
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
  std::array<bool, 3> components{true, true, true};  // Fixed: the held components (x, y, z)
  Vec3 velocity{0, 0, 0};                            // Velocity: prescribed vertex velocity
};

struct LoadSpec {
  enum class Kind { Traction, Point } kind = Kind::Traction;
  int body = 0;
  Region region;           // traction: surface triangles with all 3 vertices inside
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
  std::optional<double> dt;        // fixed dt; must not exceed the stability limit
  double dt_safety = 0.5;          // dt = dt_safety * stability limit when dt is not given
  double static_tolerance = 1e-8;  // max |residual force| / max |applied force|; the floor is
                                   // ~1e-9, set by round-off in absolute positions
  long static_max_steps = 1000000;
  std::string backend = "cpu";
  int threads = 0;  // 0: OpenMP default
};

// Checkpoints of a dynamic run (io/checkpoint_h5.hpp) for `qdemsph run --restart`.
struct CheckpointSpec {
  bool enabled = false;
  long every_steps = 0;       // 0: not by step count
  double every_seconds = 0;   // wall-clock seconds between checkpoints; 0: not by time
  int keep = 2;               // the newest `keep` files are kept
  std::filesystem::path dir;  // empty: <output dir>/checkpoints
};

struct OutputSpec {
  std::filesystem::path dir = "out";  // relative to the working directory
  double fields_every = 0;  // simulated seconds between field snapshots; 0: first and last only
  double probes_every = 0;  // simulated seconds between probe rows; 0: every 100 steps
  CheckpointSpec checkpoint;
};

// Weakly compressible SPH fluid (docs/scene-format.md, `fluid:`). Boxes are axis-aligned
// [min, max]; particles sit on a lattice of pitch `spacing`.
struct FluidBoxSpec {
  Vec3 min{0, 0, 0}, max{0, 0, 0};
  int thickness_layers = 3;  // tanks: wall layers outside the inner box
  RotationSpec rotate;       // blocks and walls: about `min` (the box is [min, max] before)
};

struct FluidSpec {
  bool present = false;
  double density = 1000;                      // rho0 [kg/m^3]
  std::optional<double> sound_speed;          // c0 [m/s]; absent: auto = 10 sqrt(2 |g| H)
  std::string viscosity_type = "artificial";  // artificial (alpha) or laminar (nu [m^2/s])
  double viscosity = 0.01;
  bool wall_viscosity = true;         // viscosity also between fluid and walls
  double delta = 0.1;                 // delta-SPH density diffusion coefficient
  double spacing = 0;                 // particle spacing dx [m]
  double smoothing = 1.3;             // h / dx
  bool hydrostatic_init = true;       // initial pressure rho0 g (H - depth) per block
  double min_pressure = 0;            // tension cut-off [Pa] (<= 0): density floor rho(p_min)
  std::vector<FluidBoxSpec> blocks;   // fluid
  std::vector<FluidBoxSpec> tanks;    // open-top containers: walls around the inner box
  std::vector<FluidBoxSpec> walls;    // solid boxes of wall particles
  bool couple_bodies = true;          // the bodies are walls for the fluid and feel its forces
  std::optional<int> solid_substeps;  // solid steps per fluid step; absent: as many as fit
  // [z0, z1]: the fluid is periodic in z over this range (a quasi-2D slab without side walls)
  std::optional<std::array<double, 2>> periodic_z;
};

// Contact between bodies (docs/scene-format.md, `contact:`). Per material pair values
// override the defaults; stiffness 0 means derived from E and the mesh size.
struct ContactPairSpec {
  int material_a = 0, material_b = 0;
  std::optional<double> mu, restitution, stiffness;
};

struct ContactSpec {
  double mu = 0.3;
  double restitution = 0.5;
  std::optional<double> d_dem;  // absent: 0.1 x the smallest body's mean surface edge
  bool self_contact = false;
  std::string broad_phase = "polygons";  // polygons | surface_tets | all_tets (report Fig. 7)
  double stiffness_factor = 0.1;         // default k_n = factor * E_pair * h_pair
  std::optional<double> skin;  // pair-list Verlet skin [m]; absent: auto; 0: rebuild every step
  // Penetration guard [m]: the run stops when surfaces cross deeper; absent: half the pair's
  // smaller mean surface edge.
  std::optional<double> max_penetration;
  std::vector<ContactPairSpec> pairs;
};

// An analytic plane: bodies stay on the side the normal points to.
struct WallSpec {
  Vec3 point{0, 0, 0}, normal{0, 0, 1};
  double mu = 0.3;
  std::optional<double> restitution;  // absent: contact.restitution
  std::optional<double> stiffness;    // absent: derived from the body's E and mesh size
};

// Domain decomposition when run on several MPI ranks (docs/parallel.md); no effect on one.
struct ParallelSpec {
  std::string curve = "hilbert";  // space-filling curve: hilbert | morton | peano
  double rebalance_threshold =
      0.10;                     // rebalance when measured max/mean - 1 of step time exceeds it
  long rebalance_every = 100;   // steps between imbalance measurements
  double max_cell_cost = 0.02;  // tree leaves are split above this fraction of a rank's load
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
  FluidSpec fluid;
  ContactSpec contact;
  std::vector<WallSpec> walls;  // analytic planes (contact), not fluid walls
  OutputSpec output;
  ParallelSpec parallel;
};

}  // namespace qdemsph
