// Load balancing as a pure function (STYLE.md item 7, METHOD.md section 4): cells sorted
// along the space-filling curve, with the cost measured for each over the last steps
// (vertices, tets, contact pairs, SPH particles weighted by their time), are cut into
// contiguous pieces of nearly equal cost, one per rank. No MPI: every rank calls it on the
// same (allgathered) cell list and gets the same answer.
//
// Cut rule: with W the total cost and P_i the cost of the cells before cell i, cell i goes
// to rank floor(n (P_i + c_i / 2) / W) (its cost midpoint decides). Owners never decrease
// along the curve (contiguous pieces), and rank r gets exactly the cells whose midpoints
// lie in [r W / n, (r + 1) W / n), so
//     |load_r - W / n| <= max_i c_i        for every rank r.
// A rank may get no cell when one cell costs more than W / n.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace qdemsph {

// Owner rank of each cell. keys: cell keys in increasing order (checked); cost: >= 0 and
// finite, one per cell; nranks >= 1. Cells of zero total cost are spread by count.
// Throws std::invalid_argument on bad input.
std::vector<int> partition_cells(std::span<const std::uint64_t> keys, std::span<const double> cost,
                                 int nranks);

// The first key of each rank's piece (nranks + 1 entries; a rank without cells gets the
// next rank's first key, the last entry is UINT64_MAX), so that any key, including keys of
// cells that are not in the list, maps to its owner by owner_of_key.
std::vector<std::uint64_t> partition_splitters(std::span<const std::uint64_t> keys,
                                               std::span<const int> owner, int nranks);
int owner_of_key(std::span<const std::uint64_t> splitters, std::uint64_t key);

struct PartitionStats {
  std::vector<double> load;  // cost per rank
  double mean = 0, max = 0;
  double imbalance = 0;  // max / mean - 1 (0 when balanced or empty)
  double max_cell = 0;   // the largest single cell cost
};
PartitionStats partition_stats(std::span<const double> cost, std::span<const int> owner,
                               int nranks);

}  // namespace qdemsph
