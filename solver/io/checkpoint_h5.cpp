#include "io/checkpoint_h5.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include "core/error.hpp"
#include "io/h5_file.hpp"
#include "io/json.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;
using h5::Handle;

constexpr const char* kFormat = "qdemsph checkpoint";
constexpr std::int64_t kVersion = 1;

std::string join_fingerprint(const std::vector<std::pair<std::string, std::string>>& items) {
  std::string s;
  for (const auto& [k, v] : items) s += k + '\t' + v + '\n';
  return s;
}

std::vector<std::pair<std::string, std::string>> split_fingerprint(const std::string& s) {
  std::vector<std::pair<std::string, std::string>> items;
  std::size_t pos = 0;
  while (pos < s.size()) {
    const std::size_t end = std::min(s.find('\n', pos), s.size());
    const std::string line = s.substr(pos, end - pos);
    const std::size_t tab = line.find('\t');
    if (tab != std::string::npos) items.emplace_back(line.substr(0, tab), line.substr(tab + 1));
    pos = end + 1;
  }
  return items;
}

hid_t group(hid_t file, const char* name) {
  const hid_t g = H5Gcreate2(file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) throw std::runtime_error(std::string("HDF5: create group ") + name + " failed");
  return g;
}

void write_contents(hid_t file, const Checkpoint& c) {
  h5::write_string_attribute(file, "format", kFormat);
  h5::write_attribute<std::int64_t>(file, "version", kVersion);
  h5::write_attribute<double>(file, "time", c.time);
  h5::write_attribute<double>(file, "dt", c.dt);
  h5::write_attribute<std::int64_t>(file, "step", c.step);
  h5::write_string_attribute(file, "scene", c.scene);
  h5::write_string_attribute(file, "fingerprint", join_fingerprint(c.fingerprint));
  {
    Handle g(group(file, "solid"), H5Gclose, "solid");
    h5::write(g.id, "vertex_gid", c.vertex_gid);
    h5::write(g.id, "x", c.solid.x);
    h5::write(g.id, "v", c.solid.v);
    h5::write(g.id, "f", c.solid.f);
    h5::write(g.id, "dissipated", c.solid.diss_v);
    h5::write(g.id, "tet_gid", c.tet_gid);
    h5::write(g.id, "tet_dissipated", c.solid.diss_t);
    if (!c.solid.fc.empty()) h5::write(g.id, "fc", c.solid.fc);
  }
  if (c.solid.contact) {
    const ContactState& s = *c.solid.contact;
    Handle g(group(file, "contact"), H5Gclose, "contact");
    std::vector<std::uint8_t> type;
    std::vector<std::uint64_t> a, b;
    for (const GlobalContactKey& k : c.contact_keys) {
      type.push_back(k.type);
      a.insert(a.end(), k.a.begin(), k.a.end());
      b.insert(b.end(), k.b.begin(), k.b.end());
    }
    h5::write(g.id, "history_type", type);
    h5::write_dataset(g.id, "history_feature1", H5T_NATIVE_UINT64, a.data(), type.size(), 3);
    h5::write_dataset(g.id, "history_feature2", H5T_NATIVE_UINT64, b.data(), type.size(), 3);
    h5::write(g.id, "history_active", s.active);
    h5::write(g.id, "history_xi", s.xi);
    h5::write(g.id, "history_h", s.h);
    h5::write(g.id, "history_energy", s.energy);
    h5::write(g.id, "history_energy_t", s.energy_t);
    h5::write_dataset(g.id, "history_vertex", H5T_NATIVE_INT64, s.v.data(), s.xi.size(), 4);
    h5::write_dataset(g.id, "history_weight", H5T_NATIVE_DOUBLE, s.w.data(), s.xi.size(), 4);
    h5::write(g.id, "history_n1", s.n1);
    h5::write(g.id, "ref_centroid", s.ref_centroid);
    h5::write(g.id, "ref_radius", s.ref_radius);
    h5::write_attribute<double>(g.id, "skin", s.skin);
    h5::write_attribute<double>(g.id, "max_overlap", s.stats.max_overlap);
    h5::write_attribute<double>(g.id, "max_overlap_ever", s.max_overlap_ever);
    h5::write_attribute<double>(g.id, "dissipated", s.dissipated);
    h5::write_attribute<std::int64_t>(g.id, "rebuilds", s.rebuilds);
    h5::write_attribute<std::int64_t>(g.id, "steps", s.steps);
    h5::write_attribute<std::int64_t>(g.id, "pairs", s.stats.pairs);
    h5::write_attribute<std::int64_t>(g.id, "contacts", s.stats.contacts);
    h5::write_attribute<std::int64_t>(g.id, "active", s.stats.active);
  }
  if (c.fluid) {
    const FluidState& s = *c.fluid;
    Handle g(group(file, "fluid"), H5Gclose, "fluid");
    h5::write(g.id, "gid", s.gid);
    h5::write(g.id, "type", s.type);
    h5::write(g.id, "x", s.x);
    h5::write(g.id, "v", s.v);
    h5::write(g.id, "a", s.a);
    h5::write(g.id, "rho", s.rho);
    h5::write(g.id, "p", s.p);
    h5::write(g.id, "m", s.m);
  }
  {
    Handle g(group(file, "output"), H5Gclose, "output");
    const CheckpointOutput& o = c.output;
    h5::write_attribute<std::int64_t>(g.id, "probes_bytes", o.probes_bytes);
    h5::write_attribute<std::int64_t>(g.id, "fluid_csv_bytes", o.fluid_csv_bytes);
    h5::write_attribute<std::int64_t>(g.id, "field_frames", o.field_frames);
    h5::write_attribute<std::int64_t>(g.id, "fluid_frames", o.fluid_frames);
    h5::write_attribute<double>(g.id, "next_probe", o.next_probe);
    h5::write_attribute<double>(g.id, "next_field", o.next_field);
    h5::write_attribute<std::int64_t>(g.id, "last_probe_step", o.last_probe_step);
    h5::write_attribute<std::int64_t>(g.id, "last_field_step", o.last_field_step);
  }
}

Checkpoint read_contents(hid_t file) {
  if (!h5::has_attribute(file, "format") || h5::read_string_attribute(file, "format") != kFormat)
    throw std::runtime_error("not a qdemsph checkpoint (no 'format' attribute)");
  const auto version = h5::read_attribute<std::int64_t>(file, "version");
  if (version != kVersion)
    throw std::runtime_error(
        fmt::format("checkpoint format version {}, this qdemsph reads {}", version, kVersion));
  Checkpoint c;
  c.time = h5::read_attribute<double>(file, "time");
  c.dt = h5::read_attribute<double>(file, "dt");
  c.step = h5::read_attribute<std::int64_t>(file, "step");
  c.scene = h5::read_string_attribute(file, "scene");
  c.fingerprint = split_fingerprint(h5::read_string_attribute(file, "fingerprint"));
  {
    Handle g(H5Gopen2(file, "solid", H5P_DEFAULT), H5Gclose, "open /solid");
    c.vertex_gid = h5::read<std::uint64_t>(g.id, "vertex_gid");
    c.solid.x = h5::read_vec3(g.id, "x");
    c.solid.v = h5::read_vec3(g.id, "v");
    c.solid.f = h5::read_vec3(g.id, "f");
    c.solid.diss_v = h5::read<double>(g.id, "dissipated");
    c.tet_gid = h5::read<std::uint64_t>(g.id, "tet_gid");
    c.solid.diss_t = h5::read<double>(g.id, "tet_dissipated");
    if (h5::exists(g.id, "fc")) c.solid.fc = h5::read_vec3(g.id, "fc");
  }
  if (h5::exists(file, "contact")) {
    Handle g(H5Gopen2(file, "contact", H5P_DEFAULT), H5Gclose, "open /contact");
    ContactState s;
    const auto type = h5::read<std::uint8_t>(g.id, "history_type");
    const std::size_t n = type.size();
    s.active = h5::read<std::uint8_t>(g.id, "history_active");
    s.xi = h5::read_vec3(g.id, "history_xi");
    s.h = h5::read_vec3(g.id, "history_h");
    s.energy = h5::read<double>(g.id, "history_energy");
    s.energy_t = h5::read<double>(g.id, "history_energy_t");
    s.n1 = h5::read<std::int32_t>(g.id, "history_n1");
    const auto fa = h5::read<std::uint64_t>(g.id, "history_feature1", 3);
    const auto fb = h5::read<std::uint64_t>(g.id, "history_feature2", 3);
    const auto hv = h5::read<std::int64_t>(g.id, "history_vertex", 4);
    const auto hw = h5::read<double>(g.id, "history_weight", 4);
    if (fa.size() != 3 * n || fb.size() != 3 * n)
      throw std::runtime_error("history_feature1/2 do not match history_type");
    if (s.active.size() != n || s.xi.size() != n || s.h.size() != n || s.energy.size() != n ||
        s.energy_t.size() != n || s.n1.size() != n || hv.size() != 4 * n || hw.size() != 4 * n)
      throw std::runtime_error("the history_* datasets differ in length");
    s.v.resize(n);
    s.w.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      for (int j = 0; j < 4; ++j) {
        s.v[k][j] = hv[4 * k + j];
        s.w[k][j] = hw[4 * k + j];
      }
    c.contact_keys.resize(type.size());
    for (std::size_t k = 0; k < type.size(); ++k) {
      c.contact_keys[k].type = type[k];
      for (int j = 0; j < 3; ++j) {
        c.contact_keys[k].a[j] = fa[3 * k + j];
        c.contact_keys[k].b[j] = fb[3 * k + j];
      }
    }
    s.ref_centroid = h5::read_vec3(g.id, "ref_centroid");
    s.ref_radius = h5::read<double>(g.id, "ref_radius");
    s.skin = h5::read_attribute<double>(g.id, "skin");
    s.stats.max_overlap = h5::read_attribute<double>(g.id, "max_overlap");
    s.max_overlap_ever = h5::read_attribute<double>(g.id, "max_overlap_ever");
    s.dissipated = h5::read_attribute<double>(g.id, "dissipated");
    s.rebuilds = h5::read_attribute<std::int64_t>(g.id, "rebuilds");
    s.steps = h5::read_attribute<std::int64_t>(g.id, "steps");
    s.stats.pairs = h5::read_attribute<std::int64_t>(g.id, "pairs");
    s.stats.contacts = h5::read_attribute<std::int64_t>(g.id, "contacts");
    s.stats.active = h5::read_attribute<std::int64_t>(g.id, "active");
    c.solid.contact = std::move(s);
  }
  if (h5::exists(file, "fluid")) {
    Handle g(H5Gopen2(file, "fluid", H5P_DEFAULT), H5Gclose, "open /fluid");
    FluidState s;
    s.gid = h5::read<std::uint64_t>(g.id, "gid");
    s.type = h5::read<std::uint8_t>(g.id, "type");
    s.x = h5::read_vec3(g.id, "x");
    s.v = h5::read_vec3(g.id, "v");
    s.a = h5::read_vec3(g.id, "a");
    s.rho = h5::read<double>(g.id, "rho");
    s.p = h5::read<double>(g.id, "p");
    s.m = h5::read<double>(g.id, "m");
    c.fluid = std::move(s);
  }
  {
    Handle g(H5Gopen2(file, "output", H5P_DEFAULT), H5Gclose, "open /output");
    CheckpointOutput& o = c.output;
    o.probes_bytes = h5::read_attribute<std::int64_t>(g.id, "probes_bytes");
    o.fluid_csv_bytes = h5::read_attribute<std::int64_t>(g.id, "fluid_csv_bytes");
    o.field_frames = h5::read_attribute<std::int64_t>(g.id, "field_frames");
    o.fluid_frames = h5::read_attribute<std::int64_t>(g.id, "fluid_frames");
    o.next_probe = h5::read_attribute<double>(g.id, "next_probe");
    o.next_field = h5::read_attribute<double>(g.id, "next_field");
    o.last_probe_step = h5::read_attribute<std::int64_t>(g.id, "last_probe_step");
    o.last_field_step = h5::read_attribute<std::int64_t>(g.id, "last_field_step");
  }
  return c;
}

// fsync of a file or folder; false when it cannot be opened or synced.
bool sync_path(const fs::path& p, bool directory) {
  const int fd = ::open(p.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

bool is_checkpoint_name(const std::string& name, std::int64_t& step) {
  constexpr std::string_view pre = "checkpoint_", post = ".h5";
  if (name.size() <= pre.size() + post.size() || name.compare(0, pre.size(), pre) != 0 ||
      name.compare(name.size() - post.size(), post.size(), post) != 0)
    return false;
  const std::string digits = name.substr(pre.size(), name.size() - pre.size() - post.size());
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return false;
  step = std::stoll(digits);
  return true;
}

}  // namespace

void write_checkpoint(const fs::path& path, const Checkpoint& c) {
  const fs::path tmp = path.string() + ".tmp";
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t file = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw InputError("cannot create checkpoint '" + tmp.string() + "'");
  try {
    write_contents(file, c);
    h5::check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush");
  } catch (const std::exception& e) {
    H5Fclose(file);
    std::error_code ec;
    fs::remove(tmp, ec);
    throw InputError("cannot write checkpoint '" + tmp.string() + "': " + e.what());
  }
  if (H5Fclose(file) < 0 || !sync_path(tmp, false))
    throw InputError("cannot write checkpoint '" + tmp.string() + "' (disk full?)");
  std::error_code ec;
  fs::rename(tmp, path, ec);  // atomic within one file system
  if (ec)
    throw InputError("cannot rename '" + tmp.string() + "' to '" + path.string() +
                     "': " + ec.message());
  sync_path(path.parent_path().empty() ? fs::path(".") : path.parent_path(), true);
}

Checkpoint read_checkpoint(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw InputError("checkpoint '" + path.string() + "': no such file");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (H5Fis_hdf5(path.c_str()) <= 0)
    throw InputError("checkpoint '" + path.string() + "': not an HDF5 file (or damaged)");
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw InputError("checkpoint '" + path.string() + "': cannot be opened");
  try {
    Checkpoint c = read_contents(file);
    H5Fclose(file);
    return c;
  } catch (const std::exception& e) {
    H5Fclose(file);
    throw InputError("checkpoint '" + path.string() + "': unreadable or incomplete: " + e.what());
  }
}

std::vector<fs::path> list_checkpoints(const fs::path& dir) {
  std::vector<std::pair<std::int64_t, fs::path>> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::int64_t step = 0;
    if (e.is_regular_file(ec) && is_checkpoint_name(e.path().filename().string(), step))
      found.emplace_back(step, e.path());
  }
  std::sort(found.begin(), found.end());
  std::vector<fs::path> out;
  for (auto& f : found) out.push_back(std::move(f.second));
  return out;
}

Checkpoint read_latest_checkpoint(const fs::path& dir, fs::path& path) {
  const std::vector<fs::path> all = list_checkpoints(dir);
  for (auto it = all.rbegin(); it != all.rend(); ++it) {
    try {
      Checkpoint c = read_checkpoint(*it);
      path = *it;
      return c;
    } catch (const InputError& e) {
      fmt::print(stderr, "qdemsph: warning: skipping {}\n", e.what());
    }
  }
  throw InputError("--restart latest: no readable checkpoint in '" + dir.string() + "'");
}

CheckpointSeries::CheckpointSeries(fs::path dir, int keep) : dir_(std::move(dir)), keep_(keep) {
  ensure_output_dir(dir_);
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("checkpoint_", 0) == 0 && name.size() > 4 &&
        name.compare(name.size() - 4, 4, ".tmp") == 0)
      fs::remove(e.path(), ec);  // a write a killed run did not finish
  }
}

fs::path CheckpointSeries::write(const Checkpoint& c) {
  const fs::path path = dir_ / fmt::format("checkpoint_{:010d}.h5", c.step);
  write_checkpoint(path, c);
  std::vector<fs::path> all = list_checkpoints(dir_);
  std::error_code ec;
  for (std::size_t k = 0; k + keep_ < all.size(); ++k) fs::remove(all[k], ec);
  return path;
}

}  // namespace qdemsph
