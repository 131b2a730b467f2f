// The contact stage's state between steps, on the host: everything the next step reads, so
// that a run continues exactly after ContactStage::load_state. One form serves both users:
// checkpoints (integrate/restart.cpp maps keys and vertices to global ids for the file) and a
// distributed run's migration (parallel/distributed_backend.cpp sends the history entries,
// keys and vertices by global id, to the new owners when the decomposition changes).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

// Counters of the last step (summary.json).
struct ContactStepStats {
  std::int64_t pairs = 0, contacts = 0, active = 0;
  double max_overlap = 0;  // max (D_DEM - d) over active contacts [m]
};

// A contact whose surfaces crossed deeper than the bound (contact.max_penetration): the
// vertex on side 1 (point-face: the vertex; edge-edge: an end of the first edge), the two
// bodies (body2 = -1: the wall `wall`), the depth -d and the bound [m].
struct DeepContact {
  std::int64_t vertex = -1;
  int body1 = -1, body2 = -1, wall = -1;
  double depth = 0, bound = 0;
};

struct ContactState {
  // Tangential history: one entry per record of the last force evaluation, sorted by key
  // (k1, k2) (contact/contact_record.hpp), with whether it was active, its spring xi, its
  // non-potential force h and stored spring energy (normal + tangential, and tangential
  // alone), and its record's vertices (side 1 first; -1: unused), weights and side-1 count
  // (a touch that ends next step dissipates its energy at these vertices' velocities).
  std::vector<std::uint64_t> k1, k2;
  std::vector<std::uint8_t> active;
  std::vector<Vec3> xi, h;
  std::vector<double> energy, energy_t;
  std::vector<std::array<std::int64_t, 4>> v;
  std::vector<std::array<double, 4>> w;
  std::vector<std::int32_t> n1;
  // Verlet pair list: primitive centroids and radii at its last rebuild (empty: never built,
  // or not valid for this layout: rebuilt at the next step) and the skin it was built with.
  std::vector<Vec3> ref_centroid;
  std::vector<double> ref_radius;
  double skin = 0;
  std::int64_t rebuilds = 0, steps = 0;
  ContactStepStats stats;
  double max_overlap_ever = 0;
  double dissipated = 0;  // contact dissipation since the start [J]

  std::size_t size() const { return k1.size(); }
  void resize(std::size_t n) {
    k1.resize(n);
    k2.resize(n);
    active.resize(n, 1);
    xi.resize(n);
    h.resize(n);
    energy.resize(n);
    energy_t.resize(n);
    v.resize(n, {-1, -1, -1, -1});
    w.resize(n);
    n1.resize(n, 1);
  }
  // Entry j becomes entry e of `o` (a history entry moved between forms).
  void set(std::size_t j, const ContactState& o, std::size_t e) {
    k1[j] = o.k1[e];
    k2[j] = o.k2[e];
    active[j] = o.active[e];
    xi[j] = o.xi[e];
    h[j] = o.h[e];
    energy[j] = o.energy[e];
    energy_t[j] = o.energy_t[e];
    v[j] = o.v[e];
    w[j] = o.w[e];
    n1[j] = o.n1[e];
  }
  // Appends entry e of `o`.
  void push_back(const ContactState& o, std::size_t e) {
    resize(size() + 1);
    set(size() - 1, o, e);
  }
};

}  // namespace qdemsph
