#include "parallel/distributed_backend.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "core/radix_sort.hpp"
#include "core/select_host.hpp"
#include "core/timers.hpp"
#include "parallel/balance.hpp"
#include "parallel/band_cells.hpp"
#include "parallel/collectives.hpp"
#include "parallel/comm_plan.hpp"
#include "parallel/distributed_backend_mpi.hpp"
#include "parallel/local_model.hpp"
#include "parallel/rebuild_policy.hpp"

namespace qdemsph {

ParallelOptions parallel_options(const ParallelSpec& spec) {
  ParallelOptions o;
  o.curve = spec.curve;
  o.rebalance_threshold = spec.rebalance_threshold;
  o.rebalance_every = spec.rebalance_every;
  o.max_cell_cost = spec.max_cell_cost;
  return o;
}

namespace {

// A phase's seconds in a timer map (0 when it never ran).
double seconds_of(const std::map<std::string, double>& m, const char* phase) {
  const auto it = m.find(phase);
  return it == m.end() ? 0.0 : it->second;
}

// Every rank's slice on rank 0, concatenated in rank order, the contact dissipation summed
// (other ranks: empty).
StateSlice gather_slices(MPI_Comm comm, const StateSlice& s) {
  StateSlice a;
  a.vertex = gatherv(comm, s.vertex);
  a.x = gatherv(comm, s.x);
  a.v = gatherv(comm, s.v);
  a.f = gatherv(comm, s.f);
  a.diss_v = gatherv(comm, s.diss_v);
  a.x0 = gatherv(comm, s.x0);
  a.f0 = gatherv(comm, s.f0);
  a.tet = gatherv(comm, s.tet);
  a.diss_t = gatherv(comm, s.diss_t);
  const ContactState& c = s.contact;
  ContactState& h = a.contact;
  h.k1 = gatherv(comm, c.k1);
  h.k2 = gatherv(comm, c.k2);
  h.active = gatherv(comm, c.active);
  h.xi = gatherv(comm, c.xi);
  h.h = gatherv(comm, c.h);
  h.energy = gatherv(comm, c.energy);
  h.energy_t = gatherv(comm, c.energy_t);
  h.v = gatherv(comm, c.v);
  h.w = gatherv(comm, c.w);
  h.n1 = gatherv(comm, c.n1);
  for (double d : gatherv(comm, std::vector<double>{c.dissipated})) h.dissipated += d;
  return a;
}

template <class T>
CommField cfield(const std::vector<T>& v) {
  return comm_field(const_cast<T*>(v.data()), static_cast<std::int64_t>(v.size()));
}

// Free and global ids and bodies of the global model's vertices for anchor_slot (fixed: no
// owner), and which bodies one rank owns whole.
struct GlobalVertices {
  const std::vector<std::int32_t>& owner;
  const std::vector<std::int32_t>& vertex_body;
  const std::vector<std::int32_t>& body_rank;
  bool free(std::int64_t i) const { return owner[i] >= 0; }
  std::int64_t gid(std::int64_t i) const { return i; }
  std::int32_t body(std::int64_t i) const { return vertex_body[i]; }
  bool whole(std::int64_t b) const { return body_rank[b] >= 0; }
};

struct VertexRecord {
  std::int64_t gid;
  double x[3], v[3];
};
struct TetRecord {
  std::int64_t gid;
  double s[7];  // stress (Voigt) and von Mises
};

// Per-item time weights of the cost model [s per item per window]; only ratios matter. The
// defaults (before anything is measured) say a tet costs about four vertices.
struct Weights {
  double vertex = 0.25, tet = 1.0, contact = 1.0;
  // The partition's cost of items: vertices, the tets they are the smallest vertex of, contact
  // vertices.
  double cost(double vertices, double home_tets, double contact_vertices) const {
    return vertex * vertices + tet * home_tets + contact * contact_vertices;
  }
};

class DistributedImpl final : public DistributedBackend, private SolidSync {
 public:
  DistributedImpl(MPI_Comm comm, std::unique_ptr<Backend> local, const ParallelOptions& opt)
      : local_(std::move(local)),
        opt_(opt),
        curve_(parse_curve(opt.curve)),
        timers_([this] { local_->sync(); }) {
    MPI_Comm_dup(comm, &comm_);
    MPI_Comm_rank(comm_, &me_);
    MPI_Comm_size(comm_, &np_);
  }
  ~DistributedImpl() override {
    halo_.reset();
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Comm_free(&comm_);
  }

  std::string name() const override { return local_->name(); }
  int rank() const override { return me_; }
  int size() const override { return np_; }

  // ---- setup -------------------------------------------------------------------------------

  void upload(const Model& m) override {
    g_ = &m;
    ix_ = index_model(m);
    owner_.assign(m.n_vertices(), -1);  // fixed bodies: no owner
    body_rank_.assign(m.bodies.size(), -1);
    contact_ = m.contact.enabled;
    fixed_cells_.clear();
    if (contact_) {
      // Reach needed around an owned contact vertex (a touching primitive, the other side's
      // owning triangle and its neighbours, both sides moving by `slack`): 2 diam + 2 D_DEM +
      // 2 slack; two rings of band cells of width diam + D_DEM + slack cover it. diam: the
      // largest primitive diameter, +25 % for deformation.
      const double diam = 2.5 * ix_.prim_radius, d = m.contact.d_dem;
      reach_ = diam + d;
      slack0_ = 0.5 * reach_;
      set_slack(slack0_);
    }
    precompute_fixed_output();
    // Every rank starts from a contiguous share of the model's initial state, then the first
    // partition moves it to the owners: the restart path (load_state), taken by every run.
    BackendState s;
    s.x = m.x;
    s.v = m.v;
    s.f.assign(m.n_vertices(), Vec3{});
    s.diss_v.assign(m.n_vertices(), 0.0);
    s.diss_t.assign(m.n_tets(), 0.0);
    if (contact_) s.contact.emplace();
    load_state(s);
  }

  // The first distribution (every item from its start slice to its owner; after a restart,
  // from the file's shares) is set-up: its balance and migration seconds are reported apart
  // (parallel.setup_s), not in the stepping loop's phases.
  void adopt(const StateSlice& s) override {
    if (!g_) throw std::logic_error("DistributedBackend::adopt before upload");
    const double b0 = seconds("balance"), m0 = seconds("migration"), t0 = MPI_Wtime();
    reassign(s, true);
    migrate(s);
    setup_balance_s_ += seconds("balance") - b0;
    setup_migration_s_ += seconds("migration") - m0;
    rebuilt_at_ = MPI_Wtime();
    rebuild_s_ = rebuilt_at_ - t0;  // what a rebuild costs, until one is measured
  }

  // ---- stages ------------------------------------------------------------------------------

  void use_preload(bool on) override {
    preload_ = on;
    local_->use_preload(on);
  }

  void compute_forces(double dt_diss, double alpha) override {
    const bool dynamic = dt_diss > 0;
    if (dynamic) {
      relaxing_ = false;
      ++steps_;
    }
    // The phases count dynamic steps, as the Stepper's and the contact stage's do: the first
    // evaluation (the Stepper's set-up) and relaxation sweeps (dt_diss = 0) are not steps.
    PhaseTimers untimed;
    PhaseTimers& tm = dynamic ? timers_ : untimed;
    // The skin test's reduction, the halo's packing and the interior tets are queued before the
    // ranks agree on the test: on a GPU they run meanwhile (when drift marked its end, the
    // reduction and the packing are queued after the interior tets, from that mark). A rebuild
    // finishes the exchange and starts again on the new layout (the interior tets queued so far
    // are computed again).
    const bool drifted = drift_marked_;
    drift_marked_ = false;
    if (!drifted) queue_skin_and_pack(tm, true);
    start_halo(tm, dt_diss, drifted ? &drifted_ : nullptr);
    if (maybe_rebuild(dynamic)) {
      queue_skin_and_pack(tm, false);
      start_halo(tm, dt_diss);
    }
    CommEngine& e = halo_->engine();
    {
      auto s = tm.launch("halo");
      auto s1 = tm.launch("halo.xv");
      const auto in = e.finish_packed();
      local_->unpack_halo(reinterpret_cast<const double*>(in.data()), e.packed_space());
      halo_bytes_ += e.last_bytes();
    }
    // Each vertex's own contact entries and the element forces' gather (queued after the
    // contact evaluation) run while the shares are read and exchanged (on a GPU): these scopes
    // do not synchronise, that work counts at add_contact_forces, whose merge of the shares
    // runs beside the gather.
    {
      auto s = tm.launch("elements");
      local_->element_forces(L_.n_interior, static_cast<std::int64_t>(L_.tets.size()), dt_diss,
                             false);
      local_->assemble_forces(dt_diss, alpha);
    }
    std::vector<std::byte> in;
    if (contact_) {
      std::span<const ContactShare> out;
      {
        auto s = tm.launch("elements");
        auto s1 = tm.launch("elements.shares");
        out = local_->contact_shares();
      }
      {
        auto s = tm.launch("halo");
        auto s1 = tm.launch("halo.shares");
        send_shares(out);
      }
      auto s = tm.launch("halo");
      auto s1 = tm.launch("halo.shares");
      in = halo_->engine().exchange_finish();
    }
    {
      auto s = tm.scope("elements");
      local_->add_contact_forces(
          {reinterpret_cast<const ContactShare*>(in.data()), in.size() / sizeof(ContactShare)});
    }
    ++exchanges_;
  }

  // The kick's scope does not synchronise a GPU: the first half kick's device time counts in
  // the next scope that does (the second's, ~10 us, is not counted), and drift does not wait for
  // the kick before it is queued.
  void kick(double h) override {
    auto s = timers_.launch("integration");
    local_->kick(h);
  }
  // On a GPU the drift marks its end (drifted_), where the next force evaluation's skin-test
  // reduction and halo packing start on the side stream: the interior tets, which
  // compute_forces queues first, follow the drift on the device without waiting for those
  // launches or kernels (cube block, 4 GPUs: the host launched the interior tets ~35 us after a
  // step's start while it launched the packing first, against ~15 us on one GPU). The scope
  // does not synchronise (the skin test and the exchange wait for their own marks); the drift's
  // device time counts in the halo's scopes.
  void drift(double h) override {
    if (!device_halo()) {
      auto s = timers_.scope("integration");
      local_->drift(h);
      return;
    }
    auto s = timers_.launch("integration");
    local_->drift(h);
    drifted_.record();
    drift_marked_ = true;
  }
  void damped_step(double dt, double c) override {
    auto s = timers_.scope("integration");
    local_->damped_step(dt, c);
  }
  void zero_velocity() override { local_->zero_velocity(); }
  void mark_relax_start() override {
    relaxing_ = true;
    local_->mark_relax_start();
  }

  StaticStats static_stats() override {
    StaticStats s = local_->static_stats();
    double mx = 0;
    MPI_Allreduce(&s.residual_max, &mx, 1, MPI_DOUBLE, MPI_MAX, comm_);
    double sums[2] = {s.rayleigh_num, s.rayleigh_den};
    allreduce_sum_same(comm_, sums, 2);
    return {mx, sums[0], sums[1]};
  }

  Energies energies() override {
    // Each rank counts its home tets, owned vertices and the contact records it evaluates
    // (contact_stage.hpp, Evaluator): every item once over the ranks.
    const Energies e = local_->energies();
    double a[6] = {e.kinetic, e.strain, e.potential, e.dissipated, e.contact, e.contact_dissipated};
    allreduce_sum_same(comm_, a, 6);
    Energies r;
    r.kinetic = a[0];
    r.strain = a[1];
    r.potential = a[2];
    r.dissipated = a[3];
    r.contact = a[4];
    r.contact_dissipated = a[5];
    return r;
  }

  std::int64_t find_non_finite() override {
    const std::int64_t i = local_->find_non_finite();
    return min_over_ranks(i < 0 ? -1 : L_.vertices[i]);
  }

  // The smallest global id among the tets flagged since the last call (on this layout, or on
  // one a rebuild replaced).
  std::int64_t take_inverted_tet() override {
    hold_inverted();
    const std::int64_t g = held_inverted_;
    held_inverted_ = -1;
    return min_over_ranks(g);
  }

  // The deep contact of the rank holding the smallest global vertex id among the flagged ones.
  std::optional<DeepContact> take_deep_contact() override {
    hold_deep();
    const std::optional<DeepContact> c = held_deep_;
    held_deep_.reset();
    const std::int64_t gv = c ? c->vertex : -1;
    const std::int64_t v = min_over_ranks(gv);
    if (v < 0) return std::nullopt;
    double mine[5] = {-1e300, -1e300, -1e300, -1e300, -1e300}, all[5];
    if (c && gv == v) {
      mine[0] = c->depth;
      mine[1] = c->bound;
      mine[2] = c->body1;
      mine[3] = c->body2;
      mine[4] = c->wall;
    }
    MPI_Allreduce(mine, all, 5, MPI_DOUBLE, MPI_MAX, comm_);
    return DeepContact{
        v,     static_cast<int>(all[2]), static_cast<int>(all[3]), static_cast<int>(all[4]), all[0],
        all[1]};
  }

  // The smallest limit over the ranks' held tets; located: its tet by global id (the
  // smallest).
  CriticalTet critical_tet(bool locate) override {
    const CriticalTet c = local_->critical_tet(locate);
    const double dt = c.dt > 0 ? c.dt : std::numeric_limits<double>::infinity();
    double dmin = 0;
    MPI_Allreduce(&dt, &dmin, 1, MPI_DOUBLE, MPI_MIN, comm_);
    if (!(dmin < std::numeric_limits<double>::infinity())) return {};
    if (!locate) return {dmin, -1};
    return {dmin, min_over_ranks(c.tet >= 0 && dt == dmin ? L_.tets[c.tet] : -1)};
  }

  // Global fields on rank 0: free vertices and tets from their owners / home ranks, fixed
  // bodies from the model (they never move) and the stress computed for them at upload.
  HostFields download(bool with_stress) override {
    if (with_stress) refresh_ghosts();  // ghost v after the last kick, for viscous stress
    const HostFields h = local_->download(with_stress);
    std::vector<VertexRecord> vr(L_.n_owned);
    for (std::int64_t i = 0; i < L_.n_owned; ++i)
      vr[i] = {L_.vertices[i], {h.x[i].x, h.x[i].y, h.x[i].z}, {h.v[i].x, h.v[i].y, h.v[i].z}};
    const std::vector<VertexRecord> allv = gatherv(comm_, vr);
    std::vector<TetRecord> all_t;
    if (with_stress) {
      std::vector<TetRecord> tr(L_.n_home);
      for (std::int64_t j = 0; j < L_.n_home; ++j) {
        tr[j].gid = L_.tets[j];
        for (int c = 0; c < 6; ++c) tr[j].s[c] = h.stress[j][c];
        tr[j].s[6] = h.von_mises[j];
      }
      all_t = gatherv(comm_, tr);
    }
    HostFields out;
    if (me_ != 0) return out;
    const Model& g = *g_;
    out.x = g.x;
    out.v = g.v;
    for (const VertexRecord& r : allv) {
      out.x[r.gid] = {r.x[0], r.x[1], r.x[2]};
      out.v[r.gid] = {r.v[0], r.v[1], r.v[2]};
    }
    if (with_stress) {
      out.stress.assign(g.n_tets(), {});
      out.von_mises.assign(g.n_tets(), 0.0);
      for (std::size_t k = 0; k < fixed_vm_.size(); ++k) {
        out.stress[g.n_free_tets + k] = fixed_stress_[k];
        out.von_mises[g.n_free_tets + k] = fixed_vm_[k];
      }
      for (const TetRecord& r : all_t) {
        for (int c = 0; c < 6; ++c) out.stress[r.gid][c] = r.s[c];
        out.von_mises[r.gid] = r.s[6];
      }
    }
    return out;
  }

  void sync() override { local_->sync(); }

  std::size_t device_bytes() const override {
    std::int64_t mine = static_cast<std::int64_t>(local_->device_bytes()), all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT64_T, MPI_SUM, comm_);
    return static_cast<std::size_t>(all);
  }

  // Sub-phases, the largest over ranks (parallel.phases_* has max and mean of the phases):
  // contact's, and where the halo and elements time of a step goes (halo.skin: the contact
  // band's displacement test; halo.xv: the ghosts' x, v; halo.shares: the contact force shares'
  // exchange; elements.shares: collecting them from the backend), and a rebuild's (export: the
  // state from the backend; state: owners and migration plans; layout: the rank's new part,
  // of it layout.tets the held tets, layout.band the contact band's cells and ranks,
  // layout.halo the halo lists, plan and ghosts' x, v, layout.model the model; upload: into
  // the backend, of it upload.model the model, upload.state the state, upload.routes the halo
  // and share lists).
  std::map<std::string, double> stage_seconds() const override {
    const std::map<std::string, double> mine = local_sub_phases();
    constexpr int n = std::size(kBodySubPhases);
    double v[n], mx[n];
    for (int k = 0; k < n; ++k) v[k] = seconds_of(mine, kBodySubPhases[k]);
    MPI_Allreduce(v, mx, n, MPI_DOUBLE, MPI_MAX, comm_);
    std::map<std::string, double> out;
    for (int k = 0; k < n; ++k)
      if (contact_ || std::string_view(kBodySubPhases[k]).rfind("contact.", 0) != 0)
        out[kBodySubPhases[k]] = mx[k];
    return out;
  }

  // Counts summed over ranks (records and active ones: each once; candidate pairs of
  // primitives near a border on each rank holding them),
  // overlaps the largest.
  std::map<std::string, double> contact_stats() const override {
    if (!contact_) return {};
    std::map<std::string, double> c = local_->contact_stats();
    double s[3] = {c["pairs"], c["contacts"], c["active"]}, ss[3];
    double m[3] = {c["max_overlap"], std::max(c["max_overlap_ever"], overlap_acc_),
                   c["pair_rebuilds"] + rebuilds_acc_},
           mm[3];
    MPI_Allreduce(s, ss, 3, MPI_DOUBLE, MPI_SUM, comm_);
    MPI_Allreduce(m, mm, 3, MPI_DOUBLE, MPI_MAX, comm_);
    return {{"pairs", ss[0]},       {"contacts", ss[1]},         {"active", ss[2]},
            {"max_overlap", mm[0]}, {"max_overlap_ever", mm[1]}, {"pair_rebuilds", mm[2]}};
  }

  // Stages of a rank's own backend, not of the decorator.
  void element_forces(std::int64_t, std::int64_t, double, bool) override {
    unsupported("element_forces");
  }
  void undo_dissipation() override { unsupported("undo_dissipation"); }
  void assemble_forces(double, double) override { unsupported("assemble_forces"); }
  std::span<const ContactShare> contact_shares() override { unsupported("contact_shares"); }
  void add_contact_forces(std::span<const ContactShare>) override {
    unsupported("add_contact_forces");
  }
  void set_share_routes(const ShareRoutes&) override { unsupported("set_share_routes"); }
  void set_halo(const std::vector<std::int64_t>&, std::int64_t, std::int64_t) override {
    unsupported("set_halo");
  }
  void pack_halo(double*, Space) override { unsupported("pack_halo"); }
  void unpack_halo(const double*, Space) override { unsupported("unpack_halo"); }
  Space space() const override { return local_->space(); }
  void mark_positions() override { unsupported("mark_positions"); }
  void queue_max_moved() override { unsupported("queue_max_moved"); }
  double max_moved() override { unsupported("max_moved"); }
  BackendState save_owned(const OwnedPart&) override { unsupported("save_owned"); }
  void upload_same_tets(const Model&, std::int64_t) override { unsupported("upload_same_tets"); }
  void load_history(const ContactState&) override { unsupported("load_history"); }

  // ---- fluid coupling (sph/solid_coupling.hpp) ---------------------------------------------
  // The coupling reads and writes whole-model arrays by global vertex id, the same on every
  // rank, in the local backend's memory space: pull() gives it the x, v of every coupled vertex
  // (the owners' values, one allgather through host memory; fixed bodies do not move) and the
  // f, inv_mass, held of this rank's owned ones (others: inv_mass 0, so it leaves their v
  // alone); since every rank gathers the same fluid force on every coupled vertex (the stage
  // sums the marker forces over the ranks), fc here is every coupled vertex's, and push() (and
  // each rebuild) gives the owned ones theirs. Between the local and the whole-model arrays
  // values move by indexed copies where they live (space_gather / space_scatter).
  SolidViews solid_views() override {
    const Model& g = *g_;
    cspace_ = local_->solid_views().space;
    cx_ = Vec3Buffer(cspace_), cv_ = Vec3Buffer(cspace_), cf_ = Vec3Buffer(cspace_),
    cfc_ = Vec3Buffer(cspace_);
    cinv_ = Buffer<double>(cspace_), cheld_ = Buffer<std::uint8_t>(cspace_);
    cx_.assign(g.x);
    cv_.assign(g.v);
    cf_.resize(g.n_vertices());
    cfc_.resize(g.n_vertices());
    cinv_.resize(g.n_vertices());
    cheld_.resize(g.n_vertices());
    coupled_ = true;
    install_coupling();
    SolidViews s;
    s.space = cspace_;
    s.x = cx_.cview();
    s.v = cv_.view();
    s.f = cf_.view();
    s.fc = cfc_.view();
    s.inv_mass = cinv_.cview();
    s.held = cheld_.cview();
    s.sync = this;
    return s;
  }

  void pull(std::span<const std::int32_t> coupled) override {
    if (is_coupled_.empty()) {
      is_coupled_.assign(g_->n_vertices(), 0);
      for (auto v : coupled) is_coupled_[v] = 1;
      const std::int64_t nc = static_cast<std::int64_t>(coupled.size());
      all_gid_ = Buffer<std::int64_t>(cspace_);
      all_gid_.assign(std::vector<std::int64_t>(coupled.begin(), coupled.end()));
      zeros_ = Buffer<double>(cspace_, nc);
      stage_ = Buffer<double>(cspace_, 6 * nc);
      stage_idx_ = Buffer<std::int64_t>(cspace_, nc);
      index_coupled();
    }
    const SolidViews& l = local_sv_;
    const std::int64_t n = static_cast<std::int64_t>(own_gid_h_.size());
    double* st = stage_.view().p;
    // x, v of the owned coupled vertices to every rank.
    const double* comp[6] = {l.x.x, l.x.y, l.x.z, l.v.x, l.v.y, l.v.z};
    for (int c = 0; c < 6; ++c)
      space_gather(cspace_, st + c * n, comp[c], own_local_.cview().p, n, 8);
    std::vector<double> h(6 * n);
    if (n > 0) space_copy(h.data(), Space::Host, st, cspace_, h.size() * sizeof(double));
    struct Moved {
      std::int64_t gid;
      double c[6];
    };
    std::vector<Moved> mine(n);
    for (std::int64_t k = 0; k < n; ++k) {
      mine[k].gid = own_gid_h_[k];
      for (int c = 0; c < 6; ++c) mine[k].c[c] = h[c * n + k];
    }
    const std::vector<Moved> all = allgatherv(comm_, mine);
    const std::int64_t m = static_cast<std::int64_t>(all.size());
    std::vector<std::int64_t> gid(m);
    h.assign(6 * m, 0.0);
    for (std::int64_t k = 0; k < m; ++k) {
      gid[k] = all[k].gid;
      for (int c = 0; c < 6; ++c) h[c * m + k] = all[k].c[c];
    }
    if (m > 0) {
      space_copy(stage_idx_.view().p, cspace_, gid.data(), Space::Host, m * sizeof(std::int64_t));
      space_copy(st, cspace_, h.data(), Space::Host, h.size() * sizeof(double));
    }
    const Vec3View x = cx_.view(), v = cv_.view();
    double* whole[6] = {x.x, x.y, x.z, v.x, v.y, v.z};
    for (int c = 0; c < 6; ++c)
      space_scatter(cspace_, whole[c], stage_idx_.cview().p, st + c * m, m, 8);
    // f, inv_mass, held of the owned ones (inv_mass 0 for the others).
    space_scatter(cspace_, cinv_.view().p, all_gid_.cview().p, zeros_.cview().p, all_gid_.size(),
                  8);
    const Vec3View f = cf_.view();
    copy_coupled(f.x, l.f.x, n, 8, true);
    copy_coupled(f.y, l.f.y, n, 8, true);
    copy_coupled(f.z, l.f.z, n, 8, true);
    copy_coupled(cinv_.view().p, l.inv_mass.p, n, 8, true);
    copy_coupled(cheld_.view().p, l.held.p, n, 1, true);
  }

  void push(std::span<const std::int32_t>) override {
    const SolidViews& l = local_sv_;
    const std::int64_t n = static_cast<std::int64_t>(own_gid_h_.size());
    const Vec3View v = cv_.view(), f = cf_.view(), fc = cfc_.view();
    copy_coupled(l.v.x, v.x, n, 8, false), copy_coupled(l.v.y, v.y, n, 8, false);
    copy_coupled(l.v.z, v.z, n, 8, false);
    copy_coupled(l.f.x, f.x, n, 8, false), copy_coupled(l.f.y, f.y, n, 8, false);
    copy_coupled(l.f.z, f.z, n, 8, false);
    copy_coupled(l.fc.x, fc.x, n, 8, false), copy_coupled(l.fc.y, fc.y, n, 8, false);
    copy_coupled(l.fc.z, fc.z, n, 8, false);
  }

  // ---- records and the checkpoint hook -----------------------------------------------------

  ParallelRecord record(const std::map<std::string, double>& run_phases) override {
    // The last full window stands unless none was measured, a rebalance awaits its "after",
    // or at least half a window has passed since (a step or two is noise, not imbalance).
    const std::int64_t since = steps_ - window_start_;
    if (since > 0 && (windows_ == 0 || pending_after_ || 2 * since >= opt_.rebalance_every))
      measure_window();
    ParallelRecord r;
    r.ranks = np_;
    r.curve = curve_name(curve_);
    r.rebalances = rebalances_;
    r.rebuilds = rebuilds_;
    r.contact_slack = slack_;
    r.imbalance = last_.imbalance;
    r.imbalance_modelled = last_.modelled;
    r.imbalance_initial = imbalance_initial_;
    r.rebalance_log = log_;
    r.rebuild_log = rebuild_log_;
    const auto& t = timers_.seconds();
    const auto sec = seconds_of;
    const double contact = local_contact_seconds();
    // The fluid's ghost refreshes and layout rebuilds count as halo and migration, like the
    // bodies' (sph_stage.hpp: sub-phases sph.halo and sph.rebuild of the run's "sph"), and its
    // first layout, built before the steps (sph.setup), as set-up. Balance and migration are
    // those of the stepping loop: the first distribution is set-up (adopt).
    const double fh = sec(run_phases, "sph.halo"), fr = sec(run_phases, "sph.rebuild"),
                 fs = sec(run_phases, "sph.setup");
    double p[8] = {sec(t, "elements") - contact,
                   sec(t, "integration"),
                   contact,
                   sec(run_phases, "sph") - fh - fr,
                   sec(t, "halo") + fh,
                   sec(t, "migration") - setup_migration_s_ + fr,
                   sec(t, "balance") - setup_balance_s_,
                   sec(run_phases, "output")};
    double mx[9], sum[8];
    std::copy(p, p + 8, mx);
    mx[8] = setup_balance_s_ + setup_migration_s_ + fs;
    MPI_Allreduce(MPI_IN_PLACE, mx, 9, MPI_DOUBLE, MPI_MAX, comm_);
    std::copy(p, p + 8, sum);
    allreduce_sum_same(comm_, sum, 8);
    for (int k = 0; k < 8; ++k) {
      r.phases_max[kParallelPhases[k]] = mx[k];
      r.phases_mean[kParallelPhases[k]] = sum[k] / np_;
    }
    r.setup_s = mx[8];
    // Every rank's phases and sub-phases side by side, on rank 0 (which writes the record).
    const std::map<std::string, double> subs = local_sub_phases();
    std::vector<double> row(p, p + 8);
    for (const char* k : kBodySubPhases) row.push_back(sec(subs, k));
    for (const char* k : kFluidSubPhases) row.push_back(sec(run_phases, k));
    const int w = static_cast<int>(row.size());
    std::vector<double> rows(me_ == 0 ? static_cast<std::size_t>(w) * np_ : 0);
    MPI_Gather(row.data(), w, MPI_DOUBLE, rows.data(), w, MPI_DOUBLE, 0, comm_);
    for (int q = 0; me_ == 0 && q < np_; ++q) {
      std::map<std::string, double>& m = r.phases_by_rank.emplace_back();
      int c = 0;
      for (const char* k : kParallelPhases) m[k] = rows[q * w + c++];
      auto sub = [&](const char* k) {  // sub-phases a rank did not time are left out
        if (const double v = rows[q * w + c++]; v != 0) m[k] = v;
      };
      for (const char* k : kBodySubPhases) sub(k);
      for (const char* k : kFluidSubPhases) sub(k);
    }
    r.owned_vertices = allgatherv(comm_, std::vector<std::int64_t>{L_.n_owned});
    r.owned_tets = allgatherv(comm_, std::vector<std::int64_t>{L_.n_home});
    double b[3] = {static_cast<double>(migrated_bytes_), static_cast<double>(halo_bytes_),
                   static_cast<double>(exchanges_)};
    allreduce_sum_same(comm_, b, 3);
    r.migrated_bytes = static_cast<std::int64_t>(b[0]);
    r.halo_bytes_per_step = b[2] > 0 ? b[1] / (b[2] / np_) : 0.0;
    return r;
  }

  StateSlice export_state() override { return export_slice(true); }

  // This rank's owned vertices and home tets (in their layout's order) and the history of its
  // records, keys and vertices by global id; the forces only with `forces` (a rebuild of the
  // layout evaluates them again). Not `whole` (a layout rebuild's, not relaxing): the owned
  // vertices' x and the history alone, which complete_slice completes when vertices change
  // owner (else the device keeps the rest: install's keep_owned).
  StateSlice export_slice(bool forces, bool whole = true) {
    const std::int64_t n = whole ? L_.n_owned : 0;
    BackendState st = local_->save_owned(
        {L_.n_owned, n, whole ? L_.n_home : 0, forces, whole && relaxing_, true});
    StateSlice s;
    s.vertex = owned_vertices();
    s.x = std::move(st.x);
    if (whole) take_state(s, st);
    if (!st.contact) return s;
    // Each history entry once: a rank holds the history of the records it evaluates only
    // (those anchored at its owned vertices, contact_record.hpp anchor_slot). An inactive
    // entry is never looked up. Gathered on the threads.
    const ContactState& c = *st.contact;
    const std::vector<std::int64_t> keep =
        select_indices(HostExec{}, static_cast<std::int64_t>(c.size()),
                       [&](std::int64_t e) { return c.active[e] != 0; });
    ContactState& h = s.contact;
    h.dissipated = c.dissipated;  // this rank's share: its records' dissipation
    h.resize(keep.size());
    for_each(HostExec{}, static_cast<std::int64_t>(keep.size()), [&](std::int64_t j) {
      const std::int64_t e = keep[j];
      h.set(j, c, e);
      h.k1[j] = ids_.k1_to_global(c.k1[e]);
      h.k2[j] = ids_.k2_to_global(c.k1[e], c.k2[e]);
      for (int k = 0; k < 4; ++k) h.v[j][k] = c.v[e][k] >= 0 ? L_.vertices[c.v[e][k]] : -1;
    });
    return s;
  }

  // The owned vertices' v, dissipation and forces, relaxation start state, and the home tets
  // and their dissipation from `st` into `s`.
  void take_state(StateSlice& s, BackendState& st) const {
    s.v = std::move(st.v);
    s.f = std::move(st.f);
    s.diss_v = std::move(st.diss_v);
    s.x0 = std::move(st.x0);
    s.f0 = std::move(st.f0);
    s.tet = home_tets();
    s.diss_t = std::move(st.diss_t);
  }

  // The rest of a slice export_slice(false, false) gave, read when vertices change owner.
  void complete_slice(StateSlice& s) {
    BackendState st = local_->save_owned({0, L_.n_owned, L_.n_home, false, false, false});
    take_state(s, st);
  }

  // The whole model's state on rank 0, as one rank's backend has it: free vertices and tets
  // from their owners and home ranks, fixed bodies from the model (they never move; force and
  // dissipation zero), the history sorted by key, the contact counters of contact_stats(). The
  // pair-list reference stays empty: it belongs to one layout.
  BackendState save_state() override {
    const std::map<std::string, double> counters = contact_stats();
    const StateSlice a = gather_slices(comm_, export_state());
    BackendState w;
    if (me_ != 0) return w;
    const Model& g = *g_;
    w.x = g.x;
    w.v = g.v;
    w.f.assign(g.n_vertices(), Vec3{});
    w.diss_v.assign(g.n_vertices(), 0.0);
    w.diss_t.assign(g.n_tets(), 0.0);
    if (relaxing_) {
      w.x0.assign(g.n_vertices(), Vec3{});
      w.f0.assign(g.n_vertices(), Vec3{});
    }
    for (std::size_t k = 0; k < a.vertex.size(); ++k) {
      const std::int64_t i = a.vertex[k];
      w.x[i] = a.x[k];
      w.v[i] = a.v[k];
      w.f[i] = a.f[k];
      w.diss_v[i] = a.diss_v[k];
      if (relaxing_) {
        w.x0[i] = a.x0[k];
        w.f0[i] = a.f0[k];
      }
    }
    for (std::size_t k = 0; k < a.tet.size(); ++k) w.diss_t[a.tet[k]] = a.diss_t[k];
    if (coupled_) w.fc = cfc_.to_host();  // every coupled vertex's, the same on every rank
    if (!contact_) return w;
    const ContactState& h = a.contact;
    std::vector<std::size_t> order(h.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) {
      return std::pair(h.k1[p], h.k2[p]) < std::pair(h.k1[q], h.k2[q]);
    });
    ContactState& c = w.contact.emplace();
    for (std::size_t e : order) c.push_back(h, e);
    c.dissipated = h.dissipated;
    c.stats = {static_cast<std::int64_t>(counters.at("pairs")),
               static_cast<std::int64_t>(counters.at("contacts")),
               static_cast<std::int64_t>(counters.at("active")), counters.at("max_overlap")};
    c.max_overlap_ever = counters.at("max_overlap_ever");
    c.rebuilds = static_cast<std::int64_t>(counters.at("pair_rebuilds"));
    return w;
  }

  // Every rank passes the whole model's state; each adopts a contiguous share of the free
  // vertices, free tets and active history entries (rank 0 takes the contact dissipation).
  // The pair-list reference is dropped (the list is built afresh for the new layout); the
  // counters carry on.
  void load_state(const BackendState& w) override {
    if (!g_) throw std::logic_error("DistributedBackend::load_state before upload");
    const Model& g = *g_;
    const auto fits = [](const auto& a, std::int64_t n) {
      return static_cast<std::int64_t>(a.size()) == n;
    };
    const std::int64_t nv = g.n_vertices(), nt = g.n_tets();
    const bool relax = !w.x0.empty();
    if (!fits(w.x, nv) || !fits(w.v, nv) || !fits(w.f, nv) || !fits(w.diss_v, nv) ||
        !fits(w.diss_t, nt) || (relax && (!fits(w.x0, nv) || !fits(w.f0, nv))) ||
        (!w.fc.empty() && !fits(w.fc, nv)) || w.contact.has_value() != contact_)
      throw InputError("backend state does not fit the model (vertex, tet or contact counts)");
    // The coupling force of every vertex (whole-model, as the coupling keeps it on every rank);
    // adopt() installs the owned vertices' in the new local model.
    if (coupled_) cfc_.assign(w.fc.empty() ? std::vector<Vec3>(nv) : w.fc);
    StateSlice s;
    const std::int64_t nfv = g.n_free_vertices, nft = g.n_free_tets;
    const std::int64_t v0 = nfv * me_ / np_, v1 = nfv * (me_ + 1) / np_;
    const std::int64_t t0 = nft * me_ / np_, t1 = nft * (me_ + 1) / np_;
    std::vector<std::int64_t> ids(v1 - v0);
    std::iota(ids.begin(), ids.end(), v0);
    s.set_vertices(std::move(ids), w, v0, relax);
    s.tet.resize(t1 - t0);
    std::iota(s.tet.begin(), s.tet.end(), t0);
    s.diss_t.assign(w.diss_t.begin() + t0, w.diss_t.begin() + t1);
    if (contact_) {
      const ContactState& c = *w.contact;
      const std::int64_t ne = static_cast<std::int64_t>(c.size());
      for (std::int64_t e = ne * me_ / np_; e < ne * (me_ + 1) / np_; ++e)
        if (c.active[e]) s.contact.push_back(c, e);  // an inactive entry is never looked up
      s.contact.dissipated = me_ == 0 ? c.dissipated : 0.0;
    }
    adopt(s);
    relaxing_ = relax;
    if (contact_) {
      overlap_acc_ = w.contact->max_overlap_ever;
      rebuilds_acc_ = static_cast<double>(w.contact->rebuilds);
    }
  }

  std::vector<std::int64_t> owned_vertices() const override {
    return {L_.vertices.begin(), L_.vertices.begin() + L_.n_owned};
  }
  std::vector<std::int64_t> home_tets() const override {
    return {L_.tets.begin(), L_.tets.begin() + L_.n_home};
  }
  std::int64_t rebuilds() const override { return rebuilds_; }
  std::int64_t rebalances() const override { return rebalances_; }

 private:
  [[noreturn]] static void unsupported(const char* what) {
    throw std::logic_error(std::string("DistributedBackend: ") + what +
                           " belongs to a rank's own backend");
  }

  std::int64_t min_over_ranks(std::int64_t id) const {
    std::int64_t v = id < 0 ? std::numeric_limits<std::int64_t>::max() : id, m = 0;
    MPI_Allreduce(&v, &m, 1, MPI_INT64_T, MPI_MIN, comm_);
    return m == std::numeric_limits<std::int64_t>::max() ? -1 : m;
  }

  std::uint64_t cell_key(Vec3 p) const {
    const BandCell c = band_cell(p, band_);
    return band_key(c.i[0], c.i[1], c.i[2]);
  }

  // This rank's sub-phases: its contact stage's and its timers' (names with a dot).
  std::map<std::string, double> local_sub_phases() const {
    std::map<std::string, double> mine = local_stage_seconds();
    for (const auto& [k, v] : timers_.seconds())
      if (k.find('.') != std::string::npos) mine[k] = v;
    return mine;
  }
  std::map<std::string, double> local_stage_seconds() const {
    std::map<std::string, double> s = contact_acc_;
    for (const auto& [k, v] : local_->stage_seconds()) s[k] += v;
    return s;
  }
  double local_contact_seconds() const {
    double c = 0;
    for (const auto& [k, v] : local_stage_seconds())
      if (k.rfind("contact.", 0) == 0) c += v;
    return c;
  }

  // The contact force shares of ghost vertices (this rank evaluated their records) sent to the
  // vertices' owners, as the contact stage wrote them (ContactShare: the owner's rank and index
  // there, global keys); the halo engine's exchange_finish returns the records of those other
  // ranks evaluated for owned vertices, by source rank. Over the halo plan's neighbours: a
  // ghost's owner is one.
  void send_shares(std::span<const ContactShare> out) {
    for (const ContactShare& s : out)
      if (s.rank < 0 || s.rank >= np_ || s.rank == me_)
        throw std::logic_error("contact share for vertex " + std::to_string(s.vertex) +
                               " of rank " + std::to_string(s.rank) + " on rank " +
                               std::to_string(me_));
    const Buckets by = bucket_indices(HostExec{}, static_cast<std::int64_t>(out.size()), np_,
                                      [&](std::int64_t k) { return out[k].rank; });
    shares_out_.resize(out.size());
    for (std::size_t j = 0; j < out.size(); ++j) shares_out_[j] = out[by.index[j]];
    CommEngine& e = halo_->engine();
    e.exchange_begin(std::as_bytes(std::span(shares_out_)), by.start, sizeof(ContactShare));
    halo_bytes_ += e.last_bytes();
  }

  // Where this rank's contact shares go (ShareRoutes), for the layout L just installed (its halo
  // planned): each free ghost's owner and its index there (which the owner gathers to it: the
  // owned vertices are its first), and the local model's feature ids.
  ShareRoutes share_routes(const LocalLayout& L, const FeatureIds& ids) {
    std::vector<std::uint64_t> index(halo_->n_total());
    std::iota(index.begin(), index.begin() + L.n_owned, std::uint64_t{0});
    const CommField f = comm_field(index);
    halo_->gather_begin({&f, 1});
    halo_->gather_finish({&f, 1});
    ShareRoutes r;
    const std::int64_t n = L.n_free - L.n_owned;
    r.rank.resize(n);
    r.index.resize(n);
    for_each(HostExec{}, n, [&](std::int64_t k) {
      r.rank[k] = owner_[L.vertices[L.n_owned + k]];
      r.index[k] = static_cast<std::int32_t>(index[L.n_owned + k]);
    });
    r.triangle = ids.triangle;
    r.edge = ids.edge;
    return r;
  }

  void refresh_ghosts() {
    auto s = timers_.scope("halo");
    CommEngine& e = halo_->engine();
    auto buf = e.packed_send_buffer(6 * sizeof(double));
    local_->pack_halo(reinterpret_cast<double*>(buf.data()), e.packed_space());
    e.begin_packed();
    const auto in = e.finish_packed();
    local_->unpack_halo(reinterpret_cast<const double*>(in.data()), e.packed_space());
  }

  // Fixed bodies do not deform: rank 0 computes their stress once (it is the round-off of
  // F = I, as on one rank) with a host backend over the fixed bodies alone.
  void precompute_fixed_output() {
    fixed_stress_.clear();
    fixed_vm_.clear();
    const Model& g = *g_;
    if (me_ != 0 || g.n_tets() == g.n_free_tets) return;
    LocalLayout L;
    std::vector<Vec3> x, v;
    for (std::int64_t i = g.n_free_vertices; i < g.n_vertices(); ++i) {
      L.vertices.push_back(i);
      x.push_back(g.x[i]);
      v.push_back(g.v[i]);
    }
    for (std::int64_t t = g.n_free_tets; t < g.n_tets(); ++t) L.tets.push_back(t);
    const LocalModel lm = build_local_model(g, ix_, L, x, v, false);
    auto be = make_host_backend();
    be->upload(lm.model);
    const HostFields h = be->download(true);
    fixed_stress_ = h.stress;
    fixed_vm_ = h.von_mises;
  }

  // The error flags the old layout's kernels raised, kept in global ids before a rebuild (its
  // local indices name other items, or none, on the new layout); the next take_inverted_tet /
  // take_deep_contact reports them.
  void hold_flags() {
    hold_inverted();
    hold_deep();
  }
  // The local flag, taken, in global ids beside the held one: the smaller id is kept.
  void hold_inverted() {
    const std::int64_t t = local_->take_inverted_tet();
    if (t < 0) return;
    const std::int64_t g = L_.tets[t];
    if (held_inverted_ < 0 || g < held_inverted_) held_inverted_ = g;
  }
  void hold_deep() {
    std::optional<DeepContact> c = local_->take_deep_contact();
    if (!c) return;
    c->vertex = L_.vertices[c->vertex];
    if (!held_deep_ || c->vertex < held_deep_->vertex) held_deep_ = c;
  }

  // The halo's records stay on the GPUs (CommEngine::use_device).
  bool device_halo() const { return halo_ && halo_->engine().packed_space() == Space::Cuda; }

  // The skin test's reduction when `skin` (contact band: how far a vertex moved since the
  // layout), and x, v of the owned vertices other ranks need packed: what start_halo sends. On
  // a GPU on the side stream, beside the interior tets, which do not wait for them; from
  // `after`, else from the work queued so far.
  void queue_skin_and_pack(PhaseTimers& tm, bool skin, const DeviceMark* after = nullptr) {
    CommEngine& e = halo_->engine();
    auto s = tm.launch("halo");
    auto buf = e.packed_send_buffer(6 * sizeof(double));
    SideQueue side(device_halo(), after);
    if (skin && contact_) {
      auto s1 = tm.launch("halo.skin");
      local_->queue_max_moved();
    }
    auto s1 = tm.launch("halo.xv");
    local_->pack_halo(reinterpret_cast<double*>(buf.data()), e.packed_space());
    e.mark_packed();
  }

  // Starts the exchange of what queue_skin_and_pack packed (given the drift's mark, on a GPU:
  // queues that after the interior tets, from the mark), and queues the interior tets (their
  // vertices are all owned): on a GPU they run while the records are copied (on the copy stream)
  // and unpacked; with the boundary tets queued after the halo, their device time counts in the
  // contact stage's first synchronised phase (contact.broad), as on one process. Records staged
  // through the host are posted before the interior tets, so that the messages travel
  // meanwhile; device-resident ones after, begin_packed waiting for the pack only
  // (mark_packed), so that the wait does not hold the tets back.
  void start_halo(PhaseTimers& tm, double dt_diss, const DeviceMark* drift = nullptr) {
    CommEngine& e = halo_->engine();
    const bool device = device_halo();
    if (!device) {
      auto s = tm.launch("halo");
      auto s1 = tm.launch("halo.xv");
      e.begin_packed();
    }
    {
      auto s = tm.launch("elements");
      local_->element_forces(0, L_.n_interior, dt_diss, true);
    }
    if (device) {
      if (drift) queue_skin_and_pack(tm, true, drift);
      auto s = tm.launch("halo");
      auto s1 = tm.launch("halo.xv");
      e.begin_packed();
    }
  }

  // Rebuilds when some vertex moved `slack` (contact band: the skin test compute_forces
  // queued) or, every rebalance_every steps, when the measured imbalance and the partition
  // model's exceed the threshold and a new cut pays for its rebuild (recut_pays; a threshold of
  // 0 re-cuts at every measurement, as the fluid's); the exchange start_halo began is finished
  // first. True when it rebuilt.
  bool maybe_rebuild(bool dynamic) {
    bool rebuild = false, rebalance = false;
    if (contact_) {
      auto s = timers_.launch("halo");
      auto s1 = timers_.launch("halo.skin");
      const double moved = local_->max_moved();
      double m = 0;
      MPI_Allreduce(&moved, &m, 1, MPI_DOUBLE, MPI_MAX, comm_);
      rebuild = m > slack_;
    }
    if (dynamic && steps_ % opt_.rebalance_every == 0) {
      const Window& w = measure_window();
      rebalance = np_ > 1 && recut_due(w.imbalance, w.modelled, opt_.rebalance_threshold,
                                       w.busiest_step_s, opt_.rebalance_every, w.rebuild_s);
    }
    if (!rebuild && !rebalance) return false;
    // The exchange and the interior tets of the old layout are not used.
    halo_->engine().finish_packed();
    local_->undo_dissipation();
    hold_flags();
    if (rebuild && !rebalance) adapt_slack();
    const double t0 = MPI_Wtime();
    const std::int64_t before = migrated_bytes_;
    const std::map<std::string, double> parts0 = timers_.seconds();
    StateSlice s;
    {
      auto scope = timers_.scope("migration");
      auto s1 = timers_.scope("migration.export");
      s = export_slice(false, relaxing_);
    }
    // A new cut that moves no vertex (timing noise) keeps the rank's model; a moved band
    // always rebuilds the ghosts, from the rank's own export when no vertex changed owner.
    const std::int64_t changed = reassign(s, rebalance);
    if (changed > 0) {
      if (!relaxing_) {
        auto scope = timers_.scope("migration");
        auto s1 = timers_.scope("migration.export");
        complete_slice(s);
      }
      migrate(s);
    } else if (rebuild) {
      install_own(s);
    }
    rebuilt_at_ = MPI_Wtime();
    rebuild_s_ = rebuilt_at_ - t0;
    RebuildEntry& e =
        rebuild_log_.emplace_back(RebuildEntry{steps_, rebalance, slack_, rebuild_s_, changed, {}});
    for (const auto& [k, v] : timers_.seconds())
      if (k == "balance" || k.starts_with("migration."))
        e.parts[k] = v - seconds_of(parts0, k.c_str());
    if (rebalance) {
      ++rebalances_;
      log_.push_back({steps_, last_.imbalance, predicted_after_, migrated_bytes_ - before});
      pending_after_ = true;
    }
    return true;
  }

  // The contact band for a slack (docs/parallel.md item 4): cells of diam + D_DEM + slack, in
  // which the fixed bodies' contact vertices are binned once.
  void set_slack(double slack) {
    const Model& m = *g_;
    slack_ = slack;
    band_ = reach_ + slack;
    fixed_cells_.clear();
    for (std::int64_t i = m.n_free_vertices; i < m.n_vertices(); ++i)
      if (ix_.contact_vertex[i]) fixed_cells_[cell_key(m.X[i])].push_back(i);
  }

  // Before a rebuild the motion asked for: the slack of the next layout (widened_margin, from
  // the largest rebuild and stepping times over the ranks).
  void adapt_slack() {
    double t[2] = {rebuild_s_, MPI_Wtime() - rebuilt_at_};
    MPI_Allreduce(MPI_IN_PLACE, t, 2, MPI_DOUBLE, MPI_MAX, comm_);
    const double most = kMaxMarginGrowth * slack0_;
    const double slack = widened_margin(slack_, most, t[0], t[1], kMaxMarginGrowth);
    if (slack != slack_) set_slack(slack);
  }

  double seconds(const char* phase) const { return seconds_of(timers_.seconds(), phase); }

  // A window's measurement: max / mean - 1 of the ranks' busy time, the busiest rank's busy
  // seconds a step, the largest last rebuild's seconds over the ranks, and max / mean - 1 of
  // the ranks' cost in the partition's model (the items of the current cut at the fitted
  // weights: what a new cut could even out).
  struct Window {
    double imbalance = 0, busiest_step_s = 0, rebuild_s = 0, modelled = 0;
  };

  // Busy time of each rank since the last window: the imbalance, the time per item that
  // weights the cost of the next partition, and the current cut's imbalance at those weights
  // (kept in last_ for the record).
  const Window& measure_window() {
    const double contact = local_contact_seconds();
    const double te = seconds("elements") - contact, ti = seconds("integration");
    const double busy = te + ti + contact;
    double w[8] = {busy - mark_[0],
                   te - mark_[1],
                   ti - mark_[2],
                   contact - mark_[3],
                   static_cast<double>(L_.tets.size()),
                   static_cast<double>(L_.n_owned),
                   static_cast<double>(n_contact_owned_),
                   static_cast<double>(L_.n_home)};
    mark_[0] = busy, mark_[1] = te, mark_[2] = ti, mark_[3] = contact;
    double mx[2] = {w[0], rebuild_s_};
    MPI_Allreduce(MPI_IN_PLACE, mx, 2, MPI_DOUBLE, MPI_MAX, comm_);
    const double home = w[7];
    allreduce_sum_same(comm_, w, 8);
    const double mean = w[0] / np_;
    const double imb = mean > 0 ? mx[0] / mean - 1 : 0.0;
    const std::int64_t n = steps_ - window_start_;
    if (w[4] > 0 && w[1] > 0) w_.tet = w[1] / w[4];
    if (w[5] > 0 && w[2] > 0) w_.vertex = w[2] / w[5];
    if (w[6] > 0 && w[3] > 0) w_.contact = w[3] / w[6];
    // The cut's cost of this rank's items (reassign's), its largest over the ranks, the mean.
    double cost = w_.cost(L_.n_owned, home, n_contact_owned_);
    MPI_Allreduce(MPI_IN_PLACE, &cost, 1, MPI_DOUBLE, MPI_MAX, comm_);
    const double mean_cost = w_.cost(w[5], w[7], w[6]) / np_;
    const double modelled = mean_cost > 0 ? cost / mean_cost - 1 : 0.0;
    if (windows_++ == 0) imbalance_initial_ = imb;
    if (pending_after_) {
      log_.back().imbalance_after = imb;
      pending_after_ = false;
    }
    window_start_ = steps_;
    last_ = {imb, n > 0 ? mx[0] / static_cast<double>(n) : 0.0, mx[1], modelled};
    return last_;
  }

  // body_rank_ from owner_: a body per thread at a time.
  void update_body_ranks() {
    const std::vector<BodyRange>& bodies = g_->bodies;
    const auto nb = static_cast<std::int64_t>(bodies.size());
    body_rank_.assign(nb, -1);
    for_each_coarse(HostExec{}, nb, [&](std::int64_t b) {
      const BodyRange& r = bodies[b];
      if (r.fixed || r.v_end == r.v_begin) return;
      const std::int32_t o = owner_[r.v_begin];
      for (std::int64_t i = r.v_begin + 1; i < r.v_end; ++i)
        if (owner_[i] != o) return;
      body_rank_[b] = o;
    });
  }

  // The owners of the free vertices in `s` (any distribution over the ranks). rebalance: a new
  // partition from the measured costs first; otherwise the current partition's at the current
  // positions (a curve key each, in parallel). Every rank learns the changes (owner_ covers all
  // free vertices). The number of free vertices that changed owner (all ranks).
  std::int64_t reassign(const StateSlice& s, bool rebalance) {
    const std::int64_t nsv = static_cast<std::int64_t>(s.vertex.size());
    if (rebalance || dec_.splitters.empty()) {
      auto scope = timers_.scope("balance");
      std::vector<double> cost(nsv);
      for (std::int64_t k = 0; k < nsv; ++k) {
        const std::int64_t gv = s.vertex[k];
        cost[k] = w_.cost(1, ix_.tets_at[gv], ix_.contact_vertex[gv]);
      }
      dec_ = balance(comm_, s.x, cost, curve_, opt_.max_cell_cost);
      predicted_after_ = dec_.predicted_imbalance;
    }
    auto scope = timers_.scope("migration");
    auto s1 = timers_.scope("migration.state");
    std::vector<int> dest(nsv);
    for_each(HostExec{}, nsv, [&](std::int64_t k) { dest[k] = dec_.owner(s.x[k]); });
    const std::vector<std::int64_t> moved = select_indices(
        HostExec{}, nsv, [&](std::int64_t k) { return owner_[s.vertex[k]] != dest[k]; });
    std::vector<std::pair<std::int64_t, std::int64_t>> changed(moved.size());
    for_each(HostExec{}, static_cast<std::int64_t>(moved.size()), [&](std::int64_t j) {
      changed[j] = {s.vertex[moved[j]], dest[moved[j]]};
    });
    std::int64_t bytes = 0;
    const auto all_changed = allgatherv(comm_, changed, &bytes);
    migrated_bytes_ += bytes;
    for (const auto& [gv, r] : all_changed) owner_[gv] = static_cast<std::int32_t>(r);
    if (!all_changed.empty()) update_body_ranks();
    return static_cast<std::int64_t>(all_changed.size());
  }

  // A layout rebuild in which no vertex changed owner: every vertex, tet and history entry
  // stays on its rank, and the held tets are the last layout's (they follow from the owners
  // alone). The device keeps the owned state and the tets' dissipation; while relaxing the
  // rank's own whole export (export_slice) is its part, with its halo tets added (their
  // dissipation is counted by their home ranks; here it starts again from zero).
  void install_own(StateSlice& s) {
    auto scope = timers_.scope("migration");
    if (relaxing_) {
      s.tet.insert(s.tet.end(), L_.tets.begin() + L_.n_home, L_.tets.end());
      s.diss_t.resize(L_.tets.size(), 0.0);
    }
    install(s, true);
  }

  // Moves the state in `s` (any distribution over the ranks) to the owners reassign gave and
  // installs the rank's new part.
  void migrate(const StateSlice& s) {
    const std::int64_t nsv = static_cast<std::int64_t>(s.vertex.size());
    auto scope = timers_.scope("migration");
    std::optional<PhaseTimers::Scope> part;
    part.emplace(timers_, "migration.state");
    std::int64_t bytes = 0;
    std::vector<int> dest(nsv);
    for_each(HostExec{}, nsv, [&](std::int64_t k) { dest[k] = owner_[s.vertex[k]]; });

    // Vertices: id, x, v, dissipation (and the force of the last evaluation when the slice has
    // it, the relaxation start state while relaxing; a rank without them sends zeros). The plans
    // of the three migrations stand from one rebuild to the next (replanned: no new communicator
    // or message buffers, page-locked on a GPU rank).
    const int has[2] = {!s.f.empty(), !s.x0.empty()};
    int any[2] = {0, 0};
    MPI_Allreduce(has, any, 2, MPI_INT, MPI_MAX, comm_);
    const bool any_f = any[0], any_relax = any[1];
    // What arrives (arrived_, then mine_ in gid order) goes into arrays kept from one rebuild
    // to the next, as the tets' lists below: resized without zeroing or copying (a fresh array
    // is zeroed on one thread), written on the threads.
    auto fit = [](std::int64_t n, auto&... a) {
      (resize_for_overwrite(a, static_cast<std::size_t>(n)), ...);
    };
    MigratePlan& mv = replanned(vertex_plan_, dest);
    const std::int64_t nn = mv.n_new();
    StateSlice& in = arrived_;
    fit(nn, in.vertex, in.x, in.v, in.diss_v);
    std::vector<CommField> src{cfield(s.vertex), cfield(s.x), cfield(s.v), cfield(s.diss_v)},
        dst{cfield(in.vertex), cfield(in.x), cfield(in.v), cfield(in.diss_v)};
    std::vector<Vec3> zeros;  // made only when some field is missing here
    auto optional_field = [&](bool any_rank, const std::vector<Vec3>& from, std::vector<Vec3>& to) {
      to.clear();
      if (!any_rank) return;
      fit(nn, to);
      if (from.empty()) zeros.resize(nsv);
      src.push_back(cfield(from.empty() ? zeros : from));
      dst.push_back(cfield(to));
    };
    optional_field(any_f, s.f, in.f);
    optional_field(any_relax, s.x0, in.x0);
    optional_field(any_relax, s.f0, in.f0);
    mv.move(src, dst);
    bytes += mv.engine().last_bytes();

    // Tets: from their holder to every new owner of one of their vertices (each tet's ranks
    // without repeats, in any order; counted, then written, in parallel).
    const std::int64_t nst = static_cast<std::int64_t>(s.tet.size());
    auto tet_ranks = [&](std::int64_t k, int* r) {
      const auto& tv = g_->tets[s.tet[k]];
      std::int64_t n = 0;
      for (int q = 0; q < 4; ++q) {
        const int o = owner_[tv[q]];
        bool seen = false;
        for (std::int64_t j = 0; j < n; ++j) seen = seen || r[j] == o;
        if (!seen) r[n++] = o;
      }
      return n;
    };
    std::vector<std::int64_t>& toff = tet_off_;
    fit(nst + 1, toff);
    toff[0] = 0;
    for_each(HostExec{}, nst, [&](std::int64_t k) {
      int r[4];
      toff[k + 1] = tet_ranks(k, r);
    });
    std::partial_sum(toff.begin(), toff.end(), toff.begin());
    std::vector<int>& tranks = tet_ranks_;
    fit(toff[nst], tranks);
    for_each(HostExec{}, nst, [&](std::int64_t k) {
      int r[4];
      const std::int64_t n = tet_ranks(k, r);
      std::copy(r, r + n, tranks.begin() + toff[k]);
    });
    if (tet_plan_)
      tet_plan_->replan(toff, tranks, 0);
    else
      tet_plan_ = std::make_unique<CommEngine>(comm_, toff, tranks, 0);
    CommEngine& te = *tet_plan_;
    StateSlice& mine = mine_;  // the tets as they come
    fit(te.n_recv(), mine.tet, mine.diss_t);
    {
      const CommField a[2] = {cfield(s.tet), cfield(s.diss_t)},
                      b[2] = {cfield(mine.tet), cfield(mine.diss_t)};
      te.forward(a, b);
      bytes += te.last_bytes();
    }

    // Contact history: to the new owner of the entry's anchor vertex, which evaluates it.
    const ContactState& sh = s.contact;
    const std::int64_t nsh = static_cast<std::int64_t>(sh.size());
    std::vector<int> hdest(nsh);
    std::atomic<bool> unanchored{false};
    for_each(HostExec{}, nsh, [&](std::int64_t k) {
      const int a = anchor_slot(static_cast<int>(sh.k1[k] >> 60), sh.v[k].data(),
                                GlobalVertices{owner_, g_->body, body_rank_});
      if (a < 0) unanchored.store(true, std::memory_order_relaxed);
      hdest[k] = a < 0 ? me_ : owner_[sh.v[k][a]];
    });
    if (unanchored) throw std::logic_error("contact history entry without a free vertex");
    MigratePlan& he = replanned(history_plan_, hdest);
    ContactState& hist = mine.contact;
    hist.resize(he.n_new());
    hist.dissipated = sh.dissipated;  // the rank's share stays with the rank
    {
      const CommField a[10] = {cfield(sh.k1), cfield(sh.k2),     cfield(sh.active),   cfield(sh.xi),
                               cfield(sh.h),  cfield(sh.energy), cfield(sh.energy_t), cfield(sh.v),
                               cfield(sh.w),  cfield(sh.n1)},
                      b[10] = {cfield(hist.k1),       cfield(hist.k2), cfield(hist.active),
                               cfield(hist.xi),       cfield(hist.h),  cfield(hist.energy),
                               cfield(hist.energy_t), cfield(hist.v),  cfield(hist.w),
                               cfield(hist.n1)};
      he.move(a, b);
      bytes += he.engine().last_bytes();
    }
    migrated_bytes_ += bytes;

    // The new owned vertices in gid order, so a rank's layout depends only on what it owns
    // (sorted and gathered in parallel).
    const std::vector<std::int64_t> perm = sorted_order(in.vertex);
    gather_into(mine.vertex, in.vertex, perm);
    gather_into(mine.x, in.x, perm);
    gather_into(mine.v, in.v, perm);
    gather_into(mine.diss_v, in.diss_v, perm);
    auto optional_gather = [&](const std::vector<Vec3>& from, std::vector<Vec3>& to) {
      if (from.empty())
        to.clear();
      else
        gather_into(to, from, perm);
    };
    optional_gather(in.f, mine.f);
    optional_gather(in.x0, mine.x0);
    optional_gather(in.f0, mine.f0);
    part.reset();
    install(mine);
  }

  // `plan` planned for `dest` (made at the first migration, replanned after).
  MigratePlan& replanned(std::unique_ptr<MigratePlan>& plan, std::span<const int> dest) {
    if (plan)
      plan->replan(dest);
    else
      plan = std::make_unique<MigratePlan>(comm_, dest);
    return *plan;
  }

  // Held tets: every free tet with an owned vertex (the owned vertices are those owner_
  // gives this rank), in id order; interior, boundary home, halo. A body one rank owns whole
  // (body_rank_) gives all its tets to that rank as interior tets and none to the others, so
  // the candidates are the tets of this rank's whole bodies and of split bodies (body by
  // body: body_items, in id order), not the global model's. Each candidate's class is decided
  // in parallel, then the candidates are bucketed by class (in parallel too).
  void held_tets(LocalLayout& L) const {
    const Model& g = *g_;
    std::vector<std::uint8_t> mine(g.bodies.size());
    for (std::size_t b = 0; b < mine.size(); ++b)
      mine[b] = !g.bodies[b].fixed && (body_rank_[b] < 0 || body_rank_[b] == me_);
    const std::vector<std::int64_t> cand = body_items(ix_.body_tet_off, mine);
    const auto nc = static_cast<std::int64_t>(cand.size());
    std::vector<std::uint8_t> cls(nc);
    enum : std::uint8_t { kInterior, kBoundary, kHalo, kNotHeld };
    for_each(HostExec{}, nc, [&](std::int64_t j) {
      const auto& tv = g.tets[cand[j]];
      if (body_rank_[g.body[tv[0]]] == me_) {
        cls[j] = kInterior;
        return;
      }
      int owned = 0;
      for (int q = 0; q < 4; ++q) owned += owner_[tv[q]] == me_;
      cls[j] = owned == 4                                               ? kInterior
               : owner_[*std::min_element(tv.begin(), tv.end())] == me_ ? kBoundary
               : owned > 0                                              ? kHalo
                                                                        : kNotHeld;
    });
    Buckets held = bucket_indices(HostExec{}, nc, kNotHeld, [&](std::int64_t j) { return cls[j]; });
    resize_for_overwrite(L.tets, held.index.size());
    for_each(HostExec{}, static_cast<std::int64_t>(held.index.size()),
             [&](std::int64_t k) { L.tets[k] = cand[held.index[k]]; });
    L.n_interior = held.start[kBoundary];
    L.n_home = held.start[kHalo];
  }

  // The relaxation start state of the owned vertices and each held tet's dissipation from the
  // slice `s` into `st`, for the layout L (nv vertices). A tet's slot in the slice is found by
  // gid in tet_slot_ (its entries of tets the slice lacks are stale, so a hit is checked).
  void state_from_slice(const StateSlice& s, const LocalLayout& L, BackendState& st) {
    const std::int64_t nv = static_cast<std::int64_t>(L.vertices.size()), no = L.n_owned;
    st.x0.clear();
    st.f0.clear();
    if (!s.x0.empty()) {
      resize_for_overwrite(st.x0, nv);
      resize_for_overwrite(st.f0, nv);
      for_each(HostExec{}, nv, [&](std::int64_t i) {
        st.x0[i] = i < no ? s.x0[i] : Vec3{};
        st.f0[i] = i < no ? s.f0[i] : Vec3{};
      });
    }
    const auto nst = static_cast<std::int64_t>(s.tet.size());
    tet_slot_.resize(g_->n_free_tets);
    for_each(HostExec{}, nst,
             [&](std::int64_t k) { tet_slot_[s.tet[k]] = static_cast<std::int32_t>(k); });
    resize_for_overwrite(st.diss_t, L.tets.size());
    std::atomic<std::int64_t> missing{-1};  // a held tet whose state did not arrive
    for_each(HostExec{}, static_cast<std::int64_t>(L.tets.size()), [&](std::int64_t j) {
      const std::int64_t k = tet_slot_[L.tets[j]];
      if (k < nst && s.tet[k] == L.tets[j])
        st.diss_t[j] = s.diss_t[k];
      else
        missing.store(L.tets[j], std::memory_order_relaxed);
    });
    if (missing >= 0)
      throw std::logic_error("distributed install: no state arrived for tet " +
                             std::to_string(missing));
  }

  // Builds the rank's part from its owned state (vertices in gid order, the state of every
  // tet it will hold in any order, its contact history) and uploads it; the backend's and the
  // halo plan's arrays take room from their first allocation (BufferRoom).
  void install(const StateSlice& s, bool same_owners = false) {
    drift_marked_ = false;
    const BufferRoom room;
    std::optional<PhaseTimers::Scope> part;
    part.emplace(timers_, "migration.layout");
    std::optional<PhaseTimers::Scope> sub;  // the layout's and the upload's parts
    auto phase = [&](const char* name) {
      sub.reset();
      if (name) sub.emplace(timers_, name);
    };
    phase("migration.layout.tets");
    const Model& g = *g_;
    LocalLayout L;
    L.vertices = s.vertex;
    L.n_owned = static_cast<std::int64_t>(s.vertex.size());
    // With the owners of the last layout (same_owners), its held tets stand: they follow from
    // the owners alone.
    if (same_owners) {
      L.tets.swap(L_.tets);
      L.n_interior = L_.n_interior;
      L.n_home = L_.n_home;
    } else {
      held_tets(L);
    }
    L.body_whole.resize(body_rank_.size());
    for (std::size_t b = 0; b < body_rank_.size(); ++b)
      L.body_whole[b] = body_rank_[b] < 0      ? kSplit
                        : body_rank_[b] == me_ ? kWholeHere
                                               : kWholeElsewhere;
    phase("migration.layout.band");

    // Contact band: the cells holding this rank's owned contact vertices, published to all;
    // each vertex's cell and the distinct cells in key order found on the threads (a key per
    // vertex, a radix sort).
    std::unordered_map<std::uint64_t, std::vector<int>> occupied;  // cell -> other ranks
    std::vector<std::uint64_t> my_cells;
    std::vector<std::int64_t> contacts;                         // owned contact vertices
    std::vector<std::pair<std::uint64_t, std::int64_t>> keyed;  // (cell, entry of contacts)
    if (contact_) {
      contacts = select_indices(HostExec{}, L.n_owned, [&](std::int64_t i) {
        return ix_.contact_vertex[s.vertex[i]] != 0;
      });
      const auto nc = static_cast<std::int64_t>(contacts.size());
      keyed.resize(nc);
      for_each(HostExec{}, nc, [&](std::int64_t j) { keyed[j] = {cell_key(s.x[contacts[j]]), j}; });
      std::vector<std::pair<std::uint64_t, std::int64_t>> scratch;
      radix_sort(keyed, scratch);
      const std::vector<std::int64_t> first = select_indices(HostExec{}, nc, [&](std::int64_t p) {
        return p == 0 || keyed[p].first != keyed[p - 1].first;
      });
      my_cells.resize(first.size());
      for_each(HostExec{}, static_cast<std::int64_t>(first.size()),
               [&](std::int64_t q) { my_cells[q] = keyed[first[q]].first; });
      std::vector<std::pair<std::uint64_t, std::int64_t>> mine(my_cells.size());
      for (std::size_t q = 0; q < my_cells.size(); ++q) mine[q] = {my_cells[q], me_};
      for (const auto& [c, r] : allgatherv(comm_, mine))
        if (r != me_) occupied[c].push_back(static_cast<int>(r));
    }
    n_contact_owned_ = static_cast<std::int64_t>(contacts.size());
    // The ranks with owned contact vertices within the band of each of these cells (other
    // ranks' cells among its 5^3), sorted without repeats, a cell per thread at a time.
    std::vector<std::vector<int>> near(my_cells.size());
    for_each(HostExec{}, static_cast<std::int64_t>(my_cells.size()), [&](std::int64_t q) {
      std::vector<int>& r = near[q];  // allocates only beside another rank's cells
      for_each_band_neighbour(band_cell_of_key(my_cells[q]), [&](std::uint64_t k) {
        const auto o = occupied.find(k);
        if (o != occupied.end()) r.insert(r.end(), o->second.begin(), o->second.end());
      });
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
    });

    phase("migration.layout.halo");
    // Halo: an owned vertex goes to the owners of its tets' other vertices (they hold those
    // tets) and, for contact vertices, to the ranks with owned contact vertices in the band.
    // Each vertex's list is sorted, without this rank and repeats (what HaloPlan keeps),
    // counted then written in parallel; the band's lists come first (per cell).
    std::vector<const std::vector<int>*> band(L.n_owned, nullptr);
    for_each(HostExec{}, static_cast<std::int64_t>(keyed.size()), [&](std::int64_t p) {
      const auto q = std::lower_bound(my_cells.begin(), my_cells.end(), keyed[p].first);
      band[contacts[keyed[p].second]] = &near[q - my_cells.begin()];
    });
    auto other_ranks = [&](std::int64_t i, std::vector<int>& r) {
      const std::int64_t gv = s.vertex[i];
      if (body_rank_[g.body[gv]] != me_)  // else all its tets' vertices are this rank's
        for (std::int64_t q = ix_.corner_off[4 * gv]; q < ix_.corner_off[4 * gv + 4]; ++q)
          for (auto u : g.tets[ix_.corner_tet[q]])
            if (owner_[u] != me_) r.push_back(owner_[u]);
      if (band[i]) r.insert(r.end(), band[i]->begin(), band[i]->end());
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
    };
    std::vector<std::int64_t> off(L.n_owned + 1, 0);
    for_each(HostExec{}, L.n_owned, [&](std::int64_t i) {
      std::vector<int> r;  // allocates only on a border vertex
      other_ranks(i, r);
      off[i + 1] = static_cast<std::int64_t>(r.size());
    });
    std::partial_sum(off.begin(), off.end(), off.begin());
    std::vector<int> ranks(off[L.n_owned]);
    for_each(HostExec{}, L.n_owned, [&](std::int64_t i) {
      std::vector<int> r;
      other_ranks(i, r);
      std::copy(r.begin(), r.end(), ranks.begin() + off[i]);
    });
    const std::vector<std::uint64_t> gids(s.vertex.begin(), s.vertex.end());
    const bool first_halo = !halo_;  // later layouts plan again on its engine (buffers kept)
    if (first_halo)
      halo_ = std::make_unique<HaloPlan>(comm_, L.n_owned, off, ranks, gids);
    else
      halo_->replan(L.n_owned, off, ranks, gids);
    for (auto gv : halo_->ghost_gids()) L.vertices.push_back(static_cast<std::int64_t>(gv));
    L.n_free = static_cast<std::int64_t>(L.vertices.size());
    // Fixed bodies' contact vertices in the band, from the model.
    if (contact_) {
      std::vector<std::int64_t> fixed;
      for (auto c : my_cells) {
        const BandCell bc{
            {static_cast<std::int64_t>(c >> 42) - (std::int64_t{1} << 20),
             static_cast<std::int64_t>((c >> 21) & 0x1fffff) - (std::int64_t{1} << 20),
             static_cast<std::int64_t>(c & 0x1fffff) - (std::int64_t{1} << 20)}};
        for_each_band_neighbour(bc, [&](std::uint64_t k) {
          const auto f = fixed_cells_.find(k);
          if (f != fixed_cells_.end())
            fixed.insert(fixed.end(), f->second.begin(), f->second.end());
        });
      }
      std::sort(fixed.begin(), fixed.end());
      fixed.erase(std::unique(fixed.begin(), fixed.end()), fixed.end());
      L.vertices.insert(L.vertices.end(), fixed.begin(), fixed.end());
    }

    // The same owned vertices and held tets as the last layout (a rebuild of the ghosts that
    // moved no vertex): the tets' reference data stay in the model and on the device. When
    // `s` is the rank's own export (same_owners) and not relaxing, the owned vertices' state
    // and the tets' dissipation stay on the device too (keep_owned): `s` has their x alone.
    const bool same_tets =
        same_owners ||
        (rebuilds_ > 0 && L.n_owned == L_.n_owned && L.tets == L_.tets &&
         std::equal(L.vertices.begin(), L.vertices.begin() + L.n_owned, L_.vertices.begin()));
    const bool keep_owned = same_owners && !relaxing_;
    // The state the backend gets (kept: a rebuild writes it in place, on the threads), with
    // the positions and velocities the model is built from: owned from the slice, ghosts from
    // their owners, fixed bodies' from the model.
    const std::int64_t nv = static_cast<std::int64_t>(L.vertices.size());
    const std::int64_t no = L.n_owned, nf = L.n_free, nsf = static_cast<std::int64_t>(s.f.size());
    BackendState& st = installed_;
    for (auto* a : {&st.x, &st.v}) resize_for_overwrite(*a, nv);
    if (!keep_owned) {
      resize_for_overwrite(st.f, nv);
      resize_for_overwrite(st.diss_v, nv);
    }
    for_each(HostExec{}, nv, [&](std::int64_t i) {
      const bool fixed = i >= nf;
      if (i < no || fixed) {
        st.x[i] = fixed ? g.x[L.vertices[i]] : s.x[i];
        if (fixed || !keep_owned) st.v[i] = fixed ? g.v[L.vertices[i]] : s.v[i];
      }
      if (keep_owned) return;  // nor the owned vertices' v: upload_same_tets keeps theirs
      // A rebuild's slice has no forces: compute_forces evaluates them next.
      st.f[i] = i < nsf ? s.f[i] : Vec3{};
      st.diss_v[i] = i < no ? s.diss_v[i] : 0.0;
    });
    {
      const CommField f[2] = {comm_field(st.x), comm_field(st.v)};
      halo_->gather_begin(f);
      halo_->gather_finish(f);
    }
    phase("migration.layout.model");
    build_local_model(g, ix_, L, st.x, st.v, lm_, true, same_tets);
    phase(nullptr);
    part.reset();
    part.emplace(timers_, "migration.upload");

    // Keep the old contact stage's counters, then replace the rank's model.
    for (const auto& [k, sec] : local_->stage_seconds()) contact_acc_[k] += sec;
    if (contact_ && rebuilds_ > 0) {
      std::map<std::string, double> c = local_->contact_stats();
      overlap_acc_ = std::max(overlap_acc_, c["max_overlap_ever"]);
      rebuilds_acc_ += c["pair_rebuilds"];
    }
    phase("migration.upload.model");
    if (same_tets)
      local_->upload_same_tets(lm_.model, L.n_interior);
    else
      local_->upload(lm_.model);
    phase("migration.upload.state");
    local_->use_preload(preload_);
    if (!keep_owned) state_from_slice(s, L, st);
    // Contact history in this rank's feature ids and vertex indices, sorted by key (no
    // pair-list reference: the list is built for this layout at the next step).
    if (contact_) {
      const ContactState& sc = s.contact;
      const auto nsc = static_cast<std::int64_t>(sc.size());
      std::vector<std::pair<std::uint64_t, std::uint64_t>> lk(nsc);
      for_each(HostExec{}, nsc, [&](std::int64_t e) {
        lk[e] = {lm_.ids.k1_to_local(sc.k1[e]), FeatureIds::kNone};
        if (lk[e].first != FeatureIds::kNone)
          lk[e].second = lm_.ids.k2_to_local(sc.k1[e], sc.k2[e]);
      });
      std::vector<std::int64_t> hidx = select_indices(HostExec{}, nsc, [&](std::int64_t e) {
        return lk[e].first != FeatureIds::kNone && lk[e].second != FeatureIds::kNone;
      });
      std::sort(hidx.begin(), hidx.end(), [&](auto a, auto b) { return lk[a] < lk[b]; });
      hidx.erase(
          std::unique(hidx.begin(), hidx.end(), [&](auto a, auto b) { return lk[a] == lk[b]; }),
          hidx.end());
      ContactState& c = st.contact.emplace();
      c.dissipated = s.contact.dissipated;
      c.resize(hidx.size());
      for_each(HostExec{}, static_cast<std::int64_t>(hidx.size()), [&](std::int64_t j) {
        const std::int64_t e = hidx[j];
        c.set(j, sc, e);
        c.k1[j] = lk[e].first;
        c.k2[j] = lk[e].second;
        for (int q = 0; q < 4; ++q)
          if (sc.v[e][q] >= 0) c.v[j][q] = lm_.ids.local_vertex(sc.v[e][q]);
      });
    }
    if (!keep_owned)
      local_->load_state(st);
    else if (contact_)
      local_->load_history(*st.contact);
    phase("migration.upload.routes");
    if (first_halo) halo_->engine().use_device(local_->space() == Space::Cuda, 6 * sizeof(double));
    local_->set_halo(halo_->engine().send_index(), L.n_owned, halo_->n_ghost());
    if (contact_) local_->set_share_routes(share_routes(L, lm_.ids));
    local_->mark_positions();
    L_ = std::move(L);
    std::swap(ids_, lm_.ids);  // the old ids' storage serves the next rebuild
    if (coupled_) install_coupling();
    ++rebuilds_;
  }

  // The local backend's coupling views (a new upload drops them), with the fluid force of the
  // owned coupled vertices.
  void install_coupling() {
    local_sv_ = local_->solid_views();
    if (is_coupled_.empty()) return;  // nothing coupled yet: fc is zero
    index_coupled();
    const std::int64_t n = static_cast<std::int64_t>(own_gid_h_.size());
    const Vec3View fc = cfc_.view();
    copy_coupled(local_sv_.fc.x, fc.x, n, 8, false);
    copy_coupled(local_sv_.fc.y, fc.y, n, 8, false);
    copy_coupled(local_sv_.fc.z, fc.z, n, 8, false);
  }

  // The owned coupled vertices of the layout: local and global ids.
  void index_coupled() {
    std::vector<std::int64_t> loc;
    own_gid_h_.clear();
    for (std::int64_t i = 0; i < L_.n_owned; ++i)
      if (is_coupled_[L_.vertices[i]]) loc.push_back(i), own_gid_h_.push_back(L_.vertices[i]);
    own_local_ = Buffer<std::int64_t>(cspace_);
    own_gid_ = Buffer<std::int64_t>(cspace_);
    own_local_.assign(loc);
    own_gid_.assign(own_gid_h_);
  }

  // One field of the n owned coupled vertices between the whole-model array (by global id)
  // and the local one (by local id), through the staging buffer: to_whole, local -> whole.
  void copy_coupled(void* dst, const void* src, std::int64_t n, std::size_t elem, bool to_whole) {
    void* st = stage_.view().p;
    const std::int64_t* from = (to_whole ? own_local_ : own_gid_).cview().p;
    const std::int64_t* to = (to_whole ? own_gid_ : own_local_).cview().p;
    space_gather(cspace_, st, src, from, n, elem);
    space_scatter(cspace_, dst, to, st, n, elem);
  }

  MPI_Comm comm_ = MPI_COMM_NULL;
  int me_ = 0, np_ = 1;
  std::unique_ptr<Backend> local_;
  ParallelOptions opt_;
  Curve curve_;
  const Model* g_ = nullptr;
  ModelIndex ix_;
  std::vector<std::int32_t> owner_;  // per global vertex: owner rank (-1: fixed body)
  // Per body: the rank owning all its free vertices, -1 when the cut divides it or it is fixed
  // (a whole body's faces may lead its contacts, contact_record.hpp face_leads).
  std::vector<std::int32_t> body_rank_;
  Decomposition dec_;
  LocalLayout L_;
  FeatureIds ids_;
  LocalModel lm_;  // the last layout's model, its storage reused by the next (install)
  std::vector<std::int32_t> tet_slot_;  // per free tet: its slot in install's slice (or stale)
  BackendState installed_;              // the state install hands the backend (storage kept)
  // migrate's work arrays: the migrated state as it came and in gid order, and each tet's
  // destination ranks (CSR).
  StateSlice arrived_, mine_;
  std::vector<std::int64_t> tet_off_;
  std::vector<int> tet_ranks_;
  std::unique_ptr<HaloPlan> halo_;
  // The rebuilds' migrations of vertices, tets and contact history (migrate).
  std::unique_ptr<MigratePlan> vertex_plan_, history_plan_;
  std::unique_ptr<CommEngine> tet_plan_;
  bool contact_ = false, preload_ = false, relaxing_ = false;
  // The drift's end is marked for the next force evaluation (drift on a GPU: its skin test and
  // the halo's packing start there); a new layout (install) drops it.
  bool drift_marked_ = false;
  DeviceMark drifted_;
  double band_ = 1, slack_ = 0;
  double reach_ = 0, slack0_ = 0;          // diam + D_DEM; the first slack (set_slack)
  double rebuild_s_ = 0, rebuilt_at_ = 0;  // the last rebuild's seconds, its end (MPI_Wtime)
  std::unordered_map<std::uint64_t, std::vector<std::int64_t>> fixed_cells_;
  std::int64_t n_contact_owned_ = 0;
  std::vector<std::array<double, 6>> fixed_stress_;
  std::vector<double> fixed_vm_;
  std::int64_t held_inverted_ = -1;  // flags of a replaced layout, global ids (hold_flags)
  std::optional<DeepContact> held_deep_;
  // Records.
  PhaseTimers timers_;
  double setup_balance_s_ = 0, setup_migration_s_ = 0;  // of the first distribution (adopt)
  std::map<std::string, double> contact_acc_;
  double overlap_acc_ = 0, rebuilds_acc_ = 0;
  Weights w_;
  double mark_[4] = {0, 0, 0, 0};
  std::int64_t steps_ = 0, window_start_ = 0, windows_ = 0, rebuilds_ = 0, rebalances_ = 0;
  double imbalance_initial_ = 0, predicted_after_ = 0;
  Window last_;  // the last window's measurement
  bool pending_after_ = false;
  std::vector<RebalanceEntry> log_;
  std::vector<RebuildEntry> rebuild_log_;
  std::int64_t migrated_bytes_ = 0, halo_bytes_ = 0, exchanges_ = 0;
  std::vector<ContactShare> shares_out_;  // send_shares' records, by destination, in flight
  // Fluid coupling: whole-model arrays by global vertex id (solid_views()), in the local
  // backend's space, and what moves values between them and the local arrays.
  bool coupled_ = false;
  Space cspace_ = Space::Host;
  SolidViews local_sv_;                   // the local backend's, local ids
  std::vector<std::uint8_t> is_coupled_;  // per global vertex: carries fluid markers
  Vec3Buffer cx_, cv_, cf_, cfc_;
  Buffer<double> cinv_;
  Buffer<std::uint8_t> cheld_;
  std::vector<std::int64_t> own_gid_h_;       // the owned coupled vertices' global ids
  Buffer<std::int64_t> own_local_, own_gid_;  // ... their local and global ids (cspace_)
  Buffer<std::int64_t> all_gid_;              // every coupled vertex
  Buffer<double> zeros_, stage_;              // staging: 6 doubles per coupled vertex
  Buffer<std::int64_t> stage_idx_;
};

}  // namespace

std::unique_ptr<DistributedBackend> make_distributed_backend(MPI_Comm comm,
                                                             std::unique_ptr<Backend> local,
                                                             const ParallelOptions& options) {
  return std::make_unique<DistributedImpl>(comm, std::move(local), options);
}

std::unique_ptr<DistributedBackend> make_distributed_backend(std::unique_ptr<Backend> local,
                                                             const ParallelOptions& options) {
  return make_distributed_backend(MPI_COMM_WORLD, std::move(local), options);
}

}  // namespace qdemsph
