// Shared by the tests under mpirun (tests/mpi/): ranks of a communicator, the scenes the
// distributed runs are checked on (bodies, contact, a fluid coupled to a body), and the run
// options they use.
#pragma once

#include <mpi.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "integrate/stepper.hpp"
#include "io/scene_yaml.hpp"
#include "model/model.hpp"
#include "parallel/distributed_backend.hpp"
#include "parallel/distributed_backend_mpi.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph::mpi_testing {

inline int rank_of(MPI_Comm c = MPI_COMM_WORLD) {
  int r;
  MPI_Comm_rank(c, &r);
  return r;
}
inline int size_of(MPI_Comm c = MPI_COMM_WORLD) {
  int s;
  MPI_Comm_size(c, &s);
  return s;
}

// A tumbling viscoelastic bar, clamped at one end region, a prescribed-velocity patch at the
// other, a point load: every element and integration path.
inline const char* kElementScene = R"(
run: {mode: dynamic, end_time: 1.0}
gravity: [0, 0, -9.81]
damping: {mass: 0.5}
materials: {m: {law: svk, E: 2.0e6, nu: 0.3, density: 1000, viscosity: 30}}
bodies:
  - {name: bar, material: m, mesh: {type: box, size: [1.0, 0.3, 0.2], cells: [10, 3, 2]},
     velocity: [0.3, -0.2, 0.5], angular_velocity: [2, -1, 3]}
constraints:
  - {type: fixed, body: bar, region: {x: [0, 0]}}
  - {type: velocity, body: bar, region: {x: [1, 1], z: [0.1, 0.2]}, velocity: [0, 0, -0.5]}
loads:
  - {type: point, body: bar, at: [0.5, 0.3, 0.2], force: [0, 5, -20]}
)";

// Two free cubes falling onto a fixed block, sliding against a wall, with friction.
inline const char* kContactScene = R"(
run: {mode: dynamic, end_time: 1.0}
gravity: [0, 0, -9.81]
materials: {m: {E: 1.0e6, nu: 0.3, density: 1000, viscosity: 50}}
contact: {mu: 0.4, restitution: 0.5, d_dem: 0.004}
walls: [{point: [-0.02, 0, 0], normal: [1, 0, 0], mu: 0.3}]
bodies:
  - {name: a, material: m, mesh: {type: box, origin: [0.0, 0.0, 0.101], size: [0.1, 0.1, 0.1], cells: [3, 3, 3]},
     velocity: [-1.0, 0.2, -1.5], angular_velocity: [3, -4, 2]}
  - {name: b, material: m, mesh: {type: box, origin: [0.13, 0.02, 0.102], size: [0.1, 0.1, 0.1], cells: [3, 3, 3]},
     velocity: [-1.0, 0, -1.0], angular_velocity: [0, 5, 0]}
  - {name: base, material: m, fixed: true, mesh: {type: box, origin: [-0.1, -0.1, 0.0], size: [0.45, 0.3, 0.1], cells: [6, 4, 2]}}
)";

struct Problem {
  Scene scene;
  Model model;
};

inline Problem load(const char* yaml, const std::vector<std::string>& overrides = {}) {
  Problem r;
  r.scene = parse_scene(yaml, "distributed_test.yaml", overrides);
  r.model = build_model(r.scene);
  return r;
}

inline ParallelOptions options(long every, double threshold, const std::string& curve = "hilbert") {
  ParallelOptions o;
  o.curve = curve;
  o.rebalance_every = every;
  o.rebalance_threshold = threshold;
  return o;
}

// A one-rank reference and the distributed run of the same model, stepped side by side, on
// `backend` ("cpu", or "cuda": a GPU a rank).
struct SideBySide {
  std::unique_ptr<Backend> ref_be;
  std::unique_ptr<DistributedBackend> dist;
  double dt;
  Stepper ref, st;
  SideBySide(const Model& m, const ParallelOptions& opt, const std::string& backend = "cpu")
      : ref_be(make_backend(backend)),
        dist(make_distributed_backend(MPI_COMM_WORLD, make_backend(backend), opt)),
        dt(choose_dt(m, std::nullopt, 0.5)),
        ref(uploaded(*ref_be, m), *ref_be, dt),
        st(uploaded(*dist, m), *dist, dt) {}

 private:
  static const Model& uploaded(Backend& be, const Model& m) {  // before the Stepper sees it
    be.upload(m);
    return m;
  }
};

// A dam break against a free deformable cube resting on a contact wall (the floor), coupled
// both ways: 3,280 fluid and wall particles, 64 markers in the cube's 27-vertex mesh.
inline const char* kCoupledScene = R"(
run: {end_time: 0.1}
gravity: [0, 0, -9.81]
materials: {m: {E: 1.0e6, nu: 0.3, density: 500, viscosity: 5}}
contact: {mu: 0.4, d_dem: 0.004}
walls: [{point: [0, 0, 0], normal: [0, 0, 1]}]
bodies:
  - {name: cube, material: m, mesh: {type: box, origin: [0.23, 0.02, 0.002], size: [0.08, 0.08, 0.08], cells: [2, 2, 2]}}
fluid:
  spacing: 0.02
  couple_bodies: true
  blocks: [{min: [0, 0, 0], max: [0.2, 0.12, 0.2]}]
  tanks: [{min: [0, 0, 0], max: [0.5, 0.12, 0.3], thickness_layers: 2}]
)";

// The fluid of a coupled scene, with its body markers.
inline FluidSetup coupled_fluid(const Problem& r) {
  FluidSetup f = build_fluid(r.scene.fluid, r.scene.gravity);
  add_solid_markers(f, r.model);
  return f;
}

// A coupled scene's bodies, fluid and Stepper, the solid stepped twice per fluid step (the
// coupling force held over the sub-steps): on one rank (comm = MPI_COMM_NULL) or over `comm`,
// both partitions cut again every 25 steps (threshold 0).
struct CoupledRun {
  static constexpr double kStep = 2.0e-4;  // the fluid step (below its CFL limit, 2.6e-4 s)
  static constexpr int kSubsteps = 2;
  std::unique_ptr<Backend> be;
  DistributedBackend* dist = nullptr;  // be, when distributed
  SolidViews solid;
  std::unique_ptr<FluidStage> fluid;
  std::unique_ptr<Stepper> st;
  CoupledRun(const Model& m, const FluidSetup& f, MPI_Comm comm = MPI_COMM_NULL) {
    std::unique_ptr<FluidExchange> ex;
    if (comm == MPI_COMM_NULL) {
      be = make_host_backend();
    } else {
      auto d = make_distributed_backend(comm, make_host_backend(), options(25, 0.0));
      dist = d.get();
      be = std::move(d);
      ex = make_fluid_exchange(comm, options(25, 0.0), f);
    }
    be->upload(m);
    solid = be->solid_views();
    fluid = make_fluid_stage("cpu", f, &solid, std::move(ex));
    st = std::make_unique<Stepper>(m, *be, kStep);
    st->attach_fluid(fluid.get(), kSubsteps);
  }
};

inline double max_diff(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, norm(a[i] - b[i]));
  return m;
}

}  // namespace qdemsph::mpi_testing
