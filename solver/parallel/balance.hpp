// The decomposition of a distributed run (METHOD.md section 4): a cubic grid around the
// items, its cells refined as a tree where cost crowds (cell_tree.hpp), the leaves cut into
// contiguous pieces of equal cost along the space-filling curve (partition.hpp), stored as
// splitter keys so that any position maps to its owner rank.
//
// Collective over the communicator, but no item is gathered: each rank passes its own items
// (positions and measured costs); the tree is refined level by level with one sum over the
// ranks of the candidate cells' costs per level, so the traffic is O(leaves), not O(items).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/vec.hpp"
#include "parallel/cell_tree.hpp"
#include "parallel/comm_plan.hpp"
#include "parallel/partition.hpp"

namespace qdemsph {

struct Decomposition {
  SfcGrid grid;
  std::vector<std::uint64_t> splitters;  // nranks + 1 keys (partition_splitters)
  // The cost model's view of the result: loads per rank summed over leaves.
  std::vector<double> load;
  double predicted_imbalance = 0;  // max / mean - 1 of `load`
  double max_cell = 0;             // the largest leaf cost
  double mean_load = 0;
  std::int64_t leaves = 0;

  int owner(Vec3 p) const { return owner_of_key(splitters, grid.key(p)); }
};

Curve parse_curve(const std::string& name);  // hilbert | morton | peano
const char* curve_name(Curve c);

// pos/cost: this rank's items. max_cell_fraction: leaves are split while their cost exceeds
// this fraction of the mean rank load (down to the finest grid level). keys (optional):
// receives each item's key on the new grid, so that a caller who looks up the items' owners
// (owner_of_key(d.splitters, keys[i]) == d.owner(pos[i])) need not compute them again.
Decomposition balance(MPI_Comm comm, std::span<const Vec3> pos, std::span<const double> cost,
                      Curve curve, double max_cell_fraction,
                      std::vector<std::uint64_t>* keys = nullptr);

// Sum over ranks with the same result on every rank (reduce to rank 0, then broadcast), so
// that decisions taken from it agree everywhere.
void allreduce_sum_same(MPI_Comm comm, double* v, int n);

}  // namespace qdemsph
