// Prints what the C++ space-filling-curve, cell-tree and partition code gives for inputs
// read from stdin, so that tests/test_sfc.py can compare the Python twin (scaling/sfc.py).
//   keys   CURVE ORDER N  then N lines "x y z"            -> N keys
//   refine CURVE ORDER MAXCOST MINLEVEL N then N "key cost" -> leaves "key span level cost"
//   part   NRANKS N  then N "key cost"                    -> N owners, then nranks+1 splitters
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "parallel/cell_tree.hpp"
#include "parallel/partition.hpp"
#include "parallel/sfc.hpp"

using namespace qdemsph;

static Curve curve_of(const std::string& s) {
  return s == "morton" ? Curve::Morton : s == "peano" ? Curve::Peano : Curve::Hilbert;
}

int main() {
  std::string cmd;
  std::cout.precision(17);
  while (std::cin >> cmd) {
    if (cmd == "keys") {
      std::string c;
      int order;
      std::size_t n;
      std::cin >> c >> order >> n;
      for (std::size_t i = 0; i < n; ++i) {
        std::uint32_t x, y, z;
        std::cin >> x >> y >> z;
        std::cout << sfc_key(curve_of(c), x, y, z, order) << "\n";
      }
    } else if (cmd == "refine") {
      std::string c;
      int order, min_level;
      double max_cost;
      std::size_t n;
      std::cin >> c >> order >> max_cost >> min_level >> n;
      std::vector<std::uint64_t> k(n);
      std::vector<double> w(n);
      for (std::size_t i = 0; i < n; ++i) std::cin >> k[i] >> w[i];
      for (const auto& t : refine_cells(curve_of(c), order, k, w, max_cost, min_level))
        std::cout << t.key << " " << t.span << " " << t.level << " " << t.cost << "\n";
    } else if (cmd == "part") {
      int nranks;
      std::size_t n;
      std::cin >> nranks >> n;
      std::vector<std::uint64_t> k(n);
      std::vector<double> w(n);
      for (std::size_t i = 0; i < n; ++i) std::cin >> k[i] >> w[i];
      const auto owner = partition_cells(k, w, nranks);
      for (int o : owner) std::cout << o << "\n";
      for (auto s : partition_splitters(k, owner, nranks)) std::cout << s << "\n";
    }
  }
  return 0;
}
