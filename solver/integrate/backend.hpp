// The interface between the host-side stepper and a compute backend (CPU or CUDA). A
// backend owns the state in its memory space for the whole run; the host only sees what
// download() returns. Each method is one stage; the stepper assembles a run from them.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/memory.hpp"
#include "core/vec.hpp"
#include "model/model.hpp"
#include "physics/energies.hpp"

namespace qdemsph {

// Reductions a dynamic-relaxation step needs (over unconstrained free vertices).
struct StaticStats {
  double residual_max = 0;  // max |f|
  double rayleigh_num = 0;  // sum d . (f0 - f), d = x - x0: d^T K d for a linear law
  double rayleigh_den = 0;  // sum m' |u|^2 with the relaxation masses
};

struct HostFields {
  std::vector<Vec3> x, v;
  std::vector<std::array<double, 6>> stress;  // Cauchy: xx, yy, zz, yz, xz, xy
  std::vector<double> von_mises;
};

// The solid state a fluid couples to (sph/solid_coupling.hpp), in the backend's memory space.
// compute_forces adds fc (the fluid's force on each vertex) to f; the coupling writes fc, f and v.
struct SolidViews {
  Space space = Space::Host;
  Vec3CView x;
  Vec3View v, f, fc;
  View<const double> inv_mass;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;
  virtual void upload(const Model& model) = 0;
  // Selects the dead loads: the preload set (initial static solve) or the run's.
  virtual void use_preload(bool on) = 0;
  // f = element forces + dead loads + m g - alpha m v on free vertices; accumulates the
  // dissipated energy of this step (dt_dissipation = 0: none, as in dynamic relaxation).
  virtual void compute_forces(double dt_dissipation, double mass_damping) = 0;
  virtual void kick(double h) = 0;   // v += h f / m
  virtual void drift(double h) = 0;  // x += h v
  // Dynamic relaxation with the fictitious masses m' (Model::relax_inv_mass):
  // v = ((1 - c dt/2) v + dt f/m') / (1 + c dt/2), then x += dt v.
  virtual void damped_step(double dt, double c) = 0;
  virtual void zero_velocity() = 0;
  // Remembers x0 and f0 = f(x0) (call after compute_forces) for static_stats' Rayleigh
  // quotient, which then covers only the free part of displacement-driven problems.
  virtual void mark_relax_start() = 0;
  virtual StaticStats static_stats() = 0;
  virtual Energies energies() = 0;
  // -1 when all positions/velocities are finite, else the first offending vertex found.
  virtual std::int64_t find_non_finite() = 0;
  // -1, or a tet whose det F <= 0 in the last compute_forces (clears the flag).
  virtual std::int64_t take_inverted_tet() = 0;
  virtual HostFields download(bool with_stress) = 0;
  virtual void sync() = 0;
  virtual std::size_t device_bytes() const = 0;
  // Wall time of sub-stages run inside compute_forces (e.g. "contact.broad"), cumulative.
  virtual std::map<std::string, double> stage_seconds() const { return {}; }
  // The contact stage's counters of the last step (pairs, contacts, max_overlap, ...).
  virtual std::map<std::string, double> contact_stats() const { return {}; }
  // Enables the fluid coupling force fc (zero until the fluid writes it); views stay valid
  // until the next upload.
  virtual SolidViews solid_views();
};

// "cpu" (OpenMP) or "cuda"; throws InputError for an unknown or unavailable backend.
std::unique_ptr<Backend> make_backend(const std::string& name);
std::unique_ptr<Backend> make_host_backend();
std::unique_ptr<Backend> make_cuda_backend();  // memory_cuda/backend_cuda.cu, or throws

}  // namespace qdemsph
