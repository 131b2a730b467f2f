// qdemsph's .msh reader (mesh/msh_reader.hpp) against libgmsh's: identical nodes and tets on
// the fuzz corpus, the repository's meshes and meshes gmsh generates in every format (MSH
// 2.2 / 4.1, ASCII / binary); every malformed case an InputError naming the file and the line
// or byte, with allocation bounded by the file size (the fuzzer's reproducers once crashed or
// exhausted memory inside libgmsh 4.8).
#include <gmsh.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "mesh/gmsh_io.hpp"
#include "mesh/gmsh_session.hpp"
#include "mesh/msh_reader.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;

const fs::path kSolver = fs::path(QDEMSPH_TEST_DATA).parent_path().parent_path();
const fs::path kRepo = kSolver.parent_path();

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string error_of(const fs::path& p) {
  try {
    read_gmsh(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string parse_error(const std::string& bytes) {
  try {
    parse_gmsh(bytes, "mesh file 'x.msh'");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// The reference: what read_gmsh returned through libgmsh before qdemsph read .msh itself.
struct Library {
  bool ok = false;
  MshData d;
};
Library read_with_libgmsh(const fs::path& p) {
  Library r;
  GmshSession session;
  try {
    gmsh::model::add("reference");
    gmsh::merge(p.string());
    std::vector<double> param;
    gmsh::model::mesh::getNodes(r.d.node_tags, r.d.coords, param, -1, -1, false, false);
    gmsh::model::mesh::getElementsByType(4, r.d.tet_tags, r.d.tet_nodes);
    r.ok = true;
  } catch (...) {
  }
  try {
    gmsh::model::remove();
  } catch (...) {
  }
  return r;
}

// Ours equals libgmsh's: every node (tag -> coordinates, bit for bit) and the tets in order;
// and the TetMesh built from each is identical.
void expect_same_as_libgmsh(const fs::path& p) {
  SCOPED_TRACE(p.string());
  const Library lib = read_with_libgmsh(p);
  ASSERT_TRUE(lib.ok) << "libgmsh cannot read the reference file";
  const MshData ours = parse_msh(slurp(p), p.string());
  auto by_tag = [](const MshData& d) {
    std::vector<std::pair<std::size_t, std::array<double, 3>>> v;
    for (std::size_t i = 0; i < d.node_tags.size(); ++i)
      v.push_back({d.node_tags[i], {d.coords[3 * i], d.coords[3 * i + 1], d.coords[3 * i + 2]}});
    std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    return v;
  };
  const auto a = by_tag(ours), b = by_tag(lib.d);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first);
    ASSERT_EQ(std::memcmp(a[i].second.data(), b[i].second.data(), sizeof a[i].second), 0)
        << "node " << a[i].first;
  }
  EXPECT_EQ(ours.tet_tags, lib.d.tet_tags);
  EXPECT_EQ(ours.tet_nodes, lib.d.tet_nodes);
  const TetMesh m1 = read_gmsh(p);
  const TetMesh m2 =
      tet_mesh_from_gmsh(lib.d.node_tags, lib.d.coords, lib.d.tet_tags, lib.d.tet_nodes, "lib");
  EXPECT_EQ(m1.tets, m2.tets);
  ASSERT_EQ(m1.points.size(), m2.points.size());
  EXPECT_EQ(std::memcmp(m1.points.data(), m2.points.data(), m1.points.size() * sizeof(Vec3)), 0);
}

TEST(MshReader, SameAsGmshOnTheCorpusAndTheRepositoryMeshes) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(kSolver / "fuzz" / "corpus" / "fuzz_gmsh")) {
    if (e.path().filename().string().rfind("truncated", 0) == 0) continue;
    expect_same_as_libgmsh(e.path());
    ++n;
  }
  EXPECT_GE(n, 6);
  for (const char* f : {"solver/tests/data/scenes/good/meshes/tet.msh",
                        "verification/cases/cantilever_exact/beam.msh",
                        "verification/cases/hard_sliver/sliver_beam.msh"})
    expect_same_as_libgmsh(kRepo / f);
}

TEST(MshReader, SameAsGmshOnGeneratedMeshesInEveryFormat) {
  const fs::path dir = fs::temp_directory_path() / "qdemsph_msh_reader";
  fs::create_directories(dir);
  std::vector<fs::path> files;
  {
    GmshSession session;
    gmsh::model::add("generated");
    // Two volumes (two entities, shared interface), second-order points ignored: linear tets.
    gmsh::model::occ::addBox(0, 0, 0, 1, 0.5, 0.4);
    gmsh::model::occ::addSphere(1.2, 0.25, 0.2, 0.3);
    gmsh::model::occ::synchronize();
    gmsh::option::setNumber("Mesh.MeshSizeMax", 0.15);
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::model::mesh::generate(3);
    for (const double version : {2.2, 4.1})
      for (const int binary : {0, 1}) {
        gmsh::option::setNumber("Mesh.MshFileVersion", version);
        gmsh::option::setNumber("Mesh.Binary", binary);
        gmsh::option::setNumber("Mesh.SaveAll", 1);  // points, lines, triangles and tets
        files.push_back(dir / ("gen_" + std::to_string(version) + (binary ? "_bin" : "") + ".msh"));
        gmsh::write(files.back().string());
      }
    gmsh::option::setNumber("Mesh.Binary", 0);
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    gmsh::model::remove();
  }
  for (const auto& f : files) expect_same_as_libgmsh(f);
  // MSH 2.2 with tets of two entities interleaved: libgmsh groups them by entity tag.
  const fs::path mixed = dir / "interleaved22.msh";
  std::ofstream(mixed) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n"
                          "3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n$Elements\n3\n"
                          "10 4 2 0 7 1 2 3 4\n11 4 2 0 3 2 3 4 5\n12 4 2 0 7 1 2 4 5\n"
                          "$EndElements\n";
  expect_same_as_libgmsh(mixed);
  EXPECT_EQ(parse_msh(slurp(mixed), "m").tet_tags, (std::vector<std::size_t>{11, 10, 12}));
}

TEST(MshReader, FuzzerReproducersAreInputErrors) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(kSolver / "fuzz" / "crashes")) {
    if (e.path().extension() != ".msh") continue;
    ++n;
    const std::string msg = error_of(e.path());
    EXPECT_NE(msg.find(e.path().filename().string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated or corrupt"), std::string::npos) << msg;
  }
  EXPECT_GE(n, 2);
}

TEST(MshReader, ShortElementSectionNamesTheLine) {
  const std::string head =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n"
      "3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n";
  const std::string msg = parse_error(head + "2\n1 4 2 1 1 1 2 3 4\n$EndElements\n");
  EXPECT_NE(msg.find("bad element tag '$EndElements' (line 14)"), std::string::npos) << msg;
  EXPECT_EQ(parse_error(head + "1\n1 4 2 1 1 1 2 3 4\n$EndElements\n"), "(no error)");
}

// Every malformed case: the message names the file, the reason and the line (or byte).
TEST(MshReader, MalformedFilesAreLocatedInputErrors) {
  const std::string v22 =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
      "$EndNodes\n$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n";
  auto with = [&v22](const std::string& from, const std::string& to) {
    std::string s = v22;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  const std::pair<std::string, std::string> cases[] = {
      {"garbage", "expected $MeshFormat, found 'garbage' (line 1)"},
      {with("2.2 0 8", "4.0 0 8"), "MSH 4.0 is not supported"},
      {with("2.2 0 8", "3 0 8"), "unsupported MSH version '3'"},
      {with("2.2 0 8", "2.2 2 8"), "file type must be 0 (ASCII) or 1 (binary) (line 2)"},
      {with("2.2 0 8", "2.2 1 4"), "binary data size must be 8"},
      {with("$Nodes\n4\n", "$Nodes\n4000000000\n"), "$Nodes: 4000000000 declared, more than"},
      {with("3 0 1 0", "3 0 one 0"), "bad node coordinate 'one' (line 8)"},
      {with("1 4 2 1 1", "1 99 2 1 1"), "unknown element type 99 (line 13)"},
      {with("$EndNodes", "$EndNodez"), "expected $EndNodes, found '$EndNodez' (line 10)"},
      {with("$Elements\n1\n", "$Elements\n-1\n"), "bad element count '-1' (line 12)"},
      {v22 + "$Comments\nno end\n", "section $Comments has no $EndComments"},
      {v22 + "stray\n", "expected a section ($Name), found 'stray' (line 15)"},
      {with("1 0 0 0\n2", "2 0 0 0\n2"), "node tag 2 is defined twice"},
      {with("1 1 2 3 4\n", "1 1 2 3 7\n"), "refers to missing node 7"},
  };
  for (const auto& [text, needle] : cases) {
    const std::string msg = parse_error(text);
    EXPECT_NE(msg.find("mesh file 'x.msh': "), std::string::npos) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << "expected '" << needle << "' in: " << msg;
  }
  EXPECT_EQ(parse_error(v22), "(no error)");
}

// Binary files: truncation anywhere and absurd counts are errors located by byte offset, found
// before anything of that size is allocated.
TEST(MshReader, BinaryTruncationAndHugeCountsAreBounded) {
  for (const char* name : {"cube22bin.msh", "cube41bin.msh"}) {
    const std::string bytes = slurp(kSolver / "fuzz" / "corpus" / "fuzz_gmsh" / name);
    ASSERT_NO_THROW(parse_gmsh(bytes, name));
    for (std::size_t cut = 40; cut < bytes.size(); cut += 37) {
      std::string msg;
      try {
        parse_gmsh(bytes.substr(0, cut), name);
      } catch (const InputError& e) {
        msg = e.what();
      }
      // A cut between sections leaves a well-formed file without tets.
      EXPECT_TRUE(msg.find("truncated or corrupt") != std::string::npos ||
                  msg.find("no linear tetrahedra") != std::string::npos)
          << name << " cut at " << cut << ": " << msg;
    }
  }
  // MSH 4.1 binary whose $Nodes header declares 2^60 nodes in 2^60 blocks: refused at once.
  std::string huge = "$MeshFormat\n4.1 1 8\n";
  const std::int32_t one = 1;
  huge.append(reinterpret_cast<const char*>(&one), 4);
  huge += "\n$EndMeshFormat\n$Nodes\n";
  const std::uint64_t header[4] = {1ull << 60, 1ull << 60, 1, 1ull << 60};
  huge.append(reinterpret_cast<const char*>(header), sizeof header);
  const std::string msg = parse_error(huge);
  EXPECT_NE(msg.find("declared, more than the 0 bytes left can hold (byte "), std::string::npos)
      << msg;
  // Big-endian files say so.
  std::string be = "$MeshFormat\n2.2 1 8\n";
  const std::int32_t swapped = 0x01000000;
  be.append(reinterpret_cast<const char*>(&swapped), 4);
  be += "\n$EndMeshFormat\n";
  EXPECT_NE(parse_error(be).find("big-endian"), std::string::npos) << parse_error(be);
}

}  // namespace
}  // namespace qdemsph
