#include "integrate/restart.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <numeric>
#include <tuple>
#include <unordered_map>

#include "contact/contact_record.hpp"
#include "core/error.hpp"

namespace qdemsph {
namespace {

// FNV-1a 64 over the bytes of the values added, printed as 16 hex digits.
class Hash {
 public:
  Hash& bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ b[i]) * 0x100000001b3ull;
    return *this;
  }
  template <class T>
  Hash& add(const T& v) {
    static_assert(std::is_arithmetic_v<T>);
    return bytes(&v, sizeof v);
  }
  Hash& add(const Vec3& v) { return add(v.x).add(v.y).add(v.z); }
  Hash& add(const std::string& s) { return add(s.size()).bytes(s.data(), s.size()); }
  template <class T>
  Hash& add(const std::vector<T>& v) {
    add(v.size());
    for (const T& x : v) add(x);
    return *this;
  }
  template <class T, std::size_t N>
  Hash& add(const std::array<T, N>& a) {
    for (const T& x : a) add(x);
    return *this;
  }
  std::string str() const { return fmt::format("fnv1a:{:016x}", h_); }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

const char* law_name(MaterialLaw l) { return l == MaterialLaw::Linear ? "linear" : "svk"; }

}  // namespace

Fingerprint make_fingerprint(const Scene& scene, const Model& m, double dt,
                             const FluidSetup* fluid) {
  Fingerprint f;
  auto item = [&f](std::string k, std::string v) { f.emplace_back(std::move(k), std::move(v)); };
  item("vertices", fmt::format("{} ({} free)", m.n_vertices(), m.n_free_vertices));
  item("tets", fmt::format("{} ({} free)", m.n_tets(), m.n_free_tets));
  for (const BodyRange& b : m.bodies)
    item(fmt::format("body '{}'", b.name),
         fmt::format("{} vertices, {} tets{}", b.v_end - b.v_begin, b.t_end - b.t_begin,
                     b.fixed ? ", fixed" : ""));
  item("vertex ids", Hash().add(m.gid).str());
  item("tet ids", Hash().add(m.tet_gid).str());
  item("mesh (reference positions, connectivity)", Hash().add(m.X).add(m.tets).str());
  for (const MaterialSpec& s : scene.materials)
    item(fmt::format("material '{}'", s.name),
         fmt::format("law {}, E {}, nu {}, density {}, viscosity {}", law_name(s.law), s.E, s.nu,
                     s.density, s.viscosity));
  item("masses and constraints", Hash().add(m.mass).add(m.inv_mass).add(m.flags).str());
  item("loads", Hash().add(m.fext).add(m.fpre).str());
  item("gravity", fmt::format("{} {} {}", m.gravity.x, m.gravity.y, m.gravity.z));
  item("damping.mass", fmt::format("{}", m.mass_damping));
  item("dt", fmt::format("{}", dt));
  const ContactModel& c = m.contact;
  if (c.enabled) {
    item("contact",
         fmt::format("d_dem {}, broad_phase {}, self_contact {}, {} triangles, {} edges, {} "
                     "primitives, {} walls",
                     c.d_dem, broad_phase_name(c.mode), c.self_contact, c.tri_v.size(),
                     c.edges.size(), c.prim_v.size(), c.walls.size()));
    const ContactSpec& cs = scene.contact;
    item("contact settings",
         fmt::format("mu {}, restitution {}, stiffness_factor {}, skin {}, {} material pairs",
                     cs.mu, cs.restitution, cs.stiffness_factor,
                     cs.skin ? fmt::format("{}", *cs.skin) : "auto", cs.pairs.size()));
    for (std::size_t w = 0; w < c.walls.size(); ++w) {
      const ContactWall& cw = c.walls[w];
      item(fmt::format("wall {}", w),
           fmt::format("point {} {} {}, normal {} {} {}, mu {}, damping ratio {}, stiffness {}",
                       cw.point.x, cw.point.y, cw.point.z, cw.normal.x, cw.normal.y, cw.normal.z,
                       cw.mu, cw.zeta, cw.stiffness));
    }
    Hash h;
    h.add(c.kn_factor).add(c.kt_ratio).add(c.skin).add(c.pair_mu).add(c.pair_zeta);
    h.add(c.pair_kn).add(c.pair_E).add(c.body_h).add(c.tri_v).add(c.prim_v);
    for (const ContactWall& w : c.walls)
      h.add(w.point).add(w.normal).add(w.mu).add(w.zeta).add(w.stiffness);
    item("contact parameters", h.str());
  } else {
    item("contact", "none");
  }
  if (fluid) {
    item("fluid", fmt::format("{} particles ({} fluid), spacing {}", fluid->size(), fluid->n_fluid,
                              fluid->dx));
    const FluidSpec& s = scene.fluid;
    Hash h;
    h.add(s.density).add(s.sound_speed.value_or(-1.0)).add(s.viscosity_type).add(s.viscosity);
    h.add(s.wall_viscosity).add(s.delta).add(s.smoothing).add(s.hydrostatic_init);
    h.add(fluid->params.eos.c0).add(fluid->params.kernel.h);
    h.add(fluid->x).add(fluid->m).add(fluid->type).add(fluid->gid);
    item("fluid parameters and initial particles", h.str());
  } else {
    item("fluid", "none");
  }
  std::string probes;
  for (const ProbeSpec& p : scene.probes) probes += (probes.empty() ? "" : ", ") + p.name;
  item("probes", probes.empty() ? "none" : probes);
  return f;
}

std::vector<std::string> fingerprint_differences(const Fingerprint& saved, const Fingerprint& now) {
  std::map<std::string, std::string> a(saved.begin(), saved.end()), b(now.begin(), now.end());
  std::vector<std::string> out;
  for (const auto& [k, v] : now) {
    const auto it = a.find(k);
    if (it == a.end())
      out.push_back(fmt::format("{}: the checkpoint has none, the scene has {}", k, v));
    else if (it->second != v)
      out.push_back(fmt::format("{}: checkpoint has {}, the scene has {}", k, it->second, v));
  }
  for (const auto& [k, v] : saved)
    if (!b.count(k)) out.push_back(fmt::format("{}: checkpoint has {}, the scene has none", k, v));
  return out;
}

namespace {

// Contact keys (contact/contact_record.hpp) <-> features by global vertex ids.
GlobalContactKey global_key(const Model& m, std::uint64_t k1, std::uint64_t k2) {
  const ContactModel& c = m.contact;
  GlobalContactKey g;
  g.type = static_cast<std::uint8_t>(k1 >> 60);
  const std::uint64_t id1 = k1 & ((std::uint64_t{1} << 60) - 1);
  switch (g.type) {
    case kPointFace:  // id1 is the vertex's global id (ContactTopology::vgid)
      g.a[0] = id1;
      for (int k = 0; k < 3; ++k) g.b[k] = m.gid[c.tri_v[k2][k]];
      break;
    case kEdgeEdge:
      for (int k = 0; k < 2; ++k) {
        g.a[k] = m.gid[c.edges[id1][k]];
        g.b[k] = m.gid[c.edges[k2][k]];
      }
      break;
    default:  // kWall: id1 is the vertex's global id
      g.a[0] = id1;
      g.b[0] = k2;
  }
  return g;
}

struct LocalKeys {
  std::unordered_map<std::uint64_t, std::int32_t> vertex;    // gid -> local index
  std::map<std::array<std::int32_t, 3>, std::int64_t> tri;   // vertices (as stored) -> triangle
  std::map<std::array<std::int32_t, 2>, std::int64_t> edge;  // sorted vertices -> edge
  explicit LocalKeys(const Model& m) {
    for (std::size_t i = 0; i < m.gid.size(); ++i)
      vertex.emplace(m.gid[i], static_cast<std::int32_t>(i));
    for (std::size_t s = 0; s < m.contact.tri_v.size(); ++s) tri.emplace(m.contact.tri_v[s], s);
    for (std::size_t e = 0; e < m.contact.edges.size(); ++e) {
      auto v = m.contact.edges[e];
      if (v[1] < v[0]) std::swap(v[0], v[1]);
      edge.emplace(v, e);
    }
  }
  std::int32_t v(std::uint64_t gid) const {
    const auto it = vertex.find(gid);
    if (it == vertex.end())
      throw InputError(
          fmt::format("contact history names vertex id {}, which the scene lacks", gid));
    return it->second;
  }
};

// Local (k1, k2) of a global key; `flip`: the two edges of an edge-edge key changed order here
// (the lower edge id comes first), so side 1 and 2 swap and the spring changes sign.
std::pair<std::uint64_t, std::uint64_t> local_key(const LocalKeys& L, const GlobalContactKey& g,
                                                  bool& flip) {
  flip = false;
  auto fail = [&g](const char* what) {
    return InputError(fmt::format("contact history names a {} the scene lacks (type {})", what,
                                  static_cast<int>(g.type)));
  };
  switch (g.type) {
    case kPointFace: {
      const std::array<std::int32_t, 3> t{L.v(g.b[0]), L.v(g.b[1]), L.v(g.b[2])};
      const auto it = L.tri.find(t);
      if (it == L.tri.end()) throw fail("surface triangle");
      L.v(g.a[0]);  // the vertex exists
      return {contact_key1(kPointFace, g.a[0]), static_cast<std::uint64_t>(it->second)};
    }
    case kEdgeEdge: {
      std::int64_t e[2];
      for (int s = 0; s < 2; ++s) {
        const auto& f = s == 0 ? g.a : g.b;
        std::array<std::int32_t, 2> v{L.v(f[0]), L.v(f[1])};
        if (v[1] < v[0]) std::swap(v[0], v[1]);
        const auto it = L.edge.find(v);
        if (it == L.edge.end()) throw fail("surface edge");
        e[s] = it->second;
      }
      flip = e[1] < e[0];
      if (flip) std::swap(e[0], e[1]);
      return {contact_key1(kEdgeEdge, static_cast<std::uint64_t>(e[0])),
              static_cast<std::uint64_t>(e[1])};
    }
    case kWall:
      L.v(g.a[0]);
      return {contact_key1(kWall, g.a[0]), g.b[0]};
    default:
      throw fail("contact type");
  }
}

}  // namespace

Checkpoint capture_checkpoint(const Scene& scene, const Model& model, double dt, Backend& backend,
                              FluidStage* fluid, const FluidSetup* fluid_setup,
                              const Stepper& stepper) {
  Checkpoint c;
  c.time = stepper.time();
  c.step = stepper.steps();
  c.dt = dt;
  c.scene = scene.file.string();
  c.fingerprint = make_fingerprint(scene, model, dt, fluid_setup);
  c.vertex_gid = model.gid;
  c.tet_gid = model.tet_gid;
  c.solid = backend.save_state();
  if (c.solid.contact) {
    // The active entries (an inactive one is never looked up), in key order, so that the file
    // does not depend on how many ranks wrote it.
    ContactState& all = *c.solid.contact;
    ContactState s = all;
    s.resize(0);
    for (std::size_t k = 0; k < all.size(); ++k) {
      if (!all.active[k]) continue;
      s.push_back(all, k);
      c.contact_keys.push_back(global_key(model, all.k1[k], all.k2[k]));
      for (auto& i : s.v.back())
        if (i >= 0) i = static_cast<std::int64_t>(model.gid[i]);
    }
    s.k1.clear();
    s.k2.clear();
    all = std::move(s);
  }
  if (fluid) c.fluid = fluid->save_state();
  return c;
}

void check_checkpoint(const Checkpoint& c, const std::string& source, const Scene& scene,
                      const Model& model, double dt, const FluidSetup* fluid_setup) {
  const std::vector<std::string> diff =
      fingerprint_differences(c.fingerprint, make_fingerprint(scene, model, dt, fluid_setup));
  if (diff.empty()) return;
  std::string msg =
      fmt::format("checkpoint '{}' (written from '{}') does not match scene '{}':", source, c.scene,
                  scene.file.string());
  for (const auto& d : diff) msg += "\n  " + d;
  throw InputError(msg);
}

void restore_checkpoint(const Checkpoint& c, const std::string& source, const Scene& scene,
                        const Model& model, double dt, Backend& backend, FluidStage* fluid,
                        const FluidSetup* fluid_setup, Stepper& stepper) {
  check_checkpoint(c, source, scene, model, dt, fluid_setup);
  auto fail = [&source](const std::string& what) {
    return InputError(fmt::format("checkpoint '{}': {}", source, what));
  };
  // Solid arrays by global id into the model's local order.
  const std::size_t nv = model.gid.size(), nt = model.tet_gid.size();
  if (c.vertex_gid.size() != nv || c.solid.x.size() != nv || c.solid.v.size() != nv ||
      c.solid.f.size() != nv || c.solid.diss_v.size() != nv || c.tet_gid.size() != nt ||
      c.solid.diss_t.size() != nt || (!c.solid.fc.empty() && c.solid.fc.size() != nv))
    throw fail("solid arrays do not match the vertex and tet counts");
  // A coupled run's bodies carry the fluid's force between fluid steps (SolidViews::fc).
  const bool coupled = fluid_setup && fluid_setup->n_marker > 0;
  if (coupled && c.solid.fc.empty())
    throw fail(
        "no coupling force (/solid/fc): it was written by a qdemsph that did not store it, and "
        "a run coupling fluid and bodies cannot continue exactly without it; start the run "
        "again");
  if (!coupled && !c.solid.fc.empty())
    throw fail("a coupling force, but the scene couples no fluid to bodies");
  std::unordered_map<std::uint64_t, std::size_t> vloc, tloc;
  for (std::size_t i = 0; i < nv; ++i) vloc.emplace(model.gid[i], i);
  for (std::size_t t = 0; t < nt; ++t) tloc.emplace(model.tet_gid[t], t);
  BackendState s;
  s.x.resize(nv);
  s.v.resize(nv);
  s.f.resize(nv);
  s.diss_v.resize(nv);
  s.diss_t.resize(nt);
  if (coupled) s.fc.resize(nv);
  for (std::size_t k = 0; k < nv; ++k) {
    const auto it = vloc.find(c.vertex_gid[k]);
    if (it == vloc.end())
      throw fail(fmt::format("vertex id {} is not in the scene", c.vertex_gid[k]));
    s.x[it->second] = c.solid.x[k];
    s.v[it->second] = c.solid.v[k];
    s.f[it->second] = c.solid.f[k];
    s.diss_v[it->second] = c.solid.diss_v[k];
    if (coupled) s.fc[it->second] = c.solid.fc[k];
  }
  for (std::size_t k = 0; k < nt; ++k) {
    const auto it = tloc.find(c.tet_gid[k]);
    if (it == tloc.end()) throw fail(fmt::format("tet id {} is not in the scene", c.tet_gid[k]));
    s.diss_t[it->second] = c.solid.diss_t[k];
  }
  if (c.solid.contact.has_value() != model.contact.enabled)
    throw fail(model.contact.enabled ? "no contact state, but the scene has contact"
                                     : "contact state, but the scene has no contact");
  if (c.solid.contact) {
    // History entries re-keyed in this model's features and vertices, re-sorted by key.
    const ContactState& saved = *c.solid.contact;
    if (saved.xi.size() != c.contact_keys.size()) throw fail("contact history sizes differ");
    const LocalKeys L(model);
    ContactState keyed = saved;
    keyed.k1.resize(saved.xi.size());
    keyed.k2.resize(saved.xi.size());
    for (std::size_t k = 0; k < c.contact_keys.size(); ++k) {
      bool flip = false;
      std::tie(keyed.k1[k], keyed.k2[k]) = local_key(L, c.contact_keys[k], flip);
      for (auto& i : keyed.v[k])
        if (i >= 0) i = L.v(static_cast<std::uint64_t>(i));
      if (flip) {  // side 1 and 2 swap: spring and h change sign
        keyed.xi[k] = -keyed.xi[k];
        keyed.h[k] = -keyed.h[k];
        std::swap(keyed.v[k][0], keyed.v[k][2]);
        std::swap(keyed.v[k][1], keyed.v[k][3]);
        std::swap(keyed.w[k][0], keyed.w[k][2]);
        std::swap(keyed.w[k][1], keyed.w[k][3]);
      }
    }
    std::vector<std::size_t> order(keyed.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return std::pair(keyed.k1[a], keyed.k2[a]) < std::pair(keyed.k1[b], keyed.k2[b]);
    });
    ContactState cs = saved;  // pair-list reference and counters
    cs.resize(0);
    for (std::size_t k : order) cs.push_back(keyed, k);
    s.contact = std::move(cs);
  }
  if (c.fluid.has_value() != (fluid != nullptr))
    throw fail(fluid ? "no fluid state, but the scene has fluid"
                     : "fluid state, but the scene has no fluid");
  if (fluid) {
    std::vector<std::uint64_t> a = c.fluid->gid, b = fluid_setup->gid;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    if (a != b) throw fail("the fluid particle ids differ from the scene's");
    fluid->load_state(*c.fluid);
  }
  backend.load_state(s);
  stepper.set_clock(c.time, c.step);
}

}  // namespace qdemsph
