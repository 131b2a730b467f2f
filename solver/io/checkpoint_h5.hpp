// Checkpoints of a dynamic run as HDF5 files (docs/scene-format.md, output.checkpoint).
//
// Layout of DIR/checkpoint_<step:010d>.h5:
//   /                attributes format ("qdemsph checkpoint"), version (1), time, dt (double),
//                    step (int64), scene (string); fingerprint (string: "item\tvalue" lines)
//   /solid/          vertex_gid (N) uint64, x v f (N,3), dissipated (N);
//                    tet_gid (M) uint64, tet_dissipated (M); fc (N,3): the fluid's coupling
//                    force (scenes with fluid.couple_bodies only; files written before it was
//                    stored lack it and are refused for such scenes)
//   /contact/        (contact scenes) the history (contact/contact_state.hpp), one row per
//                    active record of the last step, in key order: history_type (K) uint8,
//                    history_feature1/2 (K,3) uint64 (global vertex ids; unused slots
//                    2^64-1), history_active (K) uint8, history_xi history_h (K,3),
//                    history_energy history_energy_t (K), history_vertex (K,4) int64 (global
//                    vertex ids; -1: unused), history_weight (K,4), history_n1 (K) int32;
//                    ref_centroid (P,3), ref_radius (P): the pair list's rebuild reference
//                    (empty when written on several ranks: it belongs to one layout);
//                    attributes skin, max_overlap, max_overlap_ever, dissipated (double),
//                    rebuilds, steps, pairs, contacts, active (int64) (on several ranks: the
//                    counters of summary.json's contact object; steps 0)
//   /fluid/          (SPH scenes) gid (n) uint64, type (n) uint8, x v a (n,3), rho p m (n), in
//                    the solver's particle order (the next step's summation order)
//   /output/         attributes probes_bytes, fluid_csv_bytes, field_frames, fluid_frames,
//                    last_probe_step, last_field_step (int64), next_probe, next_field (double)
// Everything is keyed by global ids (vertex, tet, particle; contact features by their
// vertices' ids), so the state is the same whichever number of ranks wrote it (rank 0 writes
// it gathered from all) and any number of ranks can restart from it.
//
// Writing is atomic: PATH.tmp is written, flushed, fsync'ed and renamed over PATH, then the
// folder is fsync'ed. A process killed at any moment leaves the earlier checkpoints intact.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "integrate/backend.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph {

// A contact history key by global vertex ids: point-face (vertex; triangle's 3 vertices),
// edge-edge (2 vertices; 2 vertices), wall (vertex; wall index). Unused slots: kNoId.
struct GlobalContactKey {
  static constexpr std::uint64_t kNoId = ~std::uint64_t{0};
  std::uint8_t type = 0;
  std::array<std::uint64_t, 3> a{kNoId, kNoId, kNoId}, b{kNoId, kNoId, kNoId};
};

struct CheckpointOutput {
  std::int64_t probes_bytes = -1;     // length of probes.csv at the checkpoint (-1: none)
  std::int64_t fluid_csv_bytes = -1;  // length of fluid.csv (-1: none)
  std::int64_t field_frames = 0, fluid_frames = 0;
  double next_probe = 0, next_field = 0;                    // the run loop's next output times
  std::int64_t last_probe_step = -1, last_field_step = -1;  // steps of the last row and frame
};

struct Checkpoint {
  double time = 0, dt = 0;
  std::int64_t step = 0;
  std::string scene;  // the scene file it was written from (for messages)
  std::vector<std::pair<std::string, std::string>> fingerprint;  // (item, value)
  std::vector<std::uint64_t> vertex_gid, tet_gid;                // the order of solid's arrays
  // solid.contact's k1/k2 stay empty in a checkpoint: contact_keys holds them by global id;
  // its record vertices are global ids.
  BackendState solid;
  std::vector<GlobalContactKey> contact_keys;
  std::optional<FluidState> fluid;
  CheckpointOutput output;
};

// Writes atomically (see above). Throws InputError when the folder is not writable.
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c);
// Throws InputError naming the file when it is missing, not HDF5, not a qdemsph checkpoint
// or incomplete.
Checkpoint read_checkpoint(const std::filesystem::path& path);

// DIR/checkpoint_<step:010d>.h5 files, oldest first.
std::vector<std::filesystem::path> list_checkpoints(const std::filesystem::path& dir);
// The newest readable checkpoint of DIR (`path` receives its file); unreadable newer ones are
// skipped with a warning on stderr. InputError when DIR holds none.
Checkpoint read_latest_checkpoint(const std::filesystem::path& dir, std::filesystem::path& path);

// The checkpoints of one run: written into DIR, the newest `keep` kept. The constructor
// removes temporary files a killed run left behind.
class CheckpointSeries {
 public:
  CheckpointSeries(std::filesystem::path dir, int keep);
  std::filesystem::path write(const Checkpoint& c);  // returns the file written
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  int keep_;
};

}  // namespace qdemsph
