// The interface between the host-side stepper and a compute backend (CPU or CUDA). A
// backend owns the state in its memory space for the whole run; the host only sees what
// download() returns. Each method is one stage; the stepper assembles a run from them.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "contact/contact_record.hpp"
#include "contact/contact_state.hpp"
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

// The smallest current stability limit of a free tet (physics/element.hpp, tet_critical_dt
// at the deformed shape) and, when asked to locate it, that tet (else -1; -1 and dt = 0:
// no free tet).
struct CriticalTet {
  double dt = 0;
  std::int64_t tet = -1;
};

struct HostFields {
  std::vector<Vec3> x, v;
  std::vector<std::array<double, 6>> stress;  // Cauchy: xx, yy, zz, yz, xz, xy
  std::vector<double> von_mises;
};

// The dynamic state between two steps, in the uploaded model's order: everything a run
// needs to continue exactly. Vertex fields [n_vertices]: position, velocity, the force of the
// last evaluation (the next half kick uses it), the mass-damping dissipation and the
// relaxation start state (mark_relax_start); per-tet viscous dissipation [n_tets]; the
// contact stage's state; a coupled run's fluid force fc [n_vertices] (SolidViews: the next
// sub-steps add it to f, and the coupling's next velocity correction is taken against it). A
// checkpoint stores it (integrate/restart.hpp); a distributed run carries it across a rebuild of
// its decomposition (parallel/distributed_backend.cpp).
struct BackendState {
  std::vector<Vec3> x, v, f;
  std::vector<double> diss_v, diss_t;
  std::vector<Vec3> x0, f0;             // empty in load_state: zero
  std::optional<ContactState> contact;  // present when the model has contact
  std::vector<Vec3> fc;                 // coupled to a fluid (solid_views), else empty: zero
};

// A distributed backend's exchange around the coupling (parallel/distributed_backend.hpp): its
// SolidViews are whole-model arrays by global vertex id; pull() fills them for the coupled
// vertices before the coupling reads them, push() hands the owned ones' f, v, fc back after it
// wrote them.
class SolidSync {
 public:
  virtual ~SolidSync() = default;
  virtual void pull(std::span<const std::int32_t> coupled) = 0;
  virtual void push(std::span<const std::int32_t> coupled) = 0;
};

// The solid state a fluid couples to (sph/solid_coupling.hpp), in the backend's memory space,
// indexed by the model's vertex ids. compute_forces adds fc (the fluid's force on each vertex)
// to f; the coupling writes fc, f and v.
struct SolidViews {
  Space space = Space::Host;
  Vec3CView x;
  Vec3View v, f, fc;
  View<const double> inv_mass;
  View<const std::uint8_t> held;  // components held by constraints (bits x, y, z)
  SolidSync* sync = nullptr;      // distributed: the exchange around the coupling; else none
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
  // The first contact found deeper than its bound since the last call (clears it), if any.
  virtual std::optional<DeepContact> take_deep_contact() = 0;
  virtual CriticalTet critical_tet(bool locate) = 0;
  virtual HostFields download(bool with_stress) = 0;
  // The state between steps (BackendState): load_state after upload (and after the
  // Stepper's first force evaluation, which would overwrite f) restores a saved state
  // exactly; InputError when the sizes do not fit the uploaded model.
  virtual BackendState save_state() = 0;
  virtual void load_state(const BackendState& state) = 0;
  virtual void sync() = 0;
  virtual std::size_t device_bytes() const = 0;
  // Wall time of sub-stages run inside compute_forces (e.g. "contact.broad"), cumulative.
  virtual std::map<std::string, double> stage_seconds() const { return {}; }
  // The contact stage's counters of the last step (pairs, contacts, max_overlap, ...).
  virtual std::map<std::string, double> contact_stats() const { return {}; }

  // ---- Used by distributed runs (parallel/distributed_backend.hpp) -----------------------
  // compute_forces = element_forces(0, n_free_tets) + assemble_forces + add_contact_forces({}):
  // the element forces of tets [t0, t1) into the corner array, then the contact evaluation
  // and the gather to vertices of loads, damping and each vertex's own contact entries, then
  // the other ranks' contact forces, so that a halo exchange can overlap the tets whose
  // vertices are all owned, and the contact force shares of other ranks' vertices
  // (contact_shares(), contact_stage.hpp) can reach their owners, whose add_contact_forces
  // merges them in the one-rank order, while the gather runs. `undoable`:
  // the tets' dissipated energy before this evaluation is kept, and undo_dissipation() restores it
  // (a distributed rank queues its interior tets before the ranks agree that the layout stays; a
  // rebuild then discards that evaluation).
  virtual void element_forces(std::int64_t t0, std::int64_t t1, double dt_dissipation,
                              bool undoable) = 0;
  virtual void undo_dissipation() = 0;
  virtual void assemble_forces(double dt_dissipation, double mass_damping) = 0;
  // The shares as they travel (ContactShare; valid until the next call), and the shares that
  // arrived for this rank's vertices. set_share_routes says where they go (a layout's).
  virtual std::span<const ContactShare> contact_shares() = 0;
  virtual void add_contact_forces(std::span<const ContactShare> in) = 0;
  virtual void set_share_routes(const ShareRoutes& routes) = 0;
  // Halo exchange of x and v by index lists, packed where the data lives (on the GPU for
  // CUDA): pack_halo writes 6 doubles (x, v) per entry of send_index, item-major, to `out`
  // in memory space `where`; unpack_halo reads n_recv such records from `in` (in `where`)
  // into vertices recv_base + k. Records in the backend's own space() are written and read
  // there directly (a GPU rank's device-resident halo); others pass through one copy. The
  // vertices sent are those other ranks hold: only they can get contact force shares.
  virtual void set_halo(const std::vector<std::int64_t>& send_index, std::int64_t recv_base,
                        std::int64_t n_recv) = 0;
  virtual void pack_halo(double* out, Space where) = 0;
  virtual void unpack_halo(const double* in, Space where) = 0;
  // The memory space the state lives in.
  virtual Space space() const = 0;
  // max |x_i - x_i at the last mark_positions()| over the free vertices (how far owned
  // vertices moved since the decomposition was rebuilt). The reference is allocated on the
  // first mark, so a run that never marks pays nothing. queue_max_moved() queues it (on a GPU
  // without waiting: the halo's packing and the interior tets can be queued behind it or
  // beside it, SideQueue); max_moved() waits for the value queued last.
  virtual void mark_positions() = 0;
  virtual void queue_max_moved() = 0;
  virtual double max_moved() = 0;
  // A rank's share of save_state for its export (DistributedBackend::export_state): x of the
  // first `positions` vertices, v and diss_v of the first `vertices` (its owned ones: a layout
  // rebuild reads the positions first, the rest only when vertices change owner), diss_t of the
  // first `tets` tets (its home ones), f only with `forces` (a checkpoint keeps it; a layout
  // rebuild evaluates it again), x0 and f0 only with `relaxation`, and with `history` the
  // contact history without the pair list's reference (it belongs to the layout) or counters;
  // no fc (the coupling keeps it).
  struct OwnedPart {
    std::int64_t positions = 0, vertices = 0, tets = 0;
    bool forces = false, relaxation = false, history = true;
  };
  virtual BackendState save_owned(const OwnedPart& part) = 0;
  // upload, for a distributed rank's ghosts rebuilt with its owned part the same: `model` has
  // the last upload's tets and free (owned) vertices in the same order, its first `kept_tets`
  // tets on the same vertex numbers. What did not change stays as it is: the tets' reference
  // data, dissipation and corner lists, the owned vertices' model data and state (x, v, diss_v).
  // The other vertices (ghosts, fixed bodies') take the model's x and v and no dissipation, f is
  // zero. A load_state may follow, or load_history (the owned state as it was).
  virtual void upload_same_tets(const Model& model, std::int64_t kept_tets) = 0;
  // The contact history alone, as load_state takes it.
  virtual void load_history(const ContactState& history) = 0;
  // Enables the fluid coupling force fc (zero until the fluid writes it); views stay valid
  // until the next upload.
  virtual SolidViews solid_views();
};

// "cpu" (OpenMP) or "cuda"; throws InputError for an unknown or unavailable backend.
std::unique_ptr<Backend> make_backend(const std::string& name);
std::unique_ptr<Backend> make_host_backend();
std::unique_ptr<Backend> make_cuda_backend();  // memory_cuda/backend_cuda.cu, or throws

}  // namespace qdemsph
