// Truncated or malformed ASCII Gmsh files are an InputError naming the file and the line,
// never a crash inside libgmsh (the fuzzer's reproducers in solver/fuzz/crashes once
// segfaulted libgmsh 4.8).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "mesh/gmsh_io.hpp"
#include "mesh/msh_precheck.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;

std::string error_of(const fs::path& p) {
  try {
    read_gmsh(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(MshPrecheck, FuzzerCrashReproducersAreInputErrors) {
  const fs::path dir = fs::path(QDEMSPH_TEST_DATA).parent_path().parent_path() / "fuzz" / "crashes";
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".msh") continue;
    ++n;
    const std::string msg = error_of(e.path());
    EXPECT_NE(msg.find(e.path().filename().string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated or corrupt"), std::string::npos) << msg;
  }
  EXPECT_GE(n, 1);
}

TEST(MshPrecheck, ShortElementSectionNamesTheLine) {
  const fs::path p = fs::temp_directory_path() / "qdemsph_precheck_short.msh";
  std::ofstream(p)
      << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n"
         "3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n2\n1 4 2 1 1 1 2 3 4\n$EndElements\n";
  const std::string msg = error_of(p);
  EXPECT_NE(msg.find("line 14"), std::string::npos) << msg;
  std::ofstream(p)
      << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n"
         "3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n";
  EXPECT_NO_THROW(precheck_ascii_msh(p));
}

}  // namespace
}  // namespace qdemsph
