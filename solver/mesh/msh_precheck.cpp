#include "mesh/msh_precheck.hpp"

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace qdemsph {
namespace {

// Nodes per element of the Gmsh element types a mesh file commonly holds; 1 for others.
int nodes_of_type(long type) {
  switch (type) {
    case 1:
      return 2;  // line
    case 2:
      return 3;  // triangle
    case 3:
      return 4;  // quadrangle
    case 4:
      return 4;  // tetrahedron
    case 5:
      return 8;  // hexahedron
    case 6:
      return 6;  // prism
    case 7:
      return 5;  // pyramid
    case 8:
      return 3;  // 3-node line
    case 9:
      return 6;  // 6-node triangle
    case 11:
      return 10;  // 10-node tetrahedron
    default:
      return 1;
  }
}

class Reader {
 public:
  Reader(const std::filesystem::path& path) : in_(path), path_(path) {}
  bool next(std::vector<std::string>& tok) {
    std::string line;
    if (!std::getline(in_, line)) return false;
    ++line_no_;
    tok.clear();
    std::istringstream ss(line);
    for (std::string t; ss >> t;) tok.push_back(t);
    return true;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError("mesh file '" + path_.string() + "': truncated or corrupt: " + what +
                     " (line " + std::to_string(line_no_) + ")");
  }
  long number(const std::vector<std::string>& tok, std::size_t i, const char* what) const {
    if (i >= tok.size()) fail(std::string("missing ") + what);
    try {
      std::size_t used = 0;
      const long v = std::stol(tok[i], &used);
      if (used != tok[i].size() || v < 0) fail(std::string("bad ") + what + " '" + tok[i] + "'");
      return v;
    } catch (const std::logic_error&) {
      fail(std::string("bad ") + what + " '" + tok[i] + "'");
    }
  }
  // Reads `n` lines of at least `min_tokens` tokens each.
  void lines(long n, std::size_t min_tokens, const std::string& section) {
    std::vector<std::string> tok;
    for (long k = 0; k < n; ++k) {
      if (!next(tok))
        fail(section + " ends after " + std::to_string(k) + " of " + std::to_string(n) + " lines");
      if (tok.size() < min_tokens)
        fail(section + ": a line has " + std::to_string(tok.size()) +
             " fields, expected at least " + std::to_string(min_tokens));
    }
  }
  void expect_end(const std::string& end) {
    std::vector<std::string> tok;
    if (!next(tok) || tok.empty() || tok[0] != end)
      fail("expected " + end + " after the declared entries");
  }

 private:
  std::ifstream in_;
  std::filesystem::path path_;
  long line_no_ = 0;
};

void check_v2(Reader& r, bool nodes) {
  std::vector<std::string> tok;
  if (!r.next(tok)) r.fail(nodes ? "$Nodes has no count" : "$Elements has no count");
  const long n = r.number(tok, 0, "count");
  if (nodes) {
    r.lines(n, 4, "$Nodes");
  } else {
    for (long k = 0; k < n; ++k) {
      if (!r.next(tok))
        r.fail("$Elements ends after " + std::to_string(k) + " of " + std::to_string(n) +
               " elements");
      const long ntags = r.number(tok, 2, "tag count");
      const std::size_t need = 3 + ntags + nodes_of_type(r.number(tok, 1, "element type"));
      if (tok.size() < need) r.fail("$Elements: an element line is short");
    }
  }
  r.expect_end(nodes ? "$EndNodes" : "$EndElements");
}

void check_v4(Reader& r, bool nodes) {
  std::vector<std::string> tok;
  if (!r.next(tok)) r.fail("section header missing");
  const long blocks = r.number(tok, 0, "block count");
  for (long b = 0; b < blocks; ++b) {
    if (!r.next(tok))
      r.fail("block " + std::to_string(b) + " of " + std::to_string(blocks) + " missing");
    const long n = r.number(tok, 3, "entries in block");
    if (nodes) {
      const bool parametric = r.number(tok, 2, "parametric flag") != 0;
      r.lines(n, 1, "$Nodes tags");
      r.lines(n, parametric ? 4 : 3, "$Nodes coordinates");
    } else {
      r.lines(n, 1 + nodes_of_type(r.number(tok, 2, "element type")), "$Elements");
    }
  }
  r.expect_end(nodes ? "$EndNodes" : "$EndElements");
}

}  // namespace

void precheck_ascii_msh(const std::filesystem::path& path) {
  Reader r(path);
  std::vector<std::string> tok;
  if (!r.next(tok) || tok.empty() || tok[0] != "$MeshFormat") return;  // not MSH: libgmsh decides
  if (!r.next(tok) || tok.size() < 2) r.fail("$MeshFormat has no version line");
  if (tok[1] != "0") return;  // binary
  const bool v4 = !tok[0].empty() && tok[0][0] >= '4';
  while (r.next(tok)) {
    if (tok.empty()) continue;
    if (tok[0] == "$Nodes") v4 ? check_v4(r, true) : check_v2(r, true);
    if (tok[0] == "$Elements") v4 ? check_v4(r, false) : check_v2(r, false);
  }
}

}  // namespace qdemsph
