// Scene parsing and validation (see scene_yaml.hpp for the error-message contract).
//
// Structure: a Context knows the file and the overrides (to say where a value came from);
// a Field is one YAML value plus its key path and converts itself to typed values, failing
// with a located message; a MapView checks a mapping's keys against the allowed set (unknown
// keys, duplicates) and hands out Fields. The section parsers at the bottom read the layout
// documented in docs/scene-format.md top-down.
#include "io/scene_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "core/error.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> split(std::string_view s, char sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t pos = s.find(sep, start);
    parts.emplace_back(s.substr(start, pos == std::string_view::npos ? s.npos : pos - start));
    if (pos == std::string_view::npos) return parts;
    start = pos + 1;
  }
}

std::string join(const std::vector<std::string>& items, std::string_view sep = ", ") {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? std::string(sep) : "") + items[i];
  return out;
}

// Edit distance counting a swap of adjacent letters as one edit (the commonest typo).
size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min(
          {d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1] ? 1 : 0)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// "; did you mean 'x'?" when one candidate is close enough to be a plausible typo.
std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates) {
  // Short words are close to everything: "file" is 2 edits from "size". Allow more edits
  // only as the word grows.
  const size_t max_d = word.size() <= 2 ? 0 : word.size() <= 5 ? 1 : word.size() <= 10 ? 2 : 3;
  const std::string* best = nullptr;
  size_t best_d = max_d + 1;
  for (const auto& c : candidates) {
    const size_t d = edit_distance(word, c);
    if (d < best_d) best = &c, best_d = d;
  }
  return best ? "; did you mean '" + *best + "'?" : "";
}

std::string render(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  std::string s;
  if (node.IsScalar()) {
    s = node.Scalar();
    if (s.empty()) s = "''";
  } else {
    // One line: force flow style on a copy (nodes keep the block style they were read with).
    YAML::Node copy = YAML::Clone(node);
    std::vector<YAML::Node> todo{copy};
    while (!todo.empty()) {
      YAML::Node n = todo.back();
      todo.pop_back();
      n.SetStyle(YAML::EmitterStyle::Flow);
      if (n.IsSequence())
        for (const auto& c : n) todo.push_back(c);
      else if (n.IsMap())
        for (const auto& kv : n) todo.push_back(kv.second);
    }
    YAML::Emitter e;
    e << copy;
    s = e.c_str();
  }
  return s.size() > 80 ? s.substr(0, 77) + "..." : s;
}

struct Override {
  std::string text;
  std::vector<std::string> path;
};

class Context {
 public:
  Context(std::string file, fs::path folder) : file_(std::move(file)), folder_(std::move(folder)) {}

  const fs::path& folder() const { return folder_; }
  void add_override(Override o) { overrides_.push_back(std::move(o)); }

  // Values set by an override carry no useful line: name the override instead. The latest
  // override whose path is a prefix of `path` set the value. A node without a mark (a map an
  // override created on its way down) is blamed on the latest override below its parent.
  std::string where(const YAML::Node& node, const std::string& path) const {
    auto is_prefix = [](const std::vector<std::string>& a, const std::vector<std::string>& b) {
      return a.size() <= b.size() && std::equal(a.begin(), a.end(), b.begin());
    };
    std::vector<std::string> parts = path.empty() ? std::vector<std::string>{} : split(path, '.');
    for (auto o = overrides_.rbegin(); o != overrides_.rend(); ++o)
      if (is_prefix(o->path, parts)) return file_ + ": override '" + o->text + "'";
    const YAML::Mark m = node.IsDefined() ? node.Mark() : YAML::Mark::null_mark();
    if (!m.is_null()) return file_ + ":" + std::to_string(m.line + 1);
    if (!parts.empty()) parts.pop_back();
    for (auto o = overrides_.rbegin(); o != overrides_.rend(); ++o)
      if (is_prefix(parts, o->path)) return file_ + ": override '" + o->text + "'";
    return file_;
  }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& path, const std::string& rule,
                         bool show_value = true) const {
    std::string msg =
        where(node, path) + ": " + (path.empty() ? "(top level)" : path) + ": " + rule;
    if (show_value) msg += " (got " + render(node) + ")";
    throw InputError(msg);
  }

 private:
  std::string file_;
  fs::path folder_;
  std::vector<Override> overrides_;
};

// One value of the scene tree, with its key path for messages.
class Field {
 public:
  Field(const Context& ctx, YAML::Node node, std::string path)
      : ctx_(&ctx), node_(std::move(node)), path_(std::move(path)) {}

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& rule, bool show_value = true) const {
    ctx_->fail(node_, path_, rule, show_value);
  }

  double number() const {
    if (!node_.IsScalar()) fail("expected a number");
    const std::string& s = node_.Scalar();
    // YAML spells infinities and NaN .inf/.nan; name the rule rather than "not a number".
    if (s.find(".inf") != s.npos || s.find(".nan") != s.npos || s.find(".NaN") != s.npos ||
        s.find(".Inf") != s.npos || s.find(".INF") != s.npos || s.find(".NAN") != s.npos)
      fail("must be a finite number");
    double v = 0;
    const char* begin = s.data() + (!s.empty() && s[0] == '+' ? 1 : 0);
    const auto [end, ec] = std::from_chars(begin, s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty()) fail("expected a number");
    if (!std::isfinite(v)) fail("must be a finite number");
    return v;
  }
  template <class Pred>
  double number(Pred ok, const std::string& rule) const {
    const double v = number();
    if (!ok(v)) fail(rule);
    return v;
  }
  // Integers may be written as 1e6: any finite number with an integral value within range.
  long integer(long lo, long hi) const {
    const double v = number();
    if (v != std::floor(v)) fail("expected an integer");
    if (v < static_cast<double>(lo) || v > static_cast<double>(hi))
      fail(hi == std::numeric_limits<long>::max()
               ? "must be >= " + std::to_string(lo)
               : "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<long>(v);
  }
  bool boolean() const {
    if (node_.IsScalar()) {
      std::string s = node_.Scalar();
      std::transform(s.begin(), s.end(), s.begin(),
                     [](unsigned char c) { return std::tolower(c); });
      if (s == "true") return true;
      if (s == "false") return false;
    }
    fail("expected true or false");
  }
  std::string string() const {
    if (!node_.IsScalar()) fail("expected a string");
    return node_.Scalar();
  }
  std::string name() const {
    const std::string s = string();
    if (s.empty()) fail("must not be empty");
    return s;
  }
  std::string choice(const std::vector<std::string>& allowed) const {
    const std::string s = string();
    if (std::find(allowed.begin(), allowed.end(), s) == allowed.end())
      fail("must be one of " + join(allowed) + did_you_mean(s, allowed));
    return s;
  }
  Field element(size_t i) const { return {*ctx_, node_[i], path_ + "." + std::to_string(i)}; }
  void expect_list(size_t n, const char* what) const {
    if (!node_.IsSequence() || node_.size() != n)
      fail("expected a list of " + std::to_string(n) + " " + what);
  }
  Vec3 vec3() const {
    expect_list(3, "numbers");
    return {element(0).number(), element(1).number(), element(2).number()};
  }
  std::array<int, 3> int3(long lo, long hi) const {
    expect_list(3, "integers");
    std::array<int, 3> r{};
    for (size_t i = 0; i < 3; ++i) r[i] = static_cast<int>(element(i).integer(lo, hi));
    return r;
  }
  std::vector<Field> list() const {
    if (!node_.IsSequence()) fail("expected a list");
    std::vector<Field> items;
    for (size_t i = 0; i < node_.size(); ++i) items.push_back(element(i));
    return items;
  }

 private:
  const Context* ctx_;
  YAML::Node node_;
  std::string path_;
};

// A mapping checked against its allowed keys. Empty values (null) count as absent, so that
// `constraints:` with nothing under it means "none" and `dt:` means "automatic".
class MapView {
 public:
  MapView(const Context& ctx, const Field& f, std::vector<std::string> allowed)
      : ctx_(&ctx), node_(f.node()), path_(f.path()) {
    if (!node_.IsMap()) f.fail("expected a mapping of keys to values");
    std::map<std::string, YAML::Node> seen;
    for (const auto& kv : node_) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : render(kv.first);
      const std::string kpath = sub(key);
      if (!kv.first.IsScalar()) ctx.fail(kv.first, kpath, "keys must be plain names", false);
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
        ctx.fail(kv.first, kpath,
                 "unknown key" + did_you_mean(key, allowed) + " (allowed: " + join(allowed) + ")",
                 false);
      if (auto it = seen.find(key); it != seen.end())
        ctx.fail(kv.first, kpath,
                 "duplicate key (first at line " + std::to_string(it->second.Mark().line + 1) + ")",
                 false);
      seen.emplace(key, kv.first);
      values_.emplace_back(key, kv.second);
    }
  }

  std::string sub(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  std::optional<Field> opt(const std::string& key) const {
    for (const auto& [k, v] : values_)
      if (k == key && !v.IsNull()) return Field(*ctx_, v, sub(key));
    return std::nullopt;
  }
  Field req(const std::string& key) const {
    if (auto f = opt(key)) return *f;
    ctx_->fail(node_, sub(key), "required key is missing", false);
  }
  bool has(const std::string& key) const { return opt(key).has_value(); }
  // The map's own keys in file order (used by `materials`, a name -> spec map).
  const std::vector<std::pair<std::string, YAML::Node>>& entries() const { return values_; }

 private:
  const Context* ctx_;
  YAML::Node node_;
  std::string path_;
  std::vector<std::pair<std::string, YAML::Node>> values_;
};

// ---------------------------------------------------------------------------------------
// Overrides

void apply_override(Context& ctx, YAML::Node& root, const std::string& text) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("override '" + text + "': expected key.path=value");
  const std::string key = text.substr(0, eq);
  const std::vector<std::string> path = split(key, '.');
  for (const auto& p : path)
    if (p.empty()) throw InputError("override '" + text + "': empty component in key path");
  YAML::Node value;
  try {
    value = YAML::Load(text.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw InputError("override '" + text + "': value is not valid YAML: " + e.msg);
  }
  auto bad = [&](size_t i, const std::string& why) -> InputError {
    std::vector<std::string> prefix(path.begin(), path.begin() + static_cast<long>(i) + 1);
    return InputError("override '" + text + "': " + join(prefix, ".") + ": " + why);
  };
  YAML::Node cur = root;
  for (size_t i = 0; i < path.size(); ++i) {
    const bool last = i + 1 == path.size();
    YAML::Node next;
    if (cur.IsSequence()) {
      size_t idx = 0;
      const auto [end, ec] = std::from_chars(path[i].data(), path[i].data() + path[i].size(), idx);
      if (ec != std::errc() || end != path[i].data() + path[i].size())
        throw bad(i, "a list is indexed by a number");
      if (idx > cur.size() || (idx == cur.size() && !last))
        throw bad(i, "index out of range (list has " + std::to_string(cur.size()) + " items)");
      if (last) {
        if (idx == cur.size())
          cur.push_back(value);
        else
          cur[idx] = value;
        break;
      }
      next = cur[idx];
    } else if (cur.IsMap() || cur.IsNull()) {
      if (last) {
        cur[path[i]] = value;
        break;
      }
      if (!cur[path[i]] || cur[path[i]].IsNull()) cur[path[i]] = YAML::Node(YAML::NodeType::Map);
      next = cur[path[i]];
    } else {
      throw bad(i - 1, "is a single value; cannot set a key inside it");
    }
    cur.reset(next);  // rebind; plain assignment would overwrite the node's content
  }
  ctx.add_override({text, path});
}

// ---------------------------------------------------------------------------------------
// Sections

bool positive(double v) { return v > 0; }
bool non_negative(double v) { return v >= 0; }

template <class Spec>
int lookup(const Field& f, const std::vector<Spec>& specs, const char* what, const char* whats) {
  const std::string name = f.string();
  std::vector<std::string> names;
  for (size_t i = 0; i < specs.size(); ++i) {
    if (specs[i].name == name) return static_cast<int>(i);
    names.push_back(specs[i].name);
  }
  f.fail(std::string("unknown ") + what + " '" + name + "'" + did_you_mean(name, names) + " (" +
             whats + ": " + join(names) + ")",
         false);
}

RunSpec parse_run(const Context& ctx, const Field& f) {
  const MapView m(ctx, f, {"mode", "end_time", "dt", "dt_safety", "backend", "threads", "static"});
  RunSpec r;
  if (auto v = m.opt("mode"))
    r.mode = v->choice({"dynamic", "static"}) == "static" ? RunMode::Static : RunMode::Dynamic;
  // A dynamic run has no natural length: a silent default would waste a run, so require it.
  if (r.mode == RunMode::Dynamic)
    r.end_time = m.req("end_time").number(positive, "must be > 0");
  else if (auto v = m.opt("end_time"))
    r.end_time = v->number(positive, "must be > 0");
  if (auto v = m.opt("dt")) r.dt = v->number(positive, "must be > 0");
  if (auto v = m.opt("dt_safety"))
    r.dt_safety = v->number([](double x) { return x > 0 && x <= 1; }, "must be in (0, 1]");
  if (auto v = m.opt("backend")) r.backend = v->choice({"cpu", "cuda"});
  if (auto v = m.opt("threads")) r.threads = static_cast<int>(v->integer(0, 4096));
  if (auto v = m.opt("static")) {
    const MapView s(ctx, *v, {"tolerance", "max_steps"});
    if (auto t = s.opt("tolerance")) r.static_tolerance = t->number(positive, "must be > 0");
    if (auto t = s.opt("max_steps"))
      r.static_max_steps = t->integer(1, std::numeric_limits<long>::max());
  }
  return r;
}

MaterialSpec parse_material(const Context& ctx, const std::string& name, const Field& f) {
  const MapView m(ctx, f, {"law", "E", "nu", "density", "viscosity"});
  MaterialSpec mat;
  mat.name = name;
  if (auto v = m.opt("law"))
    mat.law = v->choice({"linear", "svk"}) == "linear" ? MaterialLaw::Linear
                                                       : MaterialLaw::StVenantKirchhoff;
  mat.E = m.req("E").number(positive, "must be > 0");
  mat.nu = m.req("nu").number([](double x) { return x > -1 && x < 0.5; }, "must be in (-1, 0.5)");
  mat.density = m.req("density").number(positive, "must be > 0");
  if (auto v = m.opt("viscosity")) mat.viscosity = v->number(non_negative, "must be >= 0");
  return mat;
}

// `rotate: {axis, angle}` of a box or shogi mesh or a fluid box (degrees, right-handed).
RotationSpec parse_rotate(const Context& ctx, const Field& f) {
  const MapView r(ctx, f, {"axis", "angle"});
  const Field axis = r.req("axis");
  RotationSpec rot;
  rot.axis = axis.vec3();
  if (!(norm(rot.axis) > 0)) axis.fail("must not be the zero vector");
  rot.angle = r.req("angle").number();
  return rot;
}

MeshSpec parse_mesh(const Context& ctx, const Field& f) {
  if (!f.node().IsMap()) f.fail("expected a mapping of keys to values");
  const Field type(ctx, f.node()["type"], f.path() + ".type");
  if (!type.node().IsDefined() || type.node().IsNull())
    ctx.fail(f.node(), type.path(), "required key is missing", false);
  MeshSpec mesh;
  const std::string kind = type.choice({"box", "gmsh", "shogi"});
  if (kind == "shogi") {
    const MapView m(ctx, f, {"type", "piece", "mesh_size", "translate", "rotate"});
    mesh.kind = MeshSpec::Kind::Shogi;
    if (auto v = m.opt("piece"))
      mesh.piece =
          v->choice({"king", "rook", "bishop", "gold", "silver", "knight", "lance", "pawn"});
    if (auto v = m.opt("mesh_size")) mesh.mesh_size = v->number(positive, "must be > 0");
    if (auto v = m.opt("translate")) mesh.translate = v->vec3();
    if (auto v = m.opt("rotate")) mesh.rotate = parse_rotate(ctx, *v);
  } else if (kind == "box") {
    const MapView m(ctx, f, {"type", "origin", "size", "cells", "rotate"});
    mesh.kind = MeshSpec::Kind::Box;
    if (auto v = m.opt("rotate")) mesh.rotate = parse_rotate(ctx, *v);
    if (auto v = m.opt("origin")) mesh.origin = v->vec3();
    const Field size = m.req("size");
    mesh.size = size.vec3();
    for (int a = 0; a < 3; ++a)
      if (!(mesh.size[a] > 0)) size.element(a).fail("must be > 0");
    const Field cells = m.req("cells");
    mesh.cells = cells.int3(1, 1 << 20);
    // 12 tets per hex, indexed by int32 (TetMesh): refuse sizes that would overflow.
    const double tets = 12.0 * mesh.cells[0] * mesh.cells[1] * mesh.cells[2];
    if (tets >= 2147483647.0) cells.fail("12 * cx * cy * cz tets must fit in 32-bit indices");
  } else {
    const MapView m(ctx, f, {"type", "file", "scale", "translate"});
    mesh.kind = MeshSpec::Kind::Gmsh;
    const Field file = m.req("file");
    const fs::path rel = file.name();
    mesh.file = (rel.is_absolute() ? rel : fs::absolute(ctx.folder() / rel)).lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(mesh.file, ec))
      file.fail("mesh file does not exist: " + mesh.file.string());
    if (auto v = m.opt("scale")) mesh.scale = v->number(positive, "must be > 0");
    if (auto v = m.opt("translate")) mesh.translate = v->vec3();
  }
  return mesh;
}

BodySpec parse_body(const Context& ctx, const Field& f, const std::vector<MaterialSpec>& mats) {
  const MapView m(ctx, f, {"name", "material", "mesh", "velocity", "angular_velocity", "fixed"});
  BodySpec b;
  b.name = m.req("name").name();
  b.material = lookup(m.req("material"), mats, "material", "materials");
  b.mesh = parse_mesh(ctx, m.req("mesh"));
  if (auto v = m.opt("velocity")) b.velocity = v->vec3();
  if (auto v = m.opt("angular_velocity")) b.angular_velocity = v->vec3();
  if (auto v = m.opt("fixed")) b.fixed = v->boolean();
  return b;
}

Region parse_region(const Context& ctx, const Field& f) {
  const MapView m(ctx, f, {"x", "y", "z"});
  Region r;
  const char* axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (auto v = m.opt(axes[a])) {
      v->expect_list(2, "numbers [lo, hi]");
      r.range[a] = {v->element(0).number(), v->element(1).number()};
      if (r.range[a][0] > r.range[a][1]) v->fail("range must have lo <= hi");
    }
  }
  return r;
}

ConstraintSpec parse_constraint(const Context& ctx, const Field& f,
                                const std::vector<BodySpec>& bodies) {
  const Field type(ctx, f.node().IsMap() ? f.node()["type"] : YAML::Node(), f.path() + ".type");
  if (!f.node().IsMap()) f.fail("expected a mapping of keys to values");
  if (!type.node().IsDefined() || type.node().IsNull())
    ctx.fail(f.node(), type.path(), "required key is missing", false);
  ConstraintSpec c;
  if (type.choice({"fixed", "velocity"}) == "fixed") {
    const MapView m(ctx, f, {"type", "body", "region", "components"});
    c.kind = ConstraintSpec::Kind::Fixed;
    c.body = lookup(m.req("body"), bodies, "body", "bodies");
    c.region = parse_region(ctx, m.req("region"));
    if (auto v = m.opt("components")) {
      const std::vector<Field> list = v->list();
      if (list.empty()) v->fail("name at least one of x, y, z");
      c.components = {false, false, false};
      for (const Field& e : list) {
        const int a = e.choice({"x", "y", "z"})[0] - 'x';
        if (c.components[a]) e.fail("named twice");
        c.components[a] = true;
      }
    }
  } else {
    const MapView m(ctx, f, {"type", "body", "region", "velocity"});
    c.kind = ConstraintSpec::Kind::Velocity;
    c.body = lookup(m.req("body"), bodies, "body", "bodies");
    c.region = parse_region(ctx, m.req("region"));
    c.velocity = m.req("velocity").vec3();
  }
  return c;
}

LoadSpec parse_load(const Context& ctx, const Field& f, const std::vector<BodySpec>& bodies) {
  if (!f.node().IsMap()) f.fail("expected a mapping of keys to values");
  const Field type(ctx, f.node()["type"], f.path() + ".type");
  if (!type.node().IsDefined() || type.node().IsNull())
    ctx.fail(f.node(), type.path(), "required key is missing", false);
  LoadSpec l;
  if (type.choice({"traction", "point"}) == "traction") {
    const MapView m(ctx, f, {"type", "body", "region", "traction", "preload"});
    l.kind = LoadSpec::Kind::Traction;
    l.body = lookup(m.req("body"), bodies, "body", "bodies");
    l.region = parse_region(ctx, m.req("region"));
    l.traction = m.req("traction").vec3();
    if (auto v = m.opt("preload")) l.preload = v->boolean();
  } else {
    const MapView m(ctx, f, {"type", "body", "at", "force", "preload"});
    l.kind = LoadSpec::Kind::Point;
    l.body = lookup(m.req("body"), bodies, "body", "bodies");
    l.point = m.req("at").vec3();
    l.force = m.req("force").vec3();
    if (auto v = m.opt("preload")) l.preload = v->boolean();
  }
  return l;
}

ProbeSpec parse_probe(const Context& ctx, const Field& f, const std::vector<BodySpec>& bodies) {
  if (!f.node().IsMap()) f.fail("expected a mapping of keys to values");
  const Field type(ctx, f.node()["type"], f.path() + ".type");
  if (!type.node().IsDefined() || type.node().IsNull())
    ctx.fail(f.node(), type.path(), "required key is missing", false);
  ProbeSpec p;
  const bool disp = type.choice({"displacement", "com"}) == "displacement";
  const MapView m(ctx, f,
                  disp ? std::vector<std::string>{"name", "type", "body", "region"}
                       : std::vector<std::string>{"name", "type", "body"});
  p.kind = disp ? ProbeSpec::Kind::Displacement : ProbeSpec::Kind::CentreOfMass;
  const Field name = m.req("name");
  p.name = name.name();
  // Probe names become CSV column names (<name>_x): keep them free of separators and quotes.
  for (char c : p.name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      name.fail("may contain only letters, digits, '_', '-' and '.'");
  p.body = lookup(m.req("body"), bodies, "body", "bodies");
  if (disp) {
    if (auto v = m.opt("region")) p.region = parse_region(ctx, *v);
  }
  return p;
}

FluidBoxSpec parse_fluid_box(const Context& ctx, const Field& f, bool tank) {
  const MapView m(ctx, f,
                  tank ? std::vector<std::string>{"min", "max", "thickness_layers"}
                       : std::vector<std::string>{"min", "max", "rotate"});
  FluidBoxSpec b;
  if (!tank)
    if (auto v = m.opt("rotate")) b.rotate = parse_rotate(ctx, *v);
  b.min = m.req("min").vec3();
  const Field mx = m.req("max");
  b.max = mx.vec3();
  for (int a = 0; a < 3; ++a)
    if (!(b.max[a] > b.min[a])) mx.element(a).fail("must be > min");
  if (tank)
    if (auto v = m.opt("thickness_layers"))
      b.thickness_layers = static_cast<int>(v->integer(1, 16));
  return b;
}

FluidSpec parse_fluid(const Context& ctx, const Field& f) {
  const MapView m(ctx, f,
                  {"density", "sound_speed", "viscosity", "viscosity_type", "wall_viscosity",
                   "delta", "spacing", "smoothing", "hydrostatic_init", "blocks", "tanks", "walls",
                   "couple_bodies", "solid_substeps", "min_pressure", "periodic_z"});
  FluidSpec fl;
  fl.present = true;
  if (auto v = m.opt("density")) fl.density = v->number(positive, "must be > 0");
  if (auto v = m.opt("sound_speed")) {
    if (!(v->node().IsScalar() && v->node().Scalar() == "auto"))
      fl.sound_speed = v->number(positive, "must be > 0 or auto");
  }
  if (auto v = m.opt("viscosity_type")) fl.viscosity_type = v->choice({"artificial", "laminar"});
  if (auto v = m.opt("viscosity")) fl.viscosity = v->number(non_negative, "must be >= 0");
  if (auto v = m.opt("wall_viscosity")) fl.wall_viscosity = v->boolean();
  if (auto v = m.opt("delta"))
    fl.delta = v->number([](double x) { return x >= 0 && x <= 1; }, "must be in [0, 1]");
  fl.spacing = m.req("spacing").number(positive, "must be > 0");
  if (auto v = m.opt("smoothing"))
    fl.smoothing =
        v->number([](double x) { return x >= 1 && x <= 3; }, "must be in [1, 3] (h / spacing)");
  if (auto v = m.opt("hydrostatic_init")) fl.hydrostatic_init = v->boolean();
  if (auto v = m.opt("periodic_z")) {
    v->expect_list(2, "numbers [z0, z1]");
    const double z0 = v->element(0).number(), z1 = v->element(1).number();
    if (!(z1 > z0)) v->element(1).fail("must be > z0");
    const double layers = (z1 - z0) / fl.spacing;
    if (std::fabs(layers - std::round(layers)) > 1e-6 * layers)
      v->fail("z1 - z0 must be a whole number of spacings (the lattice must tile the period)");
    fl.periodic_z = std::array<double, 2>{z0, z1};
  }
  // With a periodic z every fluid box lies within the period (the lattice tiles it).
  auto in_period = [&](const Field& bf, const FluidBoxSpec& b) {
    if (!fl.periodic_z) return;
    if (!b.rotate.none() && (b.rotate.axis.x != 0 || b.rotate.axis.y != 0))
      bf.fail("rotate: in a periodic_z slab boxes may turn about z only (axis [0, 0, 1])");
    const double tol = 1e-9 * fl.spacing;
    if (b.min.z < (*fl.periodic_z)[0] - tol || b.max.z > (*fl.periodic_z)[1] + tol)
      bf.fail("must lie within fluid.periodic_z in z");
  };
  const Field blocks = m.req("blocks");
  for (const auto& bf : blocks.list()) {
    fl.blocks.push_back(parse_fluid_box(ctx, bf, false));
    in_period(bf, fl.blocks.back());
  }
  if (fl.blocks.empty()) blocks.fail("at least one fluid block is required");
  if (auto v = m.opt("tanks"))
    for (const auto& bf : v->list()) {
      fl.tanks.push_back(parse_fluid_box(ctx, bf, true));
      in_period(bf, fl.tanks.back());
    }
  if (auto v = m.opt("walls"))
    for (const auto& bf : v->list()) {
      fl.walls.push_back(parse_fluid_box(ctx, bf, false));
      in_period(bf, fl.walls.back());
    }
  if (auto v = m.opt("min_pressure"))
    fl.min_pressure = v->number([](double x) { return x <= 0; }, "must be <= 0 [Pa]");
  if (auto v = m.opt("couple_bodies")) fl.couple_bodies = v->boolean();
  if (auto v = m.opt("solid_substeps")) fl.solid_substeps = static_cast<int>(v->integer(1, 100000));
  return fl;
}

double restitution(const Field& f) {
  return f.number([](double x) { return x > 0 && x <= 1; }, "must be in (0, 1]");
}

ContactSpec parse_contact(const Context& ctx, const Field& f,
                          const std::vector<MaterialSpec>& mats) {
  const MapView m(ctx, f,
                  {"mu", "restitution", "d_dem", "self_contact", "broad_phase", "stiffness_factor",
                   "skin", "max_penetration", "pairs"});
  ContactSpec c;
  if (auto v = m.opt("mu")) c.mu = v->number(non_negative, "must be >= 0");
  if (auto v = m.opt("restitution")) c.restitution = restitution(*v);
  if (auto v = m.opt("d_dem")) c.d_dem = v->number(positive, "must be > 0");
  if (auto v = m.opt("self_contact")) c.self_contact = v->boolean();
  if (auto v = m.opt("broad_phase"))
    c.broad_phase = v->choice({"polygons", "surface_tets", "all_tets"});
  if (auto v = m.opt("stiffness_factor")) c.stiffness_factor = v->number(positive, "must be > 0");
  if (auto v = m.opt("skin")) c.skin = v->number(non_negative, "must be >= 0 [m]");
  if (auto v = m.opt("max_penetration")) c.max_penetration = v->number(positive, "must be > 0 [m]");
  if (auto v = m.opt("pairs")) {
    for (const auto& pf : v->list()) {
      const MapView pm(ctx, pf, {"materials", "mu", "restitution", "stiffness"});
      ContactPairSpec p;
      const Field ms = pm.req("materials");
      ms.expect_list(2, "material names");
      p.material_a = lookup(ms.element(0), mats, "material", "materials");
      p.material_b = lookup(ms.element(1), mats, "material", "materials");
      if (auto x = pm.opt("mu")) p.mu = x->number(non_negative, "must be >= 0");
      if (auto x = pm.opt("restitution")) p.restitution = restitution(*x);
      if (auto x = pm.opt("stiffness")) p.stiffness = x->number(positive, "must be > 0 [N/m]");
      c.pairs.push_back(p);
    }
  }
  return c;
}

WallSpec parse_wall(const Context& ctx, const Field& f) {
  const MapView m(ctx, f, {"point", "normal", "mu", "restitution", "stiffness"});
  WallSpec w;
  w.point = m.req("point").vec3();
  const Field n = m.req("normal");
  w.normal = n.vec3();
  if (!(norm(w.normal) > 0)) n.fail("must not be the zero vector");
  w.normal = w.normal / norm(w.normal);
  if (auto v = m.opt("mu")) w.mu = v->number(non_negative, "must be >= 0");
  if (auto v = m.opt("restitution")) w.restitution = restitution(*v);
  if (auto v = m.opt("stiffness")) w.stiffness = v->number(positive, "must be > 0 [N/m]");
  return w;
}

OutputSpec parse_output(const Context& ctx, const Field& f, const std::string& scene_name) {
  const MapView m(ctx, f, {"dir", "fields_every", "probes_every", "checkpoint"});
  OutputSpec o;
  o.dir = fs::path("out") / scene_name;
  if (auto v = m.opt("dir")) o.dir = v->name();
  if (auto v = m.opt("fields_every")) o.fields_every = v->number(non_negative, "must be >= 0");
  if (auto v = m.opt("probes_every")) o.probes_every = v->number(non_negative, "must be >= 0");
  if (auto v = m.opt("checkpoint")) {
    const MapView c(ctx, *v, {"every_steps", "every_seconds", "keep", "dir"});
    CheckpointSpec& k = o.checkpoint;
    k.enabled = true;
    if (auto x = c.opt("every_steps"))
      k.every_steps = x->integer(1, std::numeric_limits<long>::max());
    if (auto x = c.opt("every_seconds")) k.every_seconds = x->number(positive, "must be > 0 [s]");
    if (auto x = c.opt("keep")) k.keep = static_cast<int>(x->integer(1, 1000));
    if (auto x = c.opt("dir")) k.dir = x->name();
    if (k.every_steps == 0 && k.every_seconds == 0)
      v->fail("set every_steps, every_seconds or both", false);
  }
  return o;
}

ParallelSpec parse_parallel(const Context& ctx, const Field& f) {
  const MapView m(ctx, f, {"curve", "rebalance_threshold", "rebalance_every", "max_cell_cost"});
  ParallelSpec p;
  if (auto v = m.opt("curve")) p.curve = v->choice({"hilbert", "morton", "peano"});
  if (auto v = m.opt("rebalance_threshold"))
    p.rebalance_threshold = v->number(non_negative, "must be >= 0 (a fraction, 0.1 = 10 %)");
  if (auto v = m.opt("rebalance_every"))
    p.rebalance_every = v->integer(1, std::numeric_limits<long>::max());
  if (auto v = m.opt("max_cell_cost"))
    p.max_cell_cost = v->number([](double x) { return x > 0 && x <= 1; },
                                "must be in (0, 1] (a fraction of the mean load of a rank)");
  return p;
}

Scene build_scene(const Context& ctx, const YAML::Node& root, const fs::path& file) {
  const Field top(ctx, root, "");
  if (!root.IsDefined() || root.IsNull()) throw InputError(file.string() + ": scene file is empty");
  const MapView m(ctx, top,
                  {"name", "run", "gravity", "damping", "materials", "bodies", "constraints",
                   "loads", "probes", "fluid", "contact", "walls", "output", "parallel"});
  Scene s;
  s.file = file;
  s.name = file.stem().string();
  if (auto v = m.opt("name")) s.name = v->name();
  if (auto v = m.opt("run"))
    s.run = parse_run(ctx, *v);
  else
    ctx.fail(root, "run", "required key is missing", false);
  if (auto v = m.opt("gravity")) s.gravity = v->vec3();
  if (auto v = m.opt("damping")) {
    const MapView d(ctx, *v, {"mass"});
    if (auto a = d.opt("mass")) s.mass_damping = a->number(non_negative, "must be >= 0");
  }

  // A fluid-only scene needs no materials or bodies.
  if (auto v = m.opt("fluid")) s.fluid = parse_fluid(ctx, *v);
  const bool fluid_only = s.fluid.present && !m.has("bodies");
  const Field mats = fluid_only && !m.has("materials")
                         ? Field(ctx, YAML::Node(YAML::NodeType::Map), "materials")
                         : m.req("materials");
  if (!mats.node().IsMap()) mats.fail("expected a mapping of material names to materials");
  for (const auto& kv : mats.node()) {
    const std::string name = kv.first.IsScalar() ? kv.first.Scalar() : "";
    const Field mf(ctx, kv.second, mats.path() + "." + name);
    if (name.empty()) ctx.fail(kv.first, mats.path(), "material names must be plain names");
    for (const auto& prev : s.materials)
      if (prev.name == name) ctx.fail(kv.first, mf.path(), "duplicate material name", false);
    s.materials.push_back(parse_material(ctx, name, mf));
  }
  if (s.materials.empty() && !fluid_only) mats.fail("at least one material is required", false);

  const Field bodies =
      fluid_only ? Field(ctx, YAML::Node(YAML::NodeType::Sequence), "bodies") : m.req("bodies");
  const std::vector<Field> body_fields = bodies.list();
  if (body_fields.empty() && !fluid_only) bodies.fail("at least one body is required");
  for (const auto& bf : body_fields) {
    BodySpec b = parse_body(ctx, bf, s.materials);
    for (const auto& prev : s.bodies)
      if (prev.name == b.name)
        ctx.fail(bf.node()["name"], bf.path() + ".name", "duplicate body name");
    s.bodies.push_back(std::move(b));
  }

  if (auto v = m.opt("constraints"))
    for (const auto& cf : v->list()) s.constraints.push_back(parse_constraint(ctx, cf, s.bodies));
  if (auto v = m.opt("loads"))
    for (const auto& lf : v->list()) s.loads.push_back(parse_load(ctx, lf, s.bodies));
  if (auto v = m.opt("probes")) {
    for (const auto& pf : v->list()) {
      ProbeSpec p = parse_probe(ctx, pf, s.bodies);
      for (const auto& prev : s.probes)
        if (prev.name == p.name)
          ctx.fail(pf.node()["name"], pf.path() + ".name", "duplicate probe name");
      s.probes.push_back(std::move(p));
    }
  }
  if (auto v = m.opt("contact")) s.contact = parse_contact(ctx, *v, s.materials);
  if (auto v = m.opt("walls"))
    for (const auto& wf : v->list()) s.walls.push_back(parse_wall(ctx, wf));
  if (auto v = m.opt("output"))
    s.output = parse_output(ctx, *v, s.name);
  else
    s.output.dir = fs::path("out") / s.name;
  if (auto v = m.opt("parallel")) s.parallel = parse_parallel(ctx, *v);
  return s;
}

}  // namespace

Scene parse_scene(std::string_view text, const fs::path& file,
                  const std::vector<std::string>& overrides) {
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  Context ctx(file.string(), folder);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw InputError(file.string() + ":" + std::to_string(e.mark.line + 1) + ":" +
                     std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  }
  if (!root.IsDefined() || root.IsNull()) {
    if (overrides.empty()) throw InputError(file.string() + ": scene file is empty");
    root = YAML::Node(YAML::NodeType::Map);
  }
  if (!root.IsMap()) ctx.fail(root, "", "a scene must be a mapping of keys to values");
  for (const auto& o : overrides) apply_override(ctx, root, o);
  try {
    return build_scene(ctx, root, file);
  } catch (const YAML::Exception& e) {
    // yaml-cpp throws on malformed trees we did not anticipate; keep the promise of a located
    // InputError rather than letting a library exception escape.
    throw InputError(file.string() + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

Scene load_scene(const fs::path& file, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw InputError(file.string() + ": scene file does not exist or is not a regular file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open scene file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), file, overrides);
}

}  // namespace qdemsph
