#include "model/contact_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model.hpp"
#include "physics/contact_law.hpp"

namespace qdemsph {

const char* broad_phase_name(BroadPhase b) {
  switch (b) {
    case BroadPhase::AllTets:
      return "all_tets";
    case BroadPhase::SurfaceTets:
      return "surface_tets";
    default:
      return "polygons";
  }
}

namespace {
double youngs_modulus(const Material& m) {
  return m.mu * (3 * m.lambda + 2 * m.mu) / (m.lambda + m.mu);
}
}  // namespace

void build_contact_model(const Scene& scene, Model& model,
                         const std::vector<std::uint8_t>& tet_is_surface) {
  ContactModel& c = model.contact;
  c = ContactModel{};
  const std::size_t nb = model.bodies.size();
  const bool any_free = std::any_of(model.bodies.begin(), model.bodies.end(),
                                    [](const BodyRange& b) { return !b.fixed; });
  c.enabled = any_free && (nb > 1 || !scene.walls.empty() || scene.contact.self_contact);
  c.self_contact = scene.contact.self_contact;
  c.kn_factor = scene.contact.stiffness_factor;
  c.skin = scene.contact.skin.value_or(-1.0);
  c.max_penetration = scene.contact.max_penetration.value_or(0.0);
  c.mode = scene.contact.broad_phase == "all_tets"       ? BroadPhase::AllTets
           : scene.contact.broad_phase == "surface_tets" ? BroadPhase::SurfaceTets
                                                         : BroadPhase::Polygons;
  c.n_surface_tets = std::count(tet_is_surface.begin(), tet_is_surface.end(), 1);
  if (!c.enabled) return;

  const std::int64_t ntri = static_cast<std::int64_t>(model.surface.size());
  c.tri_v.resize(ntri);
  c.tri_body = model.surface_body;
  for (std::int64_t s = 0; s < ntri; ++s) c.tri_v[s] = model.surface[s].v;

  // Unique edges and per-body mean surface edge length.
  std::vector<double> hsum(nb, 0.0);
  std::vector<std::int64_t> hcnt(nb, 0);
  for (std::int64_t s = 0; s < ntri; ++s)
    for (int q = 0; q < 3; ++q) {
      const std::int32_t a = c.tri_v[s][q], b = c.tri_v[s][(q + 1) % 3];
      c.edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(c.edges.begin(), c.edges.end());
  c.edges.erase(std::unique(c.edges.begin(), c.edges.end()), c.edges.end());
  for (const auto& e : c.edges) {
    const int b = model.body[e[0]];
    hsum[b] += norm(model.X[e[1]] - model.X[e[0]]);
    ++hcnt[b];
  }
  c.body_h.resize(nb);
  c.body_fixed.resize(nb);
  c.body_mat.resize(nb);
  double hmin = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < nb; ++b) {
    c.body_h[b] = hcnt[b] ? hsum[b] / hcnt[b] : 0.0;
    c.body_fixed[b] = model.bodies[b].fixed;
    c.body_mat[b] = model.bodies[b].material;
    if (hcnt[b]) hmin = std::min(hmin, c.body_h[b]);
  }
  c.d_dem = scene.contact.d_dem.value_or(0.1 * hmin);

  // Ownership: each surface vertex and edge goes to the lowest-numbered triangle holding it.
  const std::int64_t nv = model.n_vertices();
  std::vector<std::int32_t> v_owner(nv, -1), e_owner(c.edges.size(), -1);
  c.own_v_off.assign(ntri + 1, 0);
  c.own_e_off.assign(ntri + 1, 0);
  c.edge_tri.assign(c.edges.size(), {-1, -1});
  for (std::int64_t s = 0; s < ntri; ++s) {
    for (int q = 0; q < 3; ++q) {
      const std::int32_t a = c.tri_v[s][q], b = c.tri_v[s][(q + 1) % 3];
      if (v_owner[a] < 0) {
        v_owner[a] = static_cast<std::int32_t>(s);
        c.own_v.push_back(a);
      }
      const std::array<std::int32_t, 2> e{std::min(a, b), std::max(a, b)};
      const auto it = std::lower_bound(c.edges.begin(), c.edges.end(), e);
      const auto ei = static_cast<std::int32_t>(it - c.edges.begin());
      auto& et = c.edge_tri[ei];
      (et[0] < 0 ? et[0] : et[1]) = static_cast<std::int32_t>(s);
      if (e_owner[ei] < 0) {
        e_owner[ei] = static_cast<std::int32_t>(s);
        c.own_e.push_back(ei);
      }
    }
    c.own_v_off[s + 1] = static_cast<std::int64_t>(c.own_v.size());
    c.own_e_off[s + 1] = static_cast<std::int64_t>(c.own_e.size());
  }

  // Broad-phase primitives.
  if (c.mode == BroadPhase::Polygons) {
    for (std::int64_t s = 0; s < ntri; ++s) {
      c.prim_v.push_back({c.tri_v[s][0], c.tri_v[s][1], c.tri_v[s][2], -1});
      c.prim_body.push_back(c.tri_body[s]);
      c.prim_tri.push_back(static_cast<std::int32_t>(s));
      c.prim_tri_off.push_back(s);
    }
    c.prim_tri_off.push_back(ntri);
  } else {
    // Surface triangles are sorted by (tet, face): one pass assigns them to their tets.
    std::int64_t s = 0;
    c.prim_tri_off.push_back(0);
    for (std::int64_t t = 0; t < model.n_tets(); ++t) {
      const bool take = c.mode == BroadPhase::AllTets || tet_is_surface[t];
      while (s < ntri && model.surface[s].tet < t) ++s;  // (never: every tet visited in order)
      std::int64_t e = s;
      while (e < ntri && model.surface[e].tet == t) ++e;
      if (take) {
        c.prim_v.push_back(model.tets[t]);
        c.prim_body.push_back(model.body[model.tets[t][0]]);
        for (std::int64_t k = s; k < e; ++k) c.prim_tri.push_back(static_cast<std::int32_t>(k));
        c.prim_tri_off.push_back(static_cast<std::int64_t>(c.prim_tri.size()));
      }
      s = e;
    }
  }

  for (std::size_t p = 0; p < c.prim_body.size(); ++p)
    if (!c.body_fixed[c.prim_body[p]]) c.n_free_prims = static_cast<std::int64_t>(p) + 1;

  // Wall vertices: surface vertices of free bodies that are integrated.
  if (!scene.walls.empty())
    for (std::int64_t i = 0; i < model.n_free_vertices; ++i)
      if (v_owner[i] >= 0) c.wall_vertices.push_back(static_cast<std::int32_t>(i));

  // Material-pair parameters.
  const int nm = static_cast<int>(model.materials.size());
  c.n_mat = nm;
  c.pair_mu.assign(nm * nm, scene.contact.mu);
  c.pair_zeta.assign(nm * nm, damping_ratio_from_restitution(scene.contact.restitution));
  c.pair_kn.assign(nm * nm, 0.0);
  c.pair_E.assign(nm * nm, 0.0);
  for (int a = 0; a < nm; ++a)
    for (int b = 0; b < nm; ++b) {
      const double Ea = youngs_modulus(model.materials[a]), Eb = youngs_modulus(model.materials[b]);
      c.pair_E[a * nm + b] = 2 * Ea * Eb / (Ea + Eb);
    }
  for (const auto& p : scene.contact.pairs)
    for (int k = 0; k < 2; ++k) {
      const int i =
          (k == 0 ? p.material_a : p.material_b) * nm + (k == 0 ? p.material_b : p.material_a);
      if (p.mu) c.pair_mu[i] = *p.mu;
      if (p.restitution) c.pair_zeta[i] = damping_ratio_from_restitution(*p.restitution);
      if (p.stiffness) c.pair_kn[i] = *p.stiffness;
    }
  for (const auto& w : scene.walls) {
    ContactWall cw;
    cw.point = w.point;
    cw.normal = w.normal / norm(w.normal);
    cw.mu = w.mu;
    cw.zeta = damping_ratio_from_restitution(w.restitution.value_or(scene.contact.restitution));
    cw.stiffness = w.stiffness.value_or(0.0);
    c.walls.push_back(cw);
  }

  // Stability estimate of the contact springs: a surface vertex of mass m on up to 4 springs
  // of k_n: omega = sqrt(4 k_n / m), dt < 2 / omega = sqrt(m / k_n).
  double dt = std::numeric_limits<double>::infinity();
  std::vector<double> mmin(nb, std::numeric_limits<double>::infinity());
  for (std::int64_t i = 0; i < model.n_free_vertices; ++i)
    if (v_owner[i] >= 0 && model.inv_mass[i] > 0)
      mmin[model.body[i]] = std::min(mmin[model.body[i]], model.mass[i]);
  double kmax = 0;
  for (double k : c.pair_kn) kmax = std::max(kmax, k);
  for (const auto& w : c.walls) kmax = std::max(kmax, w.stiffness);
  for (std::size_t b = 0; b < nb; ++b) {
    if (!std::isfinite(mmin[b])) continue;
    const int m = c.body_mat[b];
    double Emax = 0;
    for (int o = 0; o < nm; ++o) Emax = std::max(Emax, c.pair_E[m * nm + o]);
    const double k = std::max(kmax, c.kn_factor * Emax * c.body_h[b]);
    dt = std::min(dt, std::sqrt(mmin[b] / k));
  }
  c.dt_limit = std::isfinite(dt) ? dt : 0.0;
}

std::string describe_contact(const Model& model) {
  const ContactModel& c = model.contact;
  if (!c.enabled) {
    if (model.bodies.size() <= 1) return "no contact: one body";
    return "no contact: no free body";
  }
  return fmt::format(
      "contact: {} surface tets, {} surface triangles ({} broad phase over {} primitives, "
      "D_DEM = {:.3g} m, {} walls{})",
      c.n_surface_tets, c.tri_v.size(), broad_phase_name(c.mode), c.prim_v.size(), c.d_dem,
      c.walls.size(), c.self_contact ? ", self-contact" : "");
}

}  // namespace qdemsph
