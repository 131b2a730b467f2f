#include "integrate/stepper.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace qdemsph {

namespace {
const BodyRange& body_of_tet(const Model& m, std::int64_t t) {
  for (const auto& b : m.bodies)
    if (t >= b.t_begin && t < b.t_end) return b;
  return m.bodies.back();
}
}  // namespace

std::string describe_vertex(const Model& m, std::int64_t i) {
  const BodyRange& b = m.bodies[m.body[i]];
  const Vec3 X = m.X[i];
  return fmt::format("vertex {} of body '{}' (reference position {:.4g}, {:.4g}, {:.4g})",
                     i - b.v_begin, b.name, X.x, X.y, X.z);
}

std::string describe_tet(const Model& m, std::int64_t t) {
  const BodyRange& b = body_of_tet(m, t);
  return fmt::format("tet {} of body '{}'", t - b.t_begin, b.name);
}

double choose_dt(const Model& model, std::optional<double> fixed_dt, double safety) {
  if (model.dt_critical_tet < 0) return fixed_dt.value_or(1e-3);  // only fixed bodies
  if (fixed_dt) {
    if (*fixed_dt > model.dt_critical)
      throw InputError(fmt::format(
          "run.dt = {:.4e} s exceeds the stability limit {:.4e} s (smallest altitude / P-wave "
          "speed, set by {}); use a smaller dt or leave it out to use {} x the limit",
          *fixed_dt, model.dt_critical, describe_tet(model, model.dt_critical_tet), safety));
    return *fixed_dt;
  }
  return safety * model.dt_critical;
}

Stepper::Stepper(const Model& model, Backend& backend, double dt, int check_every)
    : model_(model),
      be_(backend),
      dt_(dt),
      check_every_(std::max(1, check_every)),
      timers_([&backend] { backend.sync(); }) {
  be_.compute_forces(0.0, model_.mass_damping);
  check(false);
}

void Stepper::step() {
  if (fluid_) {
    auto s = timers_.scope("sph");
    fluid_->kick(0.5 * dt_);
    fluid_->drift(dt_);
  }
  // The kicks and the drift only launch on a GPU: the device goes on to the force evaluation, or
  // to the next step, with no wait for the host between them (a synchronised scope left it idle
  // for a round trip, twice a step). Their device time counts in the next synchronised phase
  // ("elements"); on the host backend they run within their scope as before.
  const double h = dt_ / substeps_;
  for (int k = 0; k < substeps_; ++k) {
    {
      auto s = timers_.launch("integration");
      be_.kick(0.5 * h);
      be_.drift(h);
    }
    {
      auto s = timers_.scope("elements");
      be_.compute_forces(h, model_.mass_damping);
    }
    {
      auto s = timers_.launch("integration");
      be_.kick(0.5 * h);
    }
  }
  if (fluid_) {
    // The fluid at t + dt against the solids at t + dt; the coupling hands the solids the new
    // fluid force with its half-step velocity correction (sph/solid_coupling.hpp).
    auto s = timers_.scope("sph");
    fluid_->compute();
    fluid_->kick(0.5 * dt_);
  }
  t_ += dt_;
  ++n_;
  if (n_ % check_every_ == 0) check();
}

void Stepper::check(bool dynamic) const {
  auto scope = timers_.scope("checks");
  const std::int64_t t = be_.take_inverted_tet();
  if (t >= 0)
    throw SimulationError(fmt::format(
        "step {} (t = {:.6e} s): {} inverted (det F <= 0); the body was crushed or the run is "
        "unstable (dt = {:.3e} s, stability limit {:.3e} s)",
        n_, t_, describe_tet(model_, t), dt_, model_.dt_critical));
  if (const auto c = be_.take_deep_contact()) {
    const std::string other = c->body2 >= 0 ? fmt::format("body '{}'", model_.bodies[c->body2].name)
                                            : fmt::format("wall {}", c->wall);
    throw SimulationError(fmt::format(
        "step {} (t = {:.6e} s): the surfaces of body '{}' and {} crossed by {:.3e} m, beyond "
        "the penetration bound {:.3e} m (contact.max_penetration), at {}; the bodies are "
        "passing through each other: reduce dt, stiffen the contact or refine the meshes",
        n_, t_, model_.bodies[c->body1].name, other, c->depth, c->bound,
        describe_vertex(model_, c->vertex)));
  }
  if (dynamic && n_ % (kDtGuardChecks * check_every_) == 0) {
    const double h = dt_ / substeps_;
    CriticalTet ct = be_.critical_tet(false);
    if (ct.dt > 0 && h > ct.dt) ct = be_.critical_tet(true);
    if (ct.tet >= 0 && h > ct.dt)
      throw SimulationError(fmt::format(
          "step {} (t = {:.6e} s): the time step {:.3e} s exceeds the stability limit {:.3e} s "
          "of {} at its deformed shape (smallest altitude / P-wave speed); the body is being "
          "crushed: use a smaller run.dt or dt_safety",
          n_, t_, h, ct.dt, describe_tet(model_, ct.tet)));
    if (fluid_) {
      const SphDtLimits l = fluid_->dt_limits();
      if (dt_ > kFluidDtGuard * l.min()) {
        // The failure path only: find the fastest and the most accelerated fluid particle.
        const FluidState s = fluid_->save_state();
        if (s.x.empty())  // a distributed run's ranks but 0 (rank 0 has every particle and reports)
          throw SimulationError(fmt::format(
              "step {} (t = {:.6e} s): the fluid step {:.3e} s exceeds {} x the fluid's stability "
              "limit {:.3e} s",
              n_, t_, dt_, kFluidDtGuard, l.min()));
        std::size_t iv = 0, ia = 0;
        for (std::size_t i = 0; i < s.x.size(); ++i) {
          if (s.type[i] != kSphFluid) continue;
          if (s.type[iv] != kSphFluid || norm(s.v[i]) > norm(s.v[iv])) iv = i;
          if (s.type[ia] != kSphFluid || norm(s.a[i]) > norm(s.a[ia])) ia = i;
        }
        const bool cfl = l.cfl <= l.force;
        const std::size_t k = cfl ? iv : ia;
        throw SimulationError(fmt::format(
            "step {} (t = {:.6e} s): the fluid step {:.3e} s exceeds {} x the fluid's stability "
            "limit (CFL {:.3e} s, force {:.3e} s, viscous {:.3e} s), set by SPH particle {} at "
            "({:.4g}, {:.4g}, {:.4g}) m moving at {:.4g} m/s with acceleration {:.4g} m/s^2: raise "
            "fluid.sound_speed, lower run.dt or refine fluid.spacing",
            n_, t_, dt_, kFluidDtGuard, l.cfl, l.force, l.viscous, s.gid[k], s.x[k].x, s.x[k].y,
            s.x[k].z, norm(s.v[k]), norm(s.a[k])));
      }
    }
  }
  if (fluid_) {
    const std::int64_t p = fluid_->find_non_finite();
    if (p >= 0)
      throw SimulationError(fmt::format(
          "step {} (t = {:.6e} s): non-finite position, velocity or density of SPH particle {} "
          "(dt = {:.3e} s); the fluid is unstable",
          n_, t_, p, dt_));
  }
  const std::int64_t v = be_.find_non_finite();
  if (v >= 0)
    throw SimulationError(
        fmt::format("step {} (t = {:.6e} s): non-finite position or velocity at {} (dt = {:.3e} "
                    "s, stability limit {:.3e} s)",
                    n_, t_, describe_vertex(model_, v), dt_, model_.dt_critical));
}

RelaxResult Stepper::relax(double tolerance, std::int64_t max_steps, bool preload,
                           const std::function<void(std::int64_t, double)>& progress) {
  auto scope = timers_.scope("relaxation");
  // Pseudo-time: only the end state matters, so step close to the stability limit.
  const double h = model_.relax_dt > 0 ? model_.relax_dt : dt_;
  RelaxResult r;
  const std::vector<Vec3>& loads = preload ? model_.fpre : model_.fext;
  for (std::int64_t i = 0; i < model_.n_free_vertices; ++i)
    if (model_.inv_mass[i] > 0)
      r.reference = std::max(r.reference, norm(loads[i] + model_.mass[i] * model_.gravity));
  be_.use_preload(preload);
  be_.zero_velocity();
  be_.compute_forces(0.0, 0.0);
  be_.mark_relax_start();
  // Displacement-driven problems (no loads) are measured against the initial residual.
  r.reference = std::max(r.reference, be_.static_stats().residual_max);
  if (r.reference == 0) {
    r.converged = true;
  } else {
    for (; r.iterations < max_steps; ++r.iterations) {
      const StaticStats s = be_.static_stats();
      r.residual = s.residual_max / r.reference;
      if (r.residual <= tolerance) {
        r.converged = true;
        break;
      }
      // Critical damping of the lowest mode, omega^2 ~ d^T K d / d^T M' d, d = x - x0.
      const double w2 = s.rayleigh_den > 0 ? std::max(s.rayleigh_num / s.rayleigh_den, 0.0) : 0.0;
      const double c = std::min(2.0 * std::sqrt(w2), 1.0 / h);
      be_.damped_step(h, c);
      be_.compute_forces(0.0, 0.0);
      if ((r.iterations + 1) % (10 * check_every_) == 0) check(false);
      if (progress && r.iterations % 1000 == 0) progress(r.iterations, r.residual);
    }
  }
  be_.zero_velocity();
  be_.use_preload(false);
  be_.compute_forces(0.0, model_.mass_damping);
  check(false);
  return r;
}

}  // namespace qdemsph
