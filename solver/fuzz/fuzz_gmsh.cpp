// libFuzzer target: the Gmsh .msh reader (mesh/gmsh_io.hpp: read_gmsh, which goes through
// the gmsh library and then tet_mesh_from_gmsh).
//
// Input: arbitrary bytes written to a private temporary .msh file that read_gmsh then reads.
// read_gmsh must return a TetMesh (every tet positively oriented, indices in range) or throw
// InputError; any other exception, a crash, a sanitizer report, a hang or a leak is a finding.
// The gmsh library itself is not instrumented (Debian's libgmsh): coverage guidance sees
// only qdemsph's code, but ASan still catches invalid accesses of our code and allocation
// failures anywhere. One GmshSession is held for the whole process so that gmsh is
// initialised once, not per input.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "mesh/gmsh_io.hpp"

namespace {

const std::filesystem::path& temp_path() {
  static const std::filesystem::path p =
      std::filesystem::temp_directory_path() /
      ("qdemsph_fuzz_gmsh_" + std::to_string(::getpid()) + ".msh");
  return p;
}

struct Cleanup {
  ~Cleanup() {
    std::error_code ec;
    std::filesystem::remove(temp_path(), ec);
  }
};

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
  static qdemsph::GmshSession session;  // keeps gmsh initialised across inputs
  static Cleanup cleanup;
  {
    std::FILE* f = std::fopen(temp_path().c_str(), "wb");
    if (!f) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
  }
  try {
    const qdemsph::TetMesh m = qdemsph::read_gmsh(temp_path());
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
    std::fprintf(stderr, "fuzz_gmsh: exception other than InputError escaped read_gmsh: %s\n",
                 e.what());
    std::abort();
  }
  return 0;
}
