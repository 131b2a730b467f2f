// The contact stage's state between steps, on the host, in local indices: what a checkpoint
// must hold for a restarted run to continue bit-identically (integrate/restart.hpp maps the
// history keys to global vertex ids for the file).
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

struct ContactState {
  // Tangential history of the last force evaluation: the active feature pairs, sorted by key
  // (k1, k2) (contact/contact_record.hpp), and their spring elongations xi.
  std::vector<std::uint64_t> k1, k2;
  std::vector<Vec3> xi;
  // Verlet pair list: primitive centroids and radii at its last rebuild (empty: never built)
  // and the skin it was built with; the list itself is rebuilt from them, identically.
  std::vector<Vec3> ref_centroid;
  std::vector<double> ref_radius;
  double skin = 0;
  std::int64_t rebuilds = 0, steps = 0;
  // Counters of the last step and the largest overlap so far (summary.json).
  std::int64_t pairs = 0, contacts = 0, active = 0;
  double max_overlap = 0, max_overlap_ever = 0;
};

}  // namespace qdemsph
