// libFuzzer target: the Gmsh .msh reader (mesh/gmsh_io.hpp: parse_gmsh = read_gmsh on bytes:
// mesh/msh_reader.cpp, then tet_mesh_from_gmsh). No gmsh library is involved.
//
// Input: the bytes of a .msh file. parse_gmsh must return a TetMesh (every tet positively
// oriented, indices in range) or throw InputError; any other exception, a crash, a sanitizer
// report, a hang, a leak or an allocation beyond the RSS limit is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string_view>

#include "core/error.hpp"
#include "mesh/gmsh_io.hpp"

namespace {

double volume(const qdemsph::TetMesh& m, std::size_t t) {
  const auto& v = m.tets[t];
  const qdemsph::Vec3 a = m.points[v[1]] - m.points[v[0]];
  const qdemsph::Vec3 b = m.points[v[2]] - m.points[v[0]];
  const qdemsph::Vec3 c = m.points[v[3]] - m.points[v[0]];
  return a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) +
         a.z * (b.x * c.y - b.y * c.x);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    const qdemsph::TetMesh m = qdemsph::parse_gmsh(bytes, "mesh file 'fuzz.msh'");
    // The contract: indices in range, every tet positively oriented.
    for (std::size_t t = 0; t < m.tets.size(); ++t) {
      for (int k = 0; k < 4; ++k)
        if (m.tets[t][k] < 0 || static_cast<std::size_t>(m.tets[t][k]) >= m.points.size()) {
          std::fprintf(stderr, "fuzz_gmsh: tet %zu has an out-of-range vertex index\n", t);
          std::abort();
        }
      if (!(volume(m, t) > 0)) {
        std::fprintf(stderr, "fuzz_gmsh: tet %zu is not positively oriented\n", t);
        std::abort();
      }
    }
  } catch (const qdemsph::InputError&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_gmsh: exception other than InputError escaped parse_gmsh: %s\n",
                 e.what());
    std::abort();
  }
  return 0;
}
