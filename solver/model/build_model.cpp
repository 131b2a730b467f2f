#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh_io.hpp"
#include "mesh/shogi.hpp"
#include "mesh/surface.hpp"
#include "model/model.hpp"
#include "model/overlap.hpp"
#include "physics/element.hpp"

namespace qdemsph {
namespace {

ShogiSize shogi_preset(const std::string& piece) {
  if (piece == "rook" || piece == "bishop") return ShogiSize::rook();
  if (piece == "gold" || piece == "silver") return ShogiSize::gold();
  if (piece == "knight") return ShogiSize::knight();
  if (piece == "lance") return ShogiSize::lance();
  if (piece == "pawn") return ShogiSize::pawn();
  return ShogiSize::king();
}

// The mesh rotated by the spec's rotation through `pivot`, then `shift` added.
void rotate_mesh(TetMesh& m, const MeshSpec& spec, Vec3 pivot, Vec3 shift) {
  for (auto& p : m.points) p = spec.rotate.apply(p, pivot) + shift;
}

TetMesh make_body_mesh(const BodySpec& b) {
  if (b.mesh.kind == MeshSpec::Kind::Box) {
    TetMesh m = make_box(b.mesh.origin, b.mesh.size, b.mesh.cells);
    if (!b.mesh.rotate.none()) rotate_mesh(m, b.mesh, b.mesh.origin, Vec3{});
    return m;
  }
  if (b.mesh.kind == MeshSpec::Kind::Shogi) {
    TetMesh m = make_shogi_piece(shogi_preset(b.mesh.piece), b.mesh.mesh_size);
    rotate_mesh(m, b.mesh, Vec3{}, b.mesh.translate);
    return m;
  }
  TetMesh m = read_gmsh(b.mesh.file);
  for (auto& p : m.points) p = b.mesh.scale * p + b.mesh.translate;
  return m;
}

std::string describe(const Region& r) {
  std::string s;
  const char* ax = "xyz";
  for (int a = 0; a < 3; ++a)
    if (std::isfinite(r.range[a][0]) || std::isfinite(r.range[a][1]))
      s +=
          fmt::format("{}{}: [{}, {}]", s.empty() ? "" : ", ", ax[a], r.range[a][0], r.range[a][1]);
  return "{" + s + "}";
}

bool all_inside(const Region& r, const std::vector<Vec3>& X,
                const std::array<std::int32_t, 3>& tri) {
  return r.contains(X[tri[0]]) && r.contains(X[tri[1]]) && r.contains(X[tri[2]]);
}

void assign_relaxation_mass(Model& model) {
  std::vector<double> dt(model.n_free_tets);
  double target = 0;
  for (std::int64_t t = 0; t < model.n_free_tets; ++t) {
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = model.X[model.tets[t][k]];
    dt[t] = tet_critical_dt(model.materials[model.tet_material[t]], min_altitude(p));
    target = std::max(target, dt[t]);
  }
  std::vector<double> mass(model.X.size(), 0.0);
  for (std::int64_t t = 0; t < model.n_free_tets; ++t) {
    const double rho = model.materials[model.tet_material[t]].density;
    const double scale = (target / dt[t]) * (target / dt[t]);
    for (int k = 0; k < 4; ++k) mass[model.tets[t][k]] += scale * rho * model.vol0[t] / 4.0;
  }
  model.relax_inv_mass.assign(model.X.size(), 0.0);
  for (std::size_t i = 0; i < mass.size(); ++i)
    if (model.inv_mass[i] > 0 && mass[i] > 0) model.relax_inv_mass[i] = 1.0 / mass[i];
  model.relax_dt = 0.9 * target;
}

}  // namespace

namespace {

Model assemble(const Scene& scene) {
  Model model;
  model.gravity = scene.gravity;
  model.mass_damping = scene.mass_damping;
  for (const auto& m : scene.materials)
    model.materials.push_back(
        make_material(m.law == MaterialLaw::Linear ? 0 : 1, m.E, m.nu, m.density, m.viscosity));

  // Free bodies first, fixed bodies last (stable within each group).
  std::vector<int> order(scene.bodies.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_partition(order.begin(), order.end(), [&](int i) { return !scene.bodies[i].fixed; });
  std::vector<int> body_slot(scene.bodies.size());
  std::vector<std::uint8_t> tet_is_surface;  // per global tet (edge rule), for contact

  for (int bi : order) {
    const BodySpec& spec = scene.bodies[bi];
    const TetMesh mesh = make_body_mesh(spec);
    const Material& mat = model.materials[spec.material];
    BodyRange range;
    range.name = spec.name;
    range.fixed = spec.fixed;
    range.material = spec.material;
    range.scene_index = bi;
    range.v_begin = model.n_vertices();
    range.t_begin = model.n_tets();
    const auto voff = static_cast<std::int32_t>(range.v_begin);
    body_slot[bi] = static_cast<int>(model.bodies.size());

    // Mass is lumped: rho V / 4 to each vertex of a tet.
    std::vector<double> mass(mesh.points.size(), 0.0);
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
      Vec3 p[4];
      for (int k = 0; k < 4; ++k) p[k] = mesh.points[mesh.tets[t][k]];
      const Mat3 dX = edge_matrix(p);
      const double V = det(dX) / 6.0;
      if (!(V > 0))
        throw InputError(fmt::format(
            "body '{}': tet {} is {} (volume {:.3e}); meshes must hold positively oriented, "
            "non-degenerate tetrahedra",
            spec.name, t, V < 0 ? "inverted" : "degenerate", V));
      std::array<std::int32_t, 4> tv;
      for (int k = 0; k < 4; ++k) tv[k] = mesh.tets[t][k] + voff;
      model.tets.push_back(tv);
      model.dX_inv.push_back(inverse(dX));
      model.vol0.push_back(V);
      model.tet_material.push_back(spec.material);
      model.tet_gid.push_back(model.tet_gid.size());
      for (int k = 0; k < 4; ++k) mass[mesh.tets[t][k]] += mat.density * V / 4.0;
      if (!spec.fixed) {
        const double dt = tet_critical_dt(mat, min_altitude(p));
        if (model.dt_critical_tet < 0 || dt < model.dt_critical) {
          model.dt_critical = dt;
          model.dt_critical_tet = static_cast<std::int64_t>(model.tets.size()) - 1;
        }
      }
    }

    // Initial velocity: translation plus rotation about the body's centre of mass.
    Vec3 com{0, 0, 0};
    double mtot = 0;
    for (std::size_t i = 0; i < mesh.points.size(); ++i) {
      com += mass[i] * mesh.points[i];
      mtot += mass[i];
    }
    com = com / mtot;
    for (std::size_t i = 0; i < mesh.points.size(); ++i) {
      if (mass[i] == 0)
        throw InputError(
            fmt::format("body '{}': vertex {} belongs to no tetrahedron", spec.name, i));
      const Vec3 p = mesh.points[i];
      model.X.push_back(p);
      model.x.push_back(p);
      model.v.push_back(spec.fixed ? Vec3{}
                                   : spec.velocity + cross(spec.angular_velocity, p - com));
      model.mass.push_back(mass[i]);
      model.inv_mass.push_back(spec.fixed ? 0.0 : 1.0 / mass[i]);
      model.flags.push_back(spec.fixed ? kFixed : 0);
      model.gid.push_back(model.gid.size());
      model.body.push_back(body_slot[bi]);
    }
    const SurfaceInfo surf = analyse_surface(mesh);
    tet_is_surface.insert(tet_is_surface.end(), surf.tet_is_surface.begin(),
                          surf.tet_is_surface.end());
    for (const auto& tri : surf.triangles) {
      SurfaceTriangle g = tri;
      for (auto& v : g.v) v += voff;
      g.tet += static_cast<std::int32_t>(range.t_begin);
      model.surface.push_back(g);
      model.surface_body.push_back(body_slot[bi]);
      for (auto v : g.v) model.flags[v] |= kSurface;
    }
    range.v_end = model.n_vertices();
    range.t_end = model.n_tets();
    model.bodies.push_back(range);
    if (!spec.fixed) {
      model.n_free_vertices = range.v_end;
      model.n_free_tets = range.t_end;
    }
  }
  model.fext.assign(model.X.size(), Vec3{});
  model.fpre.assign(model.X.size(), Vec3{});

  // Constraints.
  for (std::size_t c = 0; c < scene.constraints.size(); ++c) {
    const ConstraintSpec& cs = scene.constraints[c];
    const BodyRange& b = model.bodies[body_slot[cs.body]];
    std::int64_t count = 0;
    for (std::int64_t i = b.v_begin; i < b.v_end; ++i) {
      if (!cs.region.contains(model.X[i])) continue;
      ++count;
      const auto& held = cs.components;
      if (cs.kind == ConstraintSpec::Kind::Fixed && !(held[0] && held[1] && held[2])) {
        for (int a = 0; a < 3; ++a)
          if (held[a]) {
            model.flags[i] |= static_cast<std::uint8_t>(kHoldX << a);
            model.v[i][a] = 0;
          }
        continue;
      }
      model.inv_mass[i] = 0;
      if (cs.kind == ConstraintSpec::Kind::Fixed) {
        model.flags[i] |= kFixed;
        model.v[i] = Vec3{};
      } else {
        model.flags[i] |= kPrescribed;
        model.v[i] = cs.velocity;
      }
    }
    if (count == 0)
      throw InputError(fmt::format("constraints[{}].region {} selects no vertex of body '{}'", c,
                                   describe(cs.region), b.name));
  }

  // Loads.
  for (std::size_t l = 0; l < scene.loads.size(); ++l) {
    const LoadSpec& ls = scene.loads[l];
    const int slot = body_slot[ls.body];
    const BodyRange& b = model.bodies[slot];
    std::vector<Vec3>& target = ls.preload ? model.fpre : model.fext;
    if (ls.kind == LoadSpec::Kind::Traction) {
      // Consistent P1 load of a constant traction: area/3 to each triangle vertex.
      int count = 0;
      for (std::size_t s = 0; s < model.surface.size(); ++s) {
        if (model.surface_body[s] != slot) continue;
        const auto& tri = model.surface[s].v;
        if (!all_inside(ls.region, model.X, tri)) continue;
        const double area =
            0.5 * norm(cross(model.X[tri[1]] - model.X[tri[0]], model.X[tri[2]] - model.X[tri[0]]));
        for (auto v : tri) target[v] += (area / 3.0) * ls.traction;
        ++count;
      }
      if (count == 0)
        throw InputError(fmt::format(
            "loads[{}].region {} contains no surface triangle of body '{}' (all 3 vertices "
            "must lie inside)",
            l, describe(ls.region), b.name));
    } else {
      std::int64_t best = -1;
      double d2 = std::numeric_limits<double>::infinity();
      for (std::int64_t i = b.v_begin; i < b.v_end; ++i)
        if (norm2(model.X[i] - ls.point) < d2) {
          d2 = norm2(model.X[i] - ls.point);
          best = i;
        }
      target[best] += ls.force;
    }
  }
  build_contact_model(scene, model, tet_is_surface);
  if (model.contact.enabled) check_initial_overlap(model);
  if (model.contact.enabled && model.contact.dt_limit > 0 && model.dt_critical_tet >= 0 &&
      model.contact.dt_limit < model.dt_critical)
    model.dt_critical = model.contact.dt_limit;
  assign_relaxation_mass(model);
  return model;
}

}  // namespace

// Errors found while assembling (a region selecting nothing, bodies overlapping, a mesh file)
// name the scene file first, like the parser's.
Model build_model(const Scene& scene) {
  try {
    return assemble(scene);
  } catch (const InputError& e) {
    const std::string file = scene.file.string(), what = e.what();
    if (file.empty() || what.rfind(file, 0) == 0) throw;
    throw InputError(file + ": " + what);
  }
}

}  // namespace qdemsph
