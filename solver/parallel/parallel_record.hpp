// The `parallel` object of summary.json: the decomposition's records for the scaling sweeps
// (scaling/ reads it; keep the keys). Written on every run: one rank reports ranks = 1, no
// rebalancing and its own phase times.
//
//   ranks, curve, rebalances
//   rebuilds             the bodies' layouts installed (the first, the rebalances and the ghost
//                        rebuilds a vertex's motion past the contact slack asked for)
//   contact_slack        the contact band's slack at the end [m] (grows when rebuilds are dear)
//   imbalance            max / mean - 1 over ranks of the busy time (elements, integration,
//                        contact) of the last measurement window (rebalance_every steps): the
//                        bodies' balancer's measure, without the fluid's passes (phases_by_rank
//                        has every rank's; scaling/run.py's busy_imbalance counts them)
//   imbalance_modelled   max / mean - 1 over ranks of the partition's cost of their items
//                        (vertices, home tets, contact vertices at the weights fitted to the
//                        last window's times): what a new cut could even out; the balancer
//                        cuts again only when this and `imbalance` exceed its threshold
//   imbalance_initial    the same as `imbalance` over the first window, before any rebalancing
//   migrated_bytes       bytes sent between ranks by migrations (state, owners, history)
//   halo_bytes_per_step  bytes sent by all ranks' halo exchanges per force evaluation
//   fluid_halo_bytes_per_step   the SPH fluid's (sph/fluid_exchange.hpp, FluidTraffic): bytes
//                        sent by all ranks through the ghost plan (the ghost fill of each
//                        layout rebuild and the refreshes of every step) per fluid evaluation
//   fluid_migrated_bytes the fluid's bytes at its layout rebuilds: particles to new owners and
//                        the allgathered border band cells (bytes x (ranks - 1))
//   fluid_rebuilds       the fluid's layout rebuilds (distribute() calls), the first included
//   fluid_recuts         of them, those that cut the fluid's partition again
//   fluid_skin           the fluid's ghost-band skin at the end [m] (widens when rebuilds are dear)
//   owned_vertices, owned_tets   per rank: owned free vertices, home free tets (at the end)
//   phases_max, phases_mean      per phase, seconds over ranks (kParallelPhases), of the
//                        stepping loop: migration and balance count the rebalances and rebuilds
//                        during the run (the fluid's layout rebuilds too), not the first
//                        distribution
//   setup_s              the first distribution (the largest over ranks): every item moved from
//                        its start slice (or a checkpoint's share) to its owner, the fluid's
//                        first layout
//   rebalance_log        [{step, imbalance_before, imbalance_after, bytes}]; imbalance_after
//                        is measured over the next window (or the rest of the run)
//   rebuild_log          the bodies' layout rebuilds and rebalances during the run:
//                        [{step, rebalance, slack, seconds, parts}]: the slack it was built
//                        with [m], this rank's (rank 0's in summary.json) wall seconds of it
//                        and of its parts (balance and the migration.* sub-phases)
//   phases_by_rank       per rank, its seconds of kParallelPhases (as in phases_*) and of the
//                        sub-phases it timed (kBodySubPhases, kFluidSubPhases, as in summary.json's
//                        phases: the first distribution's included; zeros left out): a part that
//                        ends in a collective holds the wait for slower ranks, which only the
//                        ranks side by side show
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "io/json.hpp"
#include "model/model.hpp"
#include "sph/fluid_exchange.hpp"

namespace qdemsph {

inline constexpr const char* kParallelPhases[] = {"elements", "integration", "contact", "sph",
                                                  "halo",     "migration",   "balance", "output"};

// Sub-phases of a distributed run (docs/parallel.md, "Records"): the bodies' (in summary.json's
// phases the largest over ranks) and the fluid stage's (rank 0's there).
inline constexpr const char* kBodySubPhases[] = {"contact.broad",
                                                 "contact.narrow",
                                                 "contact.force",
                                                 "halo.skin",
                                                 "halo.xv",
                                                 "halo.shares",
                                                 "elements.shares",
                                                 "migration.export",
                                                 "migration.state",
                                                 "migration.layout",
                                                 "migration.layout.tets",
                                                 "migration.layout.band",
                                                 "migration.layout.halo",
                                                 "migration.layout.model",
                                                 "migration.upload",
                                                 "migration.upload.model",
                                                 "migration.upload.state",
                                                 "migration.upload.routes"};
inline constexpr const char* kFluidSubPhases[] = {"sph.halo",
                                                  "sph.halo.skin",
                                                  "sph.halo.mpi",
                                                  "sph.rebuild",
                                                  "sph.rebuild.out",
                                                  "sph.rebuild.owners",
                                                  "sph.rebuild.migrate",
                                                  "sph.rebuild.ghosts",
                                                  "sph.rebuild.halo",
                                                  "sph.rebuild.halo.plan",
                                                  "sph.rebuild.halo.gather",
                                                  "sph.rebuild.in",
                                                  "sph.rebuild.in.order",
                                                  "sph.rebuild.in.fields",
                                                  "sph.setup"};

struct RebalanceEntry {
  std::int64_t step = 0;
  double imbalance_before = 0, imbalance_after = 0;
  std::int64_t bytes = 0;
};

// A rebuild or rebalance of the bodies' layout during the run (ParallelRecord::rebuild_log).
struct RebuildEntry {
  std::int64_t step = 0;
  bool rebalance = false;
  double slack = 0, seconds = 0;
  std::int64_t owners_changed = 0;  // free vertices that changed owner (all ranks)
  std::map<std::string, double> parts;
};

struct ParallelRecord {
  int ranks = 1;
  std::string curve = "hilbert";
  std::int64_t rebalances = 0, rebuilds = 0;
  double contact_slack = 0;
  double imbalance = 0, imbalance_initial = 0, imbalance_modelled = 0;
  std::int64_t migrated_bytes = 0;
  double halo_bytes_per_step = 0;
  double fluid_halo_bytes_per_step = 0;
  std::int64_t fluid_migrated_bytes = 0;
  std::int64_t fluid_rebuilds = 0, fluid_recuts = 0;
  double fluid_skin = 0;
  double setup_s = 0;
  std::vector<std::int64_t> owned_vertices, owned_tets;
  std::map<std::string, double> phases_max, phases_mean;
  std::vector<RebalanceEntry> rebalance_log;
  std::vector<RebuildEntry> rebuild_log;
  std::vector<std::map<std::string, double>> phases_by_rank;

  // The distributed fluid's fields from its exchange's traffic.
  void set_fluid(const FluidTraffic& t);
  Json to_json() const;
};

// One rank: the run's phase seconds (as in summary.json "phases", elements without contact).
ParallelRecord serial_parallel_record(const Model& model, const std::string& curve,
                                      const std::map<std::string, double>& phases);

}  // namespace qdemsph
