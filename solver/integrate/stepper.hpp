// Time integration on top of a Backend: explicit velocity Verlet for dynamics and
// dynamic relaxation (critically damped by a Rayleigh-quotient estimate of the lowest
// frequency, Underwood 1983) for statics. Run-time guards turn NaN, inverted tets, contacts
// crossed beyond contact.max_penetration and a time step above the current stability limit
// (of the deformed tets, or of the fluid) into a SimulationError naming the element, body or
// particle and the time.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>

#include "core/timers.hpp"
#include "integrate/backend.hpp"
#include "model/model.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph {

struct RelaxResult {
  bool converged = false;
  std::int64_t iterations = 0;
  double residual = 0;   // max |f| / reference load at the end
  double reference = 0;  // max(applied force, initial residual) on a vertex [N]
};

class Stepper {
 public:
  // dt is used as given; callers check it against model.dt_critical (see choose_dt).
  Stepper(const Model& model, Backend& backend, double dt, int check_every = 10);

  // The SPH fluid (phase timer "sph"; null: none). Each step() is then one fluid step of dt
  // in which the solids take `solid_substeps` steps of dt / solid_substeps (fluid_stage.hpp).
  void attach_fluid(FluidStage* fluid, int solid_substeps = 1) {
    fluid_ = fluid;
    substeps_ = std::max(1, solid_substeps);
  }

  // Velocity Verlet: v += dt/2 f/m; x += dt v; f = f(x, v); v += dt/2 f/m (solids and fluid).
  void step();
  // Verifies positions/velocities are finite, no tet inverted and no contact crossed beyond
  // its bound; `dynamic`: also, every kDtGuardChecks checks, that the step is within the
  // current stability limits of the tets and the fluid (sph_timestep.hpp, times
  // kFluidDtGuard). Throws SimulationError.
  void check(bool dynamic = true) const;
  // The limits cost a pass over the tets (~half an element pass): every 10th check (every 100
  // steps by default) keeps that below 1 % of a run.
  static constexpr int kDtGuardChecks = 10;
  // The fluid's limits carry a safety factor of 4 (CFL 0.25, sph_timestep.hpp): the run
  // stops once its fixed step exceeds twice them (Courant number 0.5).
  static constexpr double kFluidDtGuard = 2.0;

  // Dynamic relaxation to max |f| <= tolerance * max |applied force|. With preload, the
  // preload set of dead loads is active during the solve and released afterwards.
  RelaxResult relax(double tolerance, std::int64_t max_steps, bool preload,
                    const std::function<void(std::int64_t, double)>& progress = {});

  // Restart (integrate/restart.hpp): continue from a checkpoint's time and step count.
  void set_clock(double t, std::int64_t steps) {
    t_ = t;
    n_ = steps;
  }

  double time() const { return t_; }
  std::int64_t steps() const { return n_; }
  double dt() const { return dt_; }
  PhaseTimers& timers() { return timers_; }

 private:
  const Model& model_;
  Backend& be_;
  double dt_;
  int check_every_;
  FluidStage* fluid_ = nullptr;
  int substeps_ = 1;
  double t_ = 0;
  std::int64_t n_ = 0;
  mutable PhaseTimers timers_;
};

// The run's dt: the scene's fixed dt (InputError if above the stability limit) or
// dt_safety times the limit.
double choose_dt(const Model& model, std::optional<double> fixed_dt, double safety);

// Where a vertex or tet lives, for messages: "vertex 12 of body 'beam'".
std::string describe_vertex(const Model& m, std::int64_t i);
std::string describe_tet(const Model& m, std::int64_t t);

}  // namespace qdemsph
