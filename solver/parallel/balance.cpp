#include "parallel/balance.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "core/exec_host.hpp"
#include "core/radix_sort.hpp"
#include "parallel/partition.hpp"

namespace qdemsph {
namespace {

// keys[i] = grid.key(pos[i]) (OpenMP threads).
void grid_keys(const SfcGrid& grid, std::span<const Vec3> pos, std::vector<std::uint64_t>& keys) {
  resize_for_overwrite(keys, pos.size());
  for_each(HostExec{}, static_cast<std::int64_t>(pos.size()),
           [&](std::int64_t i) { keys[i] = grid.key(pos[i]); });
}

}  // namespace

Curve parse_curve(const std::string& name) {
  if (name == "morton") return Curve::Morton;
  if (name == "peano") return Curve::Peano;
  if (name == "hilbert") return Curve::Hilbert;
  throw std::invalid_argument("unknown space-filling curve '" + name + "'");
}

const char* curve_name(Curve c) {
  return c == Curve::Morton ? "morton" : c == Curve::Peano ? "peano" : "hilbert";
}

void allreduce_sum_same(MPI_Comm comm, double* v, int n) {
  std::vector<double> out(n, 0.0);
  MPI_Reduce(v, out.data(), n, MPI_DOUBLE, MPI_SUM, 0, comm);
  int me = 0;
  MPI_Comm_rank(comm, &me);
  if (me == 0) std::copy(out.begin(), out.end(), v);
  MPI_Bcast(v, n, MPI_DOUBLE, 0, comm);
}

Decomposition balance(MPI_Comm comm, std::span<const Vec3> pos, std::span<const double> cost,
                      Curve curve, double max_cell_fraction, std::vector<std::uint64_t>* keys_out) {
  if (pos.size() != cost.size())
    throw std::invalid_argument("balance: positions and costs differ in size");
  int nranks = 1;
  MPI_Comm_size(comm, &nranks);
  Decomposition d;
  // The grid: a cube around all items (a little larger, so that round-off stays inside).
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (const Vec3& p : pos)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  double glo[3], ghi[3];
  MPI_Allreduce(lo, glo, 3, MPI_DOUBLE, MPI_MIN, comm);
  MPI_Allreduce(hi, ghi, 3, MPI_DOUBLE, MPI_MAX, comm);
  double side = 0;
  for (int a = 0; a < 3; ++a) side = std::max(side, ghi[a] - glo[a]);
  if (!(side > 0)) side = 1;  // one item, or none: any grid
  side *= 1.001;
  d.grid.curve = curve;
  d.grid.order = curve == Curve::Peano ? 10 : 16;
  d.grid.lo = Vec3{glo[0], glo[1], glo[2]} - Vec3{0.0005 * side, 0.0005 * side, 0.0005 * side};
  if (!(glo[0] <= ghi[0])) d.grid.lo = Vec3{0, 0, 0};  // no items anywhere
  d.grid.h = side / d.grid.side();

  // Local items sorted by key (stable: those of one finest cell in their input order) with
  // prefix sums: the cost of a key range is a difference.
  std::vector<std::uint64_t> own_keys;
  std::vector<std::uint64_t>& keys = keys_out ? *keys_out : own_keys;
  grid_keys(d.grid, pos, keys);
  std::vector<std::pair<std::uint64_t, double>> items(pos.size()), scratch;
  for_each(HostExec{}, static_cast<std::int64_t>(items.size()), [&](std::int64_t i) {
    items[i] = {keys[i], cost[i]};
  });
  const std::uint64_t s = d.grid.side();
  radix_sort(items, scratch, std::bit_width(s * s * s - 1));
  std::vector<std::uint64_t> sorted(items.size());
  std::vector<double> prefix(items.size() + 1, 0.0);
  for (std::size_t i = 0; i < items.size(); ++i) {
    sorted[i] = items[i].first;
    prefix[i + 1] = prefix[i] + items[i].second;
  }
  double total = prefix.back();
  allreduce_sum_same(comm, &total, 1);
  d.mean_load = total / nranks;
  // A leaf holding one item cannot be split usefully: never ask for less than the largest
  // single item cost (else its cell would be split down to the finest level for nothing).
  double max_item = 0;
  for (double c : cost) max_item = std::max(max_item, c);
  double gmax_item = 0;
  MPI_Allreduce(&max_item, &gmax_item, 1, MPI_DOUBLE, MPI_MAX, comm);
  const double max_cost = std::max(max_cell_fraction * d.mean_load, gmax_item);
  const std::vector<TreeCell> leaves =
      refine_cells_by(curve, d.grid.order, max_cost, 0,
                      [&](std::span<const std::uint64_t> k, std::span<const std::uint64_t> span,
                          std::span<double> c) {
                        for (std::size_t j = 0; j < k.size(); ++j) {
                          const auto a = std::lower_bound(sorted.begin(), sorted.end(), k[j]);
                          const auto e = std::lower_bound(a, sorted.end(), k[j] + span[j]);
                          c[j] = prefix[e - sorted.begin()] - prefix[a - sorted.begin()];
                        }
                        allreduce_sum_same(comm, c.data(), static_cast<int>(c.size()));
                      });
  std::vector<std::uint64_t> lk(leaves.size());
  std::vector<double> lc(leaves.size());
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    lk[i] = leaves[i].key;
    lc[i] = leaves[i].cost;
  }
  const std::vector<int> owner = partition_cells(lk, lc, nranks);
  d.splitters = partition_splitters(lk, owner, nranks);
  const PartitionStats st = partition_stats(lc, owner, nranks);
  d.load = st.load;
  d.predicted_imbalance = st.imbalance;
  d.max_cell = st.max_cell;
  d.leaves = static_cast<std::int64_t>(leaves.size());
  return d;
}

}  // namespace qdemsph
