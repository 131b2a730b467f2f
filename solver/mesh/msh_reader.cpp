#include "mesh/msh_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <numeric>
#include <utility>

#include "core/error.hpp"

namespace qdemsph {
namespace {

// Nodes of gmsh element type `t` (gmsh's GmshDefines.h); 0 for a type gmsh does not define.
int nodes_of_type(std::int64_t t) {
  static constexpr int n[] = {0, 2,  3,  4,  4, 8,  6,  5,  3,  6,  9, 10, 27, 18, 14, 1,
                              8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4, 5,  6,  20, 35, 56};
  if (t >= 0 && t < static_cast<std::int64_t>(std::size(n))) return n[t];
  if (t == 92) return 64;
  if (t == 93) return 125;
  return 0;
}

constexpr int kTet = 4;

// A read position in the file with located errors: "(line L)" in text, "(byte B)" in binary
// data (the line is computed only when an error is reported).
class Cursor {
 public:
  Cursor(std::string_view s, const std::string& source) : s_(s), source_(source) {}

  [[noreturn]] void fail(const std::string& why) const {
    std::string where;
    if (binary_) {
      where = "byte " + std::to_string(pos_);
    } else {
      const auto line = 1 + std::count(s_.begin(), s_.begin() + static_cast<long>(pos_), '\n');
      where = "line " + std::to_string(line);
    }
    throw InputError(source_ + ": truncated or corrupt: " + why + " (" + where + ")");
  }

  std::size_t left() const { return s_.size() - pos_; }
  void set_binary(bool b) { binary_ = b; }

  // The next whitespace-separated word; empty at the end of the file.
  std::string_view word() {
    while (pos_ < s_.size() && is_space(s_[pos_])) ++pos_;
    const std::size_t b = pos_;
    while (pos_ < s_.size() && !is_space(s_[pos_])) ++pos_;
    return s_.substr(b, pos_ - b);
  }
  std::string_view need_word(const char* what) {
    const std::string_view w = word();
    if (w.empty()) fail(std::string("file ends where ") + what + " was expected");
    return w;
  }
  template <class T>
  T integer(const char* what) {
    const std::string_view w = need_word(what);
    T v{};
    const auto r = std::from_chars(w.data(), w.data() + w.size(), v);
    if (r.ec != std::errc() || r.ptr != w.data() + w.size())
      fail(std::string("bad ") + what + " '" + printable(w) + "'");
    return v;
  }
  double real(const char* what) {
    std::string_view w = need_word(what);
    if (!w.empty() && w[0] == '+') w.remove_prefix(1);
    double v = 0;
    const auto r = std::from_chars(w.data(), w.data() + w.size(), v);
    if (r.ec != std::errc() || r.ptr != w.data() + w.size())
      fail(std::string("bad ") + what + " '" + printable(w) + "'");
    return v;
  }
  void expect(std::string_view tag) {
    const std::string_view w = word();
    if (w != tag)
      fail("expected " + std::string(tag) +
           (w.empty() ? ", found the end of the file" : ", found '" + printable(w) + "'"));
  }
  // The line break after a header line, before binary data.
  void end_of_line() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\r')) ++pos_;
    if (pos_ >= s_.size() || s_[pos_] != '\n') fail("expected a line break before binary data");
    ++pos_;
  }
  template <class T>
  T bin(const char* what) {
    if (left() < sizeof(T)) fail(std::string("file ends inside ") + what);
    T v;
    std::memcpy(&v, s_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  // A declared count of records of at least `bytes_each` bytes must fit in the rest.
  void fits(std::uint64_t count, std::uint64_t bytes_each, const std::string& what) const {
    if (bytes_each == 0) bytes_each = 1;
    if (count > left() / bytes_each)
      fail(what + ": " + std::to_string(count) + " declared, more than the " +
           std::to_string(left()) + " bytes left can hold");
  }
  // Moves past the line "$End<name>".
  void skip_section(std::string_view name) {
    const std::string end = "$End" + std::string(name);
    for (std::size_t p = pos_;;) {
      p = s_.find(end, p);
      if (p == std::string_view::npos) fail("section $" + std::string(name) + " has no " + end);
      const std::size_t q = p + end.size();
      if ((p == 0 || s_[p - 1] == '\n') && (q == s_.size() || is_space(s_[q]))) {
        pos_ = q;
        return;
      }
      p = q;
    }
  }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\f' || c == '\v';
  }
  static std::string printable(std::string_view w) {
    std::string s(w.substr(0, 40));
    for (char& c : s)
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
    return w.size() > 40 ? s + "..." : s;
  }

  std::string_view s_;
  const std::string& source_;
  std::size_t pos_ = 0;
  bool binary_ = false;
};

struct Reader {
  explicit Reader(Cursor cursor) : c(std::move(cursor)) {}
  Cursor c;
  bool binary = false;
  bool v4 = false;
  MshData out;
  std::vector<std::int64_t> tet_entity;  // per tet, for libgmsh's grouping

  void add_tet(std::size_t tag, std::int64_t entity, const std::size_t* nodes) {
    out.tet_tags.push_back(tag);
    out.tet_nodes.insert(out.tet_nodes.end(), nodes, nodes + 4);
    tet_entity.push_back(entity);
  }
  int element_nodes(std::int64_t type) {
    const int k = nodes_of_type(type);
    if (k == 0) c.fail("unknown element type " + std::to_string(type));
    return k;
  }

  void header() {
    c.expect("$MeshFormat");
    const std::string_view version = c.need_word("the MSH version");
    const int file_type = c.integer<int>("file type");
    const int data_size = c.integer<int>("data size");
    if (version == "4.1")
      v4 = true;
    else if (version.size() >= 1 && version[0] == '2' && (version.size() == 1 || version[1] == '.'))
      v4 = false;
    else if (version == "4" || version == "4.0")
      c.fail("MSH 4.0 is not supported; save the mesh as MSH 4.1 or 2.2");
    else
      c.fail("unsupported MSH version '" + std::string(version) + "' (2.x and 4.1 are read)");
    if (file_type != 0 && file_type != 1) c.fail("file type must be 0 (ASCII) or 1 (binary)");
    binary = file_type == 1;
    if (binary) {
      if (data_size != 8) c.fail("binary data size must be 8");
      c.end_of_line();
      c.set_binary(true);
      const auto one = c.bin<std::int32_t>("the endianness check");
      c.set_binary(false);
      if (one != 1)
        c.fail(one == 0x01000000 ? "big-endian binary files are not supported"
                                 : "bad endianness check in a binary file");
    }
    c.expect("$EndMeshFormat");
  }

  // ---------------------------------------------------------------- MSH 2
  void nodes_v2() {
    const auto n = c.integer<std::uint64_t>("node count");
    c.fits(n, binary ? 28 : 8, "$Nodes");
    out.node_tags.reserve(out.node_tags.size() + n);
    out.coords.reserve(out.coords.size() + 3 * n);
    if (binary) c.end_of_line();
    c.set_binary(binary);
    for (std::uint64_t k = 0; k < n; ++k) {
      if (binary) {
        const auto tag = c.bin<std::int32_t>("a node");
        if (tag <= 0) c.fail("node tag " + std::to_string(tag) + " is not positive");
        out.node_tags.push_back(static_cast<std::size_t>(tag));
        for (int d = 0; d < 3; ++d) out.coords.push_back(c.bin<double>("a node"));
      } else {
        out.node_tags.push_back(c.integer<std::size_t>("node tag"));
        for (int d = 0; d < 3; ++d) out.coords.push_back(c.real("node coordinate"));
      }
    }
    c.set_binary(false);
    c.expect("$EndNodes");
  }

  void elements_v2() {
    const auto n = c.integer<std::uint64_t>("element count");
    c.fits(n, binary ? 16 : 8, "$Elements");
    std::vector<std::int64_t> tags;
    std::size_t en[125];
    if (!binary) {
      for (std::uint64_t k = 0; k < n; ++k) {
        const auto tag = c.integer<std::size_t>("element tag");
        const auto type = c.integer<std::int64_t>("element type");
        const int nn = element_nodes(type);
        const auto nt = c.integer<std::uint64_t>("tag count");
        c.fits(nt, 2, "element tags");
        tags.resize(nt);
        for (auto& t : tags) t = c.integer<std::int64_t>("element tag");
        for (int q = 0; q < nn; ++q) en[q] = c.integer<std::size_t>("element node");
        if (type == kTet) add_tet(tag, nt > 1 ? tags[1] : 0, en);
      }
      c.expect("$EndElements");
      return;
    }
    c.end_of_line();
    c.set_binary(true);
    for (std::uint64_t done = 0; done < n;) {
      const auto type = c.bin<std::int32_t>("an element block header");
      const auto count = c.bin<std::int32_t>("an element block header");
      const auto nt = c.bin<std::int32_t>("an element block header");
      const int nn = element_nodes(type);
      if (count <= 0 || static_cast<std::uint64_t>(count) > n - done)
        c.fail("element block of " + std::to_string(count) + " elements, " +
               std::to_string(n - done) + " left to read");
      if (nt < 0) c.fail("negative tag count");
      const std::uint64_t ints = 1 + static_cast<std::uint64_t>(nt) + nn;
      c.fits(static_cast<std::uint64_t>(count), 4 * ints, "element block");
      tags.resize(nt);
      for (std::int32_t e = 0; e < count; ++e) {
        const auto tag = c.bin<std::int32_t>("an element");
        for (auto& t : tags) t = c.bin<std::int32_t>("an element");
        for (int q = 0; q < nn; ++q) {
          const auto v = c.bin<std::int32_t>("an element");
          if (v <= 0) c.fail("element node tag " + std::to_string(v) + " is not positive");
          en[q] = static_cast<std::size_t>(v);
        }
        if (type == kTet) add_tet(static_cast<std::size_t>(tag), nt > 1 ? tags[1] : 0, en);
      }
      done += static_cast<std::uint64_t>(count);
    }
    c.set_binary(false);
    c.expect("$EndElements");
  }

  // ---------------------------------------------------------------- MSH 4.1
  std::uint64_t size_value(const char* what) {
    return binary ? c.bin<std::uint64_t>(what) : c.integer<std::uint64_t>(what);
  }
  std::int64_t int_value(const char* what) {
    return binary ? c.bin<std::int32_t>(what) : c.integer<std::int64_t>(what);
  }

  void nodes_v4() {
    if (binary) {
      c.end_of_line();
      c.set_binary(true);
    }
    const auto blocks = size_value("$Nodes header");
    const auto n = size_value("$Nodes header");
    size_value("$Nodes header");  // min tag
    size_value("$Nodes header");  // max tag
    c.fits(blocks, binary ? 20 : 8, "$Nodes entity blocks");
    c.fits(n, binary ? 32 : 8, "$Nodes");
    out.node_tags.reserve(out.node_tags.size() + n);
    out.coords.reserve(out.coords.size() + 3 * n);
    std::uint64_t total = 0;
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const auto dim = int_value("node block header");
      int_value("node block header");  // entity tag
      const auto parametric = int_value("node block header");
      const auto m = size_value("node block header");
      if (dim < 0 || dim > 3)
        c.fail("entity dimension " + std::to_string(dim) + " of a node block");
      if (parametric != 0 && parametric != 1) c.fail("parametric flag must be 0 or 1");
      if (m > n - total)
        c.fail("node blocks hold more than the " + std::to_string(n) + " nodes declared");
      const int per = 3 + (parametric ? static_cast<int>(dim) : 0);
      c.fits(m, binary ? 8 + 8 * per : 2 + 2 * per, "node block");
      for (std::uint64_t k = 0; k < m; ++k) out.node_tags.push_back(size_value("node tag"));
      for (std::uint64_t k = 0; k < m; ++k)
        for (int d = 0; d < per; ++d) {
          const double x = binary ? c.bin<double>("node coordinates") : c.real("node coordinate");
          if (d < 3) out.coords.push_back(x);
        }
      total += m;
    }
    if (total != n)
      c.fail("node blocks hold " + std::to_string(total) + " nodes, the header declares " +
             std::to_string(n));
    c.set_binary(false);
    c.expect("$EndNodes");
  }

  void elements_v4() {
    if (binary) {
      c.end_of_line();
      c.set_binary(true);
    }
    const auto blocks = size_value("$Elements header");
    const auto n = size_value("$Elements header");
    size_value("$Elements header");  // min tag
    size_value("$Elements header");  // max tag
    c.fits(blocks, binary ? 20 : 8, "$Elements entity blocks");
    c.fits(n, binary ? 16 : 4, "$Elements");
    std::uint64_t total = 0;
    std::size_t en[125];
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const auto dim = int_value("element block header");
      const auto entity = int_value("element block header");
      const auto type = int_value("element block header");
      const auto m = size_value("element block header");
      const int nn = element_nodes(type);
      if (m > n - total)
        c.fail("element blocks hold more than the " + std::to_string(n) + " elements declared");
      c.fits(m, binary ? 8 * (1 + nn) : 2 * (1 + nn), "element block");
      if (type == kTet && m > 0 && dim != 3)
        c.fail("tetrahedra in an entity of dimension " + std::to_string(dim));
      for (std::uint64_t k = 0; k < m; ++k) {
        const auto tag = size_value("element tag");
        for (int q = 0; q < nn; ++q) en[q] = size_value("element node");
        if (type == kTet) add_tet(tag, entity, en);
      }
      total += m;
    }
    if (total != n)
      c.fail("element blocks hold " + std::to_string(total) + " elements, the header declares " +
             std::to_string(n));
    c.set_binary(false);
    c.expect("$EndElements");
  }

  // ---------------------------------------------------------------- file
  void file() {
    header();
    for (;;) {
      const std::string_view w = c.word();
      if (w.empty()) break;
      if (w[0] != '$')
        c.fail("expected a section ($Name), found '" + std::string(w.substr(0, 40)) + "'");
      if (w == "$Nodes")
        v4 ? nodes_v4() : nodes_v2();
      else if (w == "$Elements")
        v4 ? elements_v4() : elements_v2();
      else
        c.skip_section(w.substr(1));
    }
    // libgmsh keeps elements per entity and lists entities by ascending tag.
    std::vector<std::size_t> order(tet_entity.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return tet_entity[a] < tet_entity[b]; });
    MshData sorted;
    sorted.tet_tags.reserve(order.size());
    sorted.tet_nodes.reserve(4 * order.size());
    for (const std::size_t e : order) {
      sorted.tet_tags.push_back(out.tet_tags[e]);
      sorted.tet_nodes.insert(sorted.tet_nodes.end(), out.tet_nodes.begin() + 4 * e,
                              out.tet_nodes.begin() + 4 * e + 4);
    }
    out.tet_tags = std::move(sorted.tet_tags);
    out.tet_nodes = std::move(sorted.tet_nodes);
  }
};

}  // namespace

MshData parse_msh(std::string_view bytes, const std::string& source) {
  Reader r(Cursor(bytes, source));
  r.file();
  return std::move(r.out);
}

}  // namespace qdemsph
