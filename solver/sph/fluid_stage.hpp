// The fluid stage seen by the stepper (host orchestration; one virtual call per stage, never
// inside a loop). Implemented by SphStage<Exec> (sph_stage.hpp) for each execution space.
//
// Time integration: velocity Verlet at the fluid step H, the bodies taking k >= 1 steps of
// H / k inside it (integrate/stepper.cpp):
//   kick(H/2): v += H/2 a                        (fluid)
//   drift(H):  x += H v                          (fluid)
//   ... the bodies advance to t + H ...
//   compute(): place the body markers; sort by cell; drho(x_{n+1}, v_{n+1/2});
//              rho += H drho; EOS; wall and marker pressure (Adami); pair forces -> a;
//              fluid forces on the bodies (sph/solid_coupling.hpp)
//   kick(H/2)
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/vec.hpp"
#include "integrate/backend.hpp"
#include "physics/sph_timestep.hpp"
#include "sph/fluid_exchange.hpp"
#include "sph/fluid_setup.hpp"

namespace qdemsph {

struct FluidHost {
  std::vector<Vec3> x, v;
  std::vector<double> rho, p;
  std::vector<std::uint8_t> type;
  std::vector<std::uint64_t> gid;
};

// The fluid state between two steps, in the stage's current (cell-sorted) order: the order
// fixes the summation order of the next step, so a checkpoint keeps it for a bit-identical
// restart; gid names each particle.
struct FluidState {
  std::vector<Vec3> x, v, a;
  std::vector<double> rho, p, m;
  std::vector<std::uint8_t> type;
  std::vector<std::uint64_t> gid;
};

struct FluidStats {
  double kinetic = 0;      // sum 1/2 m v^2 over fluid [J]
  Vec3 momentum{};         // sum m v over fluid [kg m/s]
  double v_max = 0;        // max |v| [m/s]
  double a_max = 0;        // max |a| [m/s^2]
  double rho_dev = 0;      // max |rho / rho0 - 1| over fluid
  Vec3 force_on_bodies{};  // the fluid's total force on the coupled bodies [N]
};

class FluidStage {
 public:
  virtual ~FluidStage() = default;
  virtual void kick(double h) = 0;
  virtual void drift(double h) = 0;
  virtual void compute() = 0;
  virtual FluidStats stats() = 0;
  virtual SphDtLimits dt_limits() = 0;
  // -1 when every fluid position/velocity/density is finite, else a global particle id.
  virtual std::int64_t find_non_finite() = 0;
  virtual FluidHost download() = 0;
  // Checkpoint/restart: load_state restores a saved state exactly (InputError when the
  // particle count differs).
  virtual FluidState save_state() = 0;
  virtual void load_state(const FluidState& state) = 0;
  // Seconds of the sub-phases inside compute() (distributed: "sph.halo", "sph.rebuild", and
  // "sph.setup", the first layout, built before the steps; one rank: none), for summary.json
  // and the parallel record.
  virtual std::map<std::string, double> stage_seconds() const = 0;
  virtual std::int64_t size() const = 0;
  virtual std::int64_t n_fluid() const = 0;
  virtual std::int64_t n_marker() const = 0;  // boundary markers of coupled bodies
  virtual std::size_t device_bytes() const = 0;
  virtual const SphParams& params() const = 0;
};

// "cpu" or "cuda" (the latter where a CUDA build provides it; else InputError). `solid`: the
// bodies' state (Backend::solid_views) when the setup has body markers, else null.
// `exchange`: a distributed run's (parallel/fluid_exchange.hpp), else null. Distributed, the
// counts are global, download() and save_state() give rank 0 every particle in the one-rank
// order (other ranks: empty), load_state() takes the whole state on every rank, and every call
// but size(), n_fluid(), n_marker(), device_bytes() and params() is collective.
std::unique_ptr<FluidStage> make_fluid_stage(const std::string& backend, const FluidSetup& setup,
                                             const SolidViews* solid = nullptr,
                                             std::unique_ptr<FluidExchange> exchange = nullptr);

}  // namespace qdemsph
