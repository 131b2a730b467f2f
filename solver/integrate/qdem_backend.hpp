// QDEM stages written once over an execution space (HostExec or CudaExec): the launch
// layer (for_each / reduce_*) decides where the loops run. Instantiated in
// backend_host.cpp and backend_cuda.cu.
//
// Data layout (SoA, n = count): vertex fields are Vec3 buffers (x, y, z arrays); tet
// connectivity tv[k * nt + t]; dX^-1 entries dxi[(3 r + c) * nt + t]; per-tet corner forces
// tf[k * nt + t], stored as whole Vec3s (AoS): the gather reads one 24-byte record per
// corner instead of three scattered doubles. Forces reach vertices by a gather over a
// vertex->corner CSR list rather than atomics, so the sum order is fixed: results are
// deterministic on every backend.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "contact/contact_stage.hpp"
#include "core/error.hpp"
#include "core/error_flag.hpp"
#include "core/exec_host.hpp"
#include "core/memory.hpp"
#include "integrate/backend.hpp"
#include "physics/element.hpp"

namespace qdemsph {

template <class Exec>
class QdemBackend final : public Backend {
  static constexpr Space S = Exec::space;

 public:
  explicit QdemBackend(std::string name) : name_(std::move(name)) {}
  std::string name() const override { return name_; }

  void upload(const Model& m) override { upload_model(m, -1); }
  void upload_same_tets(const Model& m, std::int64_t kept_tets) override {
    upload_model(m, kept_tets);
  }
  void load_history(const ContactState& history) override {
    if (contact_) contact_->load_state(history);
  }

  // Vertex -> (corner k, tet t) lists of the gathered vertices [0, nfv), entries k * nt + t,
  // ordered by (k, global tet id): on one rank that is increasing order; a rank of a distributed
  // run sums the corners of its vertices in the same order, so forces agree with one rank bit for
  // bit. The model's own lists when it has them (a distributed rank's part, Model::corner_off),
  // else built here in parallel: counted and filled through atomic cursors (in any order), then
  // each vertex's entries sorted (unique keys: the lists do not depend on the threads). (A model
  // without tet ids, e.g. a benchmark's, is numbered by index.)
  void upload_corner_lists(const Model& m) {
    const std::int64_t nv = nfv_, nt = nt_, nft = nft_;
    if (!m.corner_off.empty()) {
      if (static_cast<std::int64_t>(m.corner_off.size()) != nv + 1 ||
          static_cast<std::int64_t>(m.corner_ent.size()) != m.corner_off.back())
        throw std::logic_error("model corner lists do not fit its free vertices");
      assign_on_threads(csr_off_, m.corner_off, stage_);
      assign_on_threads(csr_ent_, m.corner_ent, stage_);
      return;
    }
    std::vector<std::int64_t>& off = csr_off_h_;
    off.assign(nv + 1, 0);
    auto next = [](std::int64_t& c) {
      return std::atomic_ref<std::int64_t>(c).fetch_add(1, std::memory_order_relaxed);
    };
    for_each(HostExec{}, nft, [&](std::int64_t t) {
      for (int k = 0; k < 4; ++k)
        if (m.tets[t][k] < nv) next(off[m.tets[t][k] + 1]);
    });
    std::partial_sum(off.begin(), off.end(), off.begin());
    const bool gids = static_cast<std::int64_t>(m.tet_gid.size()) == nt;
    auto before = [&](std::int64_t a, std::int64_t b) {
      if (a / nt != b / nt || !gids) return a < b;
      return m.tet_gid[a % nt] < m.tet_gid[b % nt];
    };
    write_on_host(csr_ent_, off[nv], stage_, [&](std::int64_t* ent) {
      std::vector<std::int64_t> cur(off.begin(), off.end() - 1);
      for (int k = 0; k < 4; ++k)  // corner by corner: the lists come nearly sorted
        for_each(HostExec{}, nft, [&](std::int64_t t) {
          if (m.tets[t][k] < nv) ent[next(cur[m.tets[t][k]])] = k * nt + t;
        });
      for_each(HostExec{}, nv,
               [&](std::int64_t i) { std::sort(ent + off[i], ent + off[i + 1], before); });
    });
    csr_off_.assign(off);
  }

  void use_preload(bool on) override { preload_ = on; }

  void compute_forces(double dt_diss, double alpha) override {
    element_forces(0, nft_, dt_diss, false);
    assemble_forces(dt_diss, alpha);
    add_contact_forces({});
  }

  void element_forces(std::int64_t t0, std::int64_t t1, double dt_diss, bool undoable) override {
    const bool keep = undoable && dt_diss > 0;
    undo_ = keep ? std::pair{t0, t1} : std::pair<std::int64_t, std::int64_t>{0, 0};
    if (keep && diss_undo_.size() < nt_) diss_undo_.resize(nt_);
    const auto undo = diss_undo_.view();
    const std::int64_t nt = nt_;
    const auto x = x_.cview(), v = v_.cview();
    const auto tv = tv_.cview();
    const auto dxi = dxi_.cview();
    const auto vol0 = vol0_.cview();
    const auto tmat = tmat_.cview();
    const auto mats = mats_.cview();
    const auto tf = tf_.view();
    const auto diss_t = diss_t_.view();
    unsigned long long* flag = flag_.view().p;
    for_each(
        Exec{}, t1 - t0, QDEMSPH_LAMBDA(std::int64_t j) {
          const std::int64_t t = t0 + j;
          Vec3 xs[4], vs[4];
          for (int k = 0; k < 4; ++k) {
            const std::int32_t i = tv[k * nt + t];
            xs[k] = x[i];
            vs[k] = v[i];
          }
          Mat3 Xi;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) Xi.m[r][c] = dxi[(3 * r + c) * nt + t];
          const ElementForces e = tet_forces(mats[tmat[t]], xs, vs, Xi, vol0[t]);
          if (!(det(e.F) > 0)) raise_flag(flag, t);
          for (int k = 0; k < 4; ++k) tf[k * nt + t] = e.f[k];
          if (dt_diss > 0) {
            if (keep) undo[t] = diss_t[t];
            diss_t[t] += dt_diss * vol0[t] * e.stress.dissipation;
          }
        });
  }

  void undo_dissipation() override {
    const auto [t0, t1] = undo_;
    const auto undo = diss_undo_.cview();
    const auto diss_t = diss_t_.view();
    for_each(
        Exec{}, t1 - t0, QDEMSPH_LAMBDA(std::int64_t j) { diss_t[t0 + j] = undo[t0 + j]; });
    undo_ = {0, 0};
  }

  // The contact evaluation (x, v only) first, the element forces' gather after it, which adds
  // each vertex's own contact sum (ContactStage::sums): on a GPU rank the gather then runs while
  // the host reads the contact shares and the ranks exchange them (compute_forces: the gather,
  // ~130 us a step of the cube block on an H100, had run before the contact stage, and the
  // exchange after it with the device idle), and the merge of those that arrived beside it.
  void assemble_forces(double dt_diss, double alpha) override {
    using Sums = typename ContactStage<Exec>::Sums;
    const bool contact = contact_ != nullptr;
    if (contact) contact_->evaluate(x_.cview(), v_.cview(), dt_diss);
    const Sums cs = contact ? contact_->sums() : Sums{};
    const auto v = v_.cview();
    const auto tf = tf_.cview();
    const auto off = csr_off_.cview();
    const auto ent = csr_ent_.cview();
    const auto fext = (preload_ ? fpre_ : fext_).cview();
    const auto mass = mass_.cview();
    const auto f = f_.view();
    const auto diss_v = diss_v_.view();
    const Vec3 g = gravity_;
    const bool coupled = fc_.size() > 0;
    const auto fc = fc_.cview();
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          Vec3 s = fext[i] + mass[i] * g;
          if (coupled) s += fc[i];
          for (std::int64_t j = off[i]; j < off[i + 1]; ++j) s += tf[ent[j]];
          if (alpha > 0) {
            const Vec3 vi = v[i];
            s -= (alpha * mass[i]) * vi;
            if (dt_diss > 0) diss_v[i] += dt_diss * alpha * mass[i] * norm2(vi);
          }
          if (contact) {
            if (cs.keep_base && cs.target[i]) cs.base.set(i, s);
            s += cs.sum[i];
          }
          f.set(i, s);
        });
  }
  std::span<const ContactShare> contact_shares() override {
    return contact_ ? contact_->shares() : std::span<const ContactShare>{};
  }
  void add_contact_forces(std::span<const ContactShare> in) override {
    if (contact_) contact_->add_forces(f_.view(), in);
  }
  void set_share_routes(const ShareRoutes& routes) override {
    if (contact_) contact_->set_share_routes(routes);
  }

  // The contact stage (null when the model needs none), for tests and diagnostics.
  const ContactStage<Exec>* contact_stage() const { return contact_.get(); }

  std::map<std::string, double> stage_seconds() const override {
    if (!contact_) return {};
    return contact_->seconds();
  }
  std::map<std::string, double> contact_stats() const override {
    if (!contact_) return {};
    const ContactStepStats& c = contact_->stats();
    return {{"pairs", static_cast<double>(c.pairs)},
            {"contacts", static_cast<double>(c.contacts)},
            {"active", static_cast<double>(c.active)},
            {"max_overlap", c.max_overlap},
            {"max_overlap_ever", contact_->max_overlap_ever()},
            {"pair_rebuilds", static_cast<double>(contact_->pair_rebuilds())}};
  }

  SolidViews solid_views() override {
    if (fc_.size() != nv_) fc_.resize(nv_);
    SolidViews s;
    s.space = S;
    s.x = x_.cview();
    s.v = v_.view();
    s.f = f_.view();
    s.fc = fc_.view();
    s.inv_mass = inv_mass_.cview();
    s.held = held_.cview();
    return s;
  }

  // Held components (a `fixed` constraint with `components`) keep their zero velocity.
  void kick(double h) override {
    const auto f = f_.cview();
    const auto im = inv_mass_.cview();
    const auto held = held_.cview();
    const auto v = v_.view();
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (im[i] > 0) v.set(i, v[i] + unheld((h * im[i]) * f[i], held[i]));
        });
  }

  void drift(double h) override {
    const auto v = v_.cview();
    const auto x = x_.view();
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) { x.set(i, x[i] + h * v[i]); });
  }

  void damped_step(double dt, double c) override {
    const auto f = f_.cview();
    const auto im = relax_inv_mass_.cview();
    const auto held = held_.cview();
    const auto v = v_.view();
    const auto x = x_.view();
    const double a = (1 - 0.5 * c * dt) / (1 + 0.5 * c * dt), b = dt / (1 + 0.5 * c * dt);
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (im[i] > 0) {
            const Vec3 vi = a * v[i] + unheld((b * im[i]) * f[i], held[i]);
            v.set(i, vi);
            x.set(i, x[i] + dt * vi);
          }
        });
  }

  void zero_velocity() override {
    const auto im = inv_mass_.cview();
    const auto v = v_.view();
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          if (im[i] > 0) v.set(i, Vec3{});
        });
  }

  void mark_relax_start() override {
    const auto x = x_.cview(), f = f_.cview();
    const auto x0 = x0_.view(), f0 = f0_.view();
    for_each(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          x0.set(i, x[i]);
          f0.set(i, f[i]);
        });
  }

  StaticStats static_stats() override {
    const auto f = f_.cview(), x = x_.cview(), x0 = x0_.cview(), f0 = f0_.cview();
    const auto im = inv_mass_.cview(), rim = relax_inv_mass_.cview();
    const auto held = held_.cview();
    StaticStats s;
    s.residual_max = reduce_max(
        Exec{}, nfv_,
        QDEMSPH_LAMBDA(std::int64_t i) { return im[i] > 0 ? norm(unheld(f[i], held[i])) : 0.0; },
        0.0);
    s.rayleigh_num = reduce_sum(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) {
          return rim[i] > 0 ? dot(x[i] - x0[i], f0[i] - f[i]) : 0.0;
        });
    s.rayleigh_den = reduce_sum(
        Exec{}, nfv_,
        QDEMSPH_LAMBDA(std::int64_t i) { return rim[i] > 0 ? norm2(x[i] - x0[i]) / rim[i] : 0.0; });
    return s;
  }

  Energies energies() override {
    const std::int64_t nt = nt_;
    const auto x = x_.cview(), v = v_.cview(), X = X_.cview();
    const auto fext = fext_.cview();
    const auto mass = mass_.cview();
    const auto tv = tv_.cview();
    const auto dxi = dxi_.cview();
    const auto vol0 = vol0_.cview();
    const auto tmat = tmat_.cview();
    const auto mats = mats_.cview();
    const auto diss_t = diss_t_.cview(), diss_v = diss_v_.cview();
    const Vec3 g = gravity_;
    Energies e;
    e.kinetic = reduce_sum(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) { return 0.5 * mass[i] * norm2(v[i]); });
    e.potential = reduce_sum(
        Exec{}, nfv_,
        QDEMSPH_LAMBDA(std::int64_t i) { return -dot(mass[i] * g + fext[i], x[i] - X[i]); });
    e.strain = reduce_sum(
        Exec{}, nct_, QDEMSPH_LAMBDA(std::int64_t t) {
          Vec3 xs[4];
          for (int k = 0; k < 4; ++k) xs[k] = x[tv[k * nt + t]];
          Mat3 Xi;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) Xi.m[r][c] = dxi[(3 * r + c) * nt + t];
          const Mat3 F = edge_matrix(xs) * Xi;
          return vol0[t] * material_stress(mats[tmat[t]], F, Mat3{}).energy_density;
        });
    e.dissipated = reduce_sum(
                       Exec{}, nct_, QDEMSPH_LAMBDA(std::int64_t t) { return diss_t[t]; }) +
                   reduce_sum(
                       Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) { return diss_v[i]; });
    if (contact_) {
      e.contact = contact_->stored_energy();
      e.contact_dissipated = contact_->dissipated_energy();
    }
    return e;
  }

  std::int64_t find_non_finite() override {
    const auto x = x_.cview(), v = v_.cview();
    const double m = reduce_max(
        Exec{}, nfv_,
        QDEMSPH_LAMBDA(std::int64_t i) {
          const double s = x.x[i] + x.y[i] + x.z[i] + v.x[i] + v.y[i] + v.z[i];
          return is_finite(s) ? 0.0 : static_cast<double>(i + 1);
        },
        0.0);
    return static_cast<std::int64_t>(m) - 1;
  }

  std::int64_t take_inverted_tet() override {
    const unsigned long long f = flag_.to_host()[0];
    if (f == 0) return -1;
    flag_.zero();
    return static_cast<std::int64_t>(f) - 1;
  }

  std::optional<DeepContact> take_deep_contact() override {
    if (!contact_) return std::nullopt;
    return contact_->take_deep_contact();
  }

  // A reduction over the free tets at their current shape: the largest 1 / dt_critical;
  // locate: a second one for the smallest index reaching it (same arithmetic: exact).
  CriticalTet critical_tet(bool locate) override {
    if (nft_ == 0) return {};
    const CriticalRate rate{x_.cview(), tv_.cview(), tmat_.cview(), mats_.cview(), nt_};
    const double rmax = reduce_max(
        Exec{}, nft_, QDEMSPH_LAMBDA(std::int64_t t) { return rate(t); }, 0.0);
    if (!locate) return {1.0 / rmax, -1};
    const double none = -static_cast<double>(nt_);
    const double first = reduce_max(
        Exec{}, nft_,
        QDEMSPH_LAMBDA(std::int64_t t) { return rate(t) >= rmax ? -static_cast<double>(t) : none; },
        none);
    return {1.0 / rmax, static_cast<std::int64_t>(-first)};
  }
  // 1 / tet_critical_dt of tet t at the current positions.
  struct CriticalRate {
    Vec3CView x;
    View<const std::int32_t> tv;
    View<const std::int32_t> tmat;
    View<const Material> mats;
    std::int64_t nt;
    QDEMSPH_HD double operator()(std::int64_t t) const {
      Vec3 p[4];
      for (int k = 0; k < 4; ++k) p[k] = x[tv[k * nt + t]];
      return 1.0 / tet_critical_dt(mats[tmat[t]], min_altitude(p));
    }
  };

  HostFields download(bool with_stress) override {
    HostFields h;
    h.x = x_.to_host();
    h.v = v_.to_host();
    if (!with_stress) return h;
    const std::int64_t nt = nt_;
    Buffer<double> out(S, 7 * nt);
    const auto o = out.view();
    const auto x = x_.cview();
    const auto v = v_.cview();
    const auto tv = tv_.cview();
    const auto dxi = dxi_.cview();
    const auto vol0 = vol0_.cview();
    const auto tmat = tmat_.cview();
    const auto mats = mats_.cview();
    for_each(
        Exec{}, nt_, QDEMSPH_LAMBDA(std::int64_t t) {
          Vec3 xs[4], vs[4];
          for (int k = 0; k < 4; ++k) {
            xs[k] = x[tv[k * nt + t]];
            vs[k] = v[tv[k * nt + t]];
          }
          Mat3 Xi;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) Xi.m[r][c] = dxi[(3 * r + c) * nt + t];
          const Material mat = mats[tmat[t]];
          const ElementForces e = tet_forces(mat, xs, vs, Xi, vol0[t]);
          const Mat3 s = cauchy_stress(mat, e.stress.P, e.F);
          o[0 * nt + t] = s.m[0][0];
          o[1 * nt + t] = s.m[1][1];
          o[2 * nt + t] = s.m[2][2];
          o[3 * nt + t] = s.m[1][2];
          o[4 * nt + t] = s.m[0][2];
          o[5 * nt + t] = s.m[0][1];
          o[6 * nt + t] = von_mises(s);
        });
    const std::vector<double> hs = out.to_host();
    h.stress.resize(nt);
    h.von_mises.resize(nt);
    for (std::int64_t t = 0; t < nt; ++t) {
      for (int c = 0; c < 6; ++c) h.stress[t][c] = hs[c * nt + t];
      h.von_mises[t] = hs[6 * nt + t];
    }
    return h;
  }

  BackendState save_state() override {
    BackendState s = save_fields({nv_, nv_, nt_, true, true});
    if (contact_) s.contact = contact_->save_state();
    if (fc_.size() > 0) s.fc = fc_.to_host();
    return s;
  }
  BackendState save_owned(const OwnedPart& part) override {
    BackendState s = save_fields(part);
    if (contact_ && part.history) s.contact = contact_->save_history();
    return s;
  }

  void load_state(const BackendState& s) override {
    const auto fits = [](const auto& a, std::int64_t n) {
      return static_cast<std::int64_t>(a.size()) == n;
    };
    const bool relax = !s.x0.empty() || !s.f0.empty();
    if (!fits(s.x, nv_) || !fits(s.v, nv_) || !fits(s.f, nv_) || !fits(s.diss_v, nv_) ||
        !fits(s.diss_t, nt_) || (relax && (!fits(s.x0, nv_) || !fits(s.f0, nv_))) ||
        (!s.fc.empty() && !fits(s.fc, nv_)) || s.contact.has_value() != (contact_ != nullptr))
      throw InputError("backend state does not fit the model (vertex, tet or contact counts)");
    x_.assign(s.x);
    v_.assign(s.v);
    f_.assign(s.f);
    diss_v_.assign(s.diss_v);
    diss_t_.assign(s.diss_t);
    if (relax) {
      x0_.assign(s.x0);
      f0_.assign(s.f0);
    } else {
      x0_.zero();
      f0_.zero();
    }
    if (contact_) contact_->load_state(*s.contact);
    if (!s.fc.empty())
      fc_.assign(s.fc);
    else if (fc_.size() > 0)
      fc_.zero();
  }

  void sync() override { exec_sync(Exec{}); }
  Space space() const override { return S; }

  void set_halo(const std::vector<std::int64_t>& send_index, std::int64_t recv_base,
                std::int64_t n_recv) override {
    halo_send_.assign(send_index);
    halo_base_ = recv_base;
    halo_nrecv_ = n_recv;
    if (contact_) contact_->set_share_targets(send_index);  // only vertices others hold
  }

  // Records of 6 doubles: x then v of one vertex, packed where the state lives: straight
  // into `out` when it is in this space, else into halo_buf_ and copied once.
  void pack_halo(double* out, Space where) override {
    const std::int64_t n = halo_send_.size();
    if (n == 0) return;
    const auto idx = halo_send_.cview();
    const auto x = x_.cview(), v = v_.cview();
    double* buf = where == S ? out : staging(n);
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t k) {
          const std::int64_t i = idx[k];
          double* r = buf + 6 * k;
          r[0] = x.x[i], r[1] = x.y[i], r[2] = x.z[i];
          r[3] = v.x[i], r[4] = v.y[i], r[5] = v.z[i];
        });
    if (where != S) space_copy(out, where, buf, S, 6 * n * sizeof(double));
  }

  void unpack_halo(const double* in, Space where) override {
    const std::int64_t n = halo_nrecv_, base = halo_base_;
    if (n == 0) return;
    const double* buf = in;
    if (where != S) {
      double* tmp = staging(n);
      space_copy(tmp, S, in, where, 6 * n * sizeof(double));
      buf = tmp;
    }
    const auto x = x_.view(), v = v_.view();
    for_each(
        Exec{}, n, QDEMSPH_LAMBDA(std::int64_t k) {
          const double* r = buf + 6 * k;
          x.set(base + k, Vec3{r[0], r[1], r[2]});
          v.set(base + k, Vec3{r[3], r[4], r[5]});
        });
  }

  // Room for n halo records in this space (grows only).
  double* staging(std::int64_t n) {
    if (halo_buf_.size() < 6 * n) halo_buf_.resize(6 * n);
    return halo_buf_.view().p;
  }

  void mark_positions() override {
    xmark_.resize(nv_);
    const auto x = x_.cview();
    const auto xm = xmark_.view();
    for_each(
        Exec{}, nv_, QDEMSPH_LAMBDA(std::int64_t i) { xm.set(i, x[i]); });
  }

  void queue_max_moved() override {
    moved_.resize(sizeof(double));  // page-locked on a GPU rank: the copy does not wait
    double* out = reinterpret_cast<double*>(moved_.data());
    if (xmark_.size() != nv_) {
      *out = 0;
      return;
    }
    const auto x = x_.cview(), xm = xmark_.cview();
    reduce_max_to(
        Exec{}, nfv_, QDEMSPH_LAMBDA(std::int64_t i) { return norm(x[i] - xm[i]); }, 0.0, out);
    if constexpr (S == Space::Cuda) moved_mark_.record();
  }
  double max_moved() override {
    moved_mark_.wait();
    return moved_.size() == sizeof(double) ? *reinterpret_cast<const double*>(moved_.data()) : 0;
  }

  std::size_t device_bytes() const override {
    return X_.bytes() + x_.bytes() + v_.bytes() + f_.bytes() + fext_.bytes() + fpre_.bytes() +
           mass_.bytes() + inv_mass_.bytes() + relax_inv_mass_.bytes() + held_.bytes() +
           diss_v_.bytes() + tv_.bytes() + dxi_.bytes() + vol0_.bytes() + tmat_.bytes() +
           tf_.bytes() + diss_t_.bytes() + csr_off_.bytes() + csr_ent_.bytes() + fc_.bytes() +
           (contact_ ? contact_->bytes() : 0);
  }

 private:
  // kept_tets < 0: a model of its own. Else (upload_same_tets) the last upload's tets and owned
  // vertices in the same order, its first kept_tets tets on the same vertex numbers: of the
  // vertex arrays only those from the first ghost on are written (the owned vertices' model
  // data and state, x, v and diss_v, stand), of the tets' vertex numbers those from kept_tets on;
  // the tets' reference data, dissipation and corner lists stand.
  void upload_model(const Model& m, std::int64_t kept_tets) {
    const bool same_tets = kept_tets >= 0;
    if (same_tets && (m.n_tets() != nt_ || m.n_free_vertices != nfv_ || kept_tets > nt_))
      throw std::logic_error("upload_same_tets: the model has other tets or free vertices");
    nv_ = m.n_vertices();
    nt_ = m.n_tets();
    nfv_ = m.n_free_vertices;
    nft_ = m.n_free_tets;
    nct_ = m.n_counted_tets < 0 ? nft_ : m.n_counted_tets;
    gravity_ = m.gravity;
    const std::int64_t nv = nv_, nt = nt_, v0 = same_tets ? nfv_ : 0;  // first vertex written
    for (auto [b, h] :
         {std::pair{&X_, &m.X}, {&x_, &m.x}, {&v_, &m.v}, {&fext_, &m.fext}, {&fpre_, &m.fpre}})
      assign_tail_on_threads(*b, *h, v0, stage_);
    f_.resize(nv_);
    fc_.resize(0);
    for (auto [b, h] : {std::pair{&mass_, &m.mass},
                        {&inv_mass_, &m.inv_mass},
                        {&relax_inv_mass_, &m.relax_inv_mass}})
      assign_tail_on_threads(*b, *h, v0, stage_);
    auto fit = [&](auto& b, std::int64_t n) {  // the kept prefix, or all written next
      same_tets ? b.resize_keep(n) : b.resize_for_overwrite(n);
    };
    fit(held_, nv);
    write_range_on_host(held_, v0, nv, stage_,
                        [&](std::int64_t i) { return held_components(m.flags[i]); });
    x0_.resize(nv_);  // relaxation start state (mark_relax_start)
    f0_.resize(nv_);
    fit(diss_v_, nv);
    diss_v_.zero_from(v0);
    fit(tv_, 4 * nt);
    const std::int64_t t0 = same_tets ? kept_tets : 0;  // first tet written
    for (int k = 0; k < 4; ++k)
      write_range_on_host(tv_, k * nt + t0, (k + 1) * nt, stage_,
                          [&](std::int64_t e) { return m.tets[e - k * nt][k]; });
    mats_.assign(m.materials);
    if (!same_tets) {
      write_on_host(dxi_, 9 * nt, stage_, [&](double* dxi) {
        for_each(HostExec{}, nt, [&](std::int64_t t) {
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) dxi[(3 * r + c) * nt + t] = m.dX_inv[t].m[r][c];
        });
      });
      assign_on_threads(vol0_, m.vol0, stage_);
      assign_on_threads(tmat_, m.tet_material, stage_);
      tf_.resize_for_overwrite(4 * nt_);  // element_forces writes every corner it gathers
      diss_t_.resize(nt_);
      upload_corner_lists(m);
    }
    flag_.resize(1);
    if (!m.contact.enabled) {
      contact_.reset();
    } else {
      if (!contact_) contact_ = std::make_unique<ContactStage<Exec>>();
      contact_->upload(m);  // a re-upload keeps the stage's storage
    }
  }

  // The vertex and tet fields of save_state and save_owned.
  BackendState save_fields(const OwnedPart& part) const {
    BackendState s;
    const std::int64_t n = part.vertices;
    s.x = x_.to_host(part.positions);
    s.v = v_.to_host(n);
    if (part.forces) s.f = f_.to_host(n);
    s.diss_v = diss_v_.to_host(n);
    s.diss_t = diss_t_.to_host(part.tets);
    if (part.relaxation) {
      s.x0 = x0_.to_host(n);
      s.f0 = f0_.to_host(n);
    }
    return s;
  }

  std::string name_;
  std::int64_t nv_ = 0, nt_ = 0, nfv_ = 0, nft_ = 0, nct_ = 0;
  Vec3 gravity_;
  bool preload_ = false;
  Vec3Buffer X_{S}, x_{S}, v_{S}, f_{S}, fext_{S}, fpre_{S}, x0_{S}, f0_{S};
  Vec3Buffer fc_{S};  // fluid force on the vertices (empty unless coupled: solid_views)
  Buffer<Vec3> tf_{S};
  Buffer<double> mass_{S}, inv_mass_{S}, relax_inv_mass_{S}, diss_v_{S}, dxi_{S}, vol0_{S},
      diss_t_{S};
  Buffer<std::int32_t> tv_{S}, tmat_{S};
  Buffer<std::uint8_t> held_{S};  // per vertex: held components (bits x, y, z)
  Buffer<Material> mats_{S};
  Buffer<std::int64_t> csr_off_{S}, csr_ent_{S};
  std::vector<std::int64_t> csr_off_h_;  // the corner lists' offsets as built on the host
  StagingBytes stage_;                   // host side of the uploads (write_on_host)
  Buffer<unsigned long long> flag_{S};
  // Distributed runs only (empty otherwise): halo send list and staging, moved-reference and
  // the queued max_moved (its host slot and, on a GPU, the point after its copy).
  Buffer<std::int64_t> halo_send_{S};
  Buffer<double> halo_buf_{S};
  std::int64_t halo_base_ = 0, halo_nrecv_ = 0;
  Vec3Buffer xmark_{S};
  Buffer<double> diss_undo_{S};  // dissipated energy before an undoable element_forces
  std::pair<std::int64_t, std::int64_t> undo_{0, 0};  // its tets
  StagingBytes moved_;
  DeviceMark moved_mark_;
  std::unique_ptr<ContactStage<Exec>> contact_;  // null when the model needs no contact
};

}  // namespace qdemsph
