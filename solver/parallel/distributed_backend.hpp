// A run on several MPI ranks (docs/parallel.md), seen by the Stepper and run_scene as one
// Backend: a decorator around the rank's own backend (CPU or CUDA), which computes the
// rank's part of the model (local_model.hpp). Every stage the Stepper calls maps to the local
// backend plus communication:
//
//   compute_forces   rebuild/rebalance when due; halo exchange of x, v (packed by the local
//                    backend, on the GPU for CUDA) overlapping the interior tets; then the
//                    boundary and halo tets; then the gather, loads and contact of owned
//                    vertices.
//   kick, drift, damped_step, zero_velocity, mark_relax_start    owned vertices, no messages
//                    (on a GPU drift also queues the next evaluation's skin test and packing)
//   energies, static_stats, find_non_finite, take_inverted_tet    local part + MPI_Allreduce
//                    (energies count home tets and owned vertices once; ids are global, so
//                    the Stepper's messages name the right element)
//   download         gathered to rank 0 in global order (other ranks get empty arrays)
//   save_state       the whole model's state gathered to rank 0 in the model's order, as one
//                    rank's backend gives it (other ranks get an empty state): a checkpoint
//   load_state       every rank passes the whole model's state (e.g. read from a checkpoint);
//                    each adopts a contiguous share, which adopt() moves to the owners
//
// Contact across rank borders: each rank holds, besides its owned vertices and the ghosts of
// its tets, every contact vertex within a band of its owned contact vertices (free bodies'
// from their owners by halo exchange, fixed bodies' from the model, which every rank has).
// Each feature pair is evaluated once, by the owner of its anchor vertex (contact_record.hpp,
// anchor_slot), which keeps its tangential history; the force shares of vertices other ranks
// own, addressed on the device to the owner's index with global keys (the layout's
// ShareRoutes), go to those owners (one variable-length exchange with the halo neighbours per
// step, while the element forces' gather runs on a GPU),
// which sort them in among their own entries by record key, so every vertex sums its contact
// forces in the one-rank order. The band is wide enough for the pairs of owned vertices until
// some vertex has moved `slack` since the last rebuild; then the ghosts are rebuilt (owners
// re-assigned from the current partition, one MPI_Allreduce per step checks the distance).
//
// Rebalancing: every rebalance_every steps the busy time (elements, integration, contact)
// of each rank over the window gives the imbalance max/mean - 1 and the time per tet, per
// vertex and per contact vertex; above rebalance_threshold, when the busiest rank's excess over
// the next window outweighs a rebuild's measured seconds (recut_pays, rebuild_policy.hpp), the
// tree is refined and cut again with those costs (balance.hpp), the state migrates (MigratePlan)
// and the halo plans are rebuilt. Every migration goes through a gid-keyed StateSlice, the same
// form a checkpoint is gathered from, so a restart on any number of ranks is adopt(slice).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "integrate/backend.hpp"
#include "io/scene.hpp"
#include "model/model.hpp"
#include "parallel/parallel_record.hpp"

namespace qdemsph {

struct ParallelOptions {
  std::string curve = "hilbert";
  double rebalance_threshold = 0.10;
  long rebalance_every = 100;
  double max_cell_cost = 0.02;
};
ParallelOptions parallel_options(const ParallelSpec& spec);

// A rank's share of the dynamic state, by global id: what a checkpoint writes (export_state
// on every rank gives each vertex, tet and contact once) and what a restart on any number of
// ranks hands to adopt(), each rank any slice (e.g. a contiguous range of the file). Static
// data (reference geometry, masses, loads, topology) come from the model built from the scene.
struct StateSlice {
  std::vector<std::int64_t> vertex;  // free vertices
  std::vector<Vec3> x, v;
  // The force of the last evaluation (the next half kick reads it), or empty: zero, for a
  // rebuild inside compute_forces, which evaluates the forces right after.
  std::vector<Vec3> f;
  std::vector<double> diss_v;
  std::vector<Vec3> x0, f0;       // dynamic relaxation start state, or empty
  std::vector<std::int64_t> tet;  // free tets
  std::vector<double> diss_t;
  // Contact history (active entries only) with global keys (vertex gid, global triangle /
  // edge, wall index) and the gids of each entry's vertices (-1: unused); `dissipated` is
  // this slice's share of the contact dissipation since the start (the shares sum to the
  // run's); the pair-list reference and counters stay empty (the list is rebuilt for the new
  // layout).
  ContactState contact;

  // The free vertices `ids`, with entries first, first + 1, ... of a backend state (their x0,
  // f0 when relaxing).
  void set_vertices(std::vector<std::int64_t> ids, const BackendState& st, std::int64_t first,
                    bool relaxing) {
    const auto part = [&](const auto& a) {
      return std::vector(a.begin() + first, a.begin() + first + ids.size());
    };
    x = part(st.x);
    v = part(st.v);
    f = part(st.f);
    diss_v = part(st.diss_v);
    x0 = relaxing ? part(st.x0) : std::vector<Vec3>{};
    f0 = relaxing ? part(st.f0) : std::vector<Vec3>{};
    vertex = std::move(ids);
  }
};

class DistributedBackend : public Backend {
 public:
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Records for summary.json (collective). run_phases: the run's phase seconds on this rank
  // ("output", "sph" and the fluid's sub-phases "sph.halo", "sph.rebuild" are taken from it).
  virtual ParallelRecord record(const std::map<std::string, double>& run_phases) = 0;
  // The checkpoint hook: this rank's owned state, and the collective restart from slices.
  virtual StateSlice export_state() = 0;
  virtual void adopt(const StateSlice& slice) = 0;
  // For tests: owned free vertices and home tets (global ids), rebuilds and rebalances so far.
  virtual std::vector<std::int64_t> owned_vertices() const = 0;
  virtual std::vector<std::int64_t> home_tets() const = 0;
  virtual std::int64_t rebuilds() const = 0;
  virtual std::int64_t rebalances() const = 0;
};

// On MPI_COMM_WORLD (parallel/world.hpp). `local` computes this rank's part; upload() takes
// the global model (every rank builds it from the scene), which must outlive the backend.
std::unique_ptr<DistributedBackend> make_distributed_backend(std::unique_ptr<Backend> local,
                                                             const ParallelOptions& options);

}  // namespace qdemsph
