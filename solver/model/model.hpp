// The assembled problem on the host: every body's vertices and tets in global arrays,
// materials, constraints and loads resolved to per-vertex values. Backends upload it.
//
// Ordering: vertices and tets of free bodies come first, fixed bodies last, so the element
// and integration stages run over the prefixes [0, n_free_vertices) and [0, n_free_tets):
// a fixed body costs no element or integration work.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.hpp"
#include "io/scene.hpp"
#include "mesh/tet_mesh.hpp"
#include "model/contact_model.hpp"
#include "physics/material.hpp"

namespace qdemsph {

enum VertexFlag : std::uint8_t {
  kFixed = 1,
  kPrescribed = 2,
  kSurface = 4,
  kHoldX = 8,  // a held component (a `fixed` constraint with `components`): bit kHoldX << a
  kHoldY = 16,
  kHoldZ = 32
};
// The held components of a vertex's flags as bits 0..2 (x, y, z).
inline std::uint8_t held_components(std::uint8_t flags) { return (flags / kHoldX) & 7; }

struct BodyRange {
  std::string name;
  std::int64_t v_begin = 0, v_end = 0;  // vertex range in the global arrays
  std::int64_t t_begin = 0, t_end = 0;  // tet range
  bool fixed = false;
  int material = 0;
  int scene_index = 0;  // index in Scene::bodies
};

struct Model {
  // Vertices.
  std::vector<Vec3> X;                 // reference positions
  std::vector<Vec3> x, v;              // initial state
  std::vector<Vec3> fext;              // dead loads applied during the run [N]
  std::vector<Vec3> fpre;              // dead loads of the initial static solve only (preload)
  std::vector<double> mass, inv_mass;  // inv_mass = 0 on fixed and prescribed vertices
  std::vector<std::uint8_t> flags;
  std::vector<std::uint64_t> gid;
  std::vector<std::int32_t> body;  // index into bodies
  // Tets.
  std::vector<std::array<std::int32_t, 4>> tets;
  std::vector<Mat3> dX_inv;
  std::vector<double> vol0;
  std::vector<std::int32_t> tet_material;
  std::vector<std::uint64_t> tet_gid;
  // Vertex -> tet corners of the vertices the backend gathers forces for, [0, n_free_vertices):
  // CSR (n_free_vertices + 1 offsets), entry k * n_tets() + t for corner k of tet t, each
  // vertex's in (k, tet gid) order, the order its corner forces are summed in. Optional: a
  // model without them gets them built at upload (QdemBackend::upload_corner_lists); a rank's
  // part of a distributed model has them from the global model's (build_local_model).
  std::vector<std::int64_t> corner_off, corner_ent;
  // Surface triangles (global vertex ids), with the owning body.
  std::vector<SurfaceTriangle> surface;
  std::vector<std::int32_t> surface_body;

  std::vector<Material> materials;
  std::vector<BodyRange> bodies;
  std::int64_t n_free_vertices = 0, n_free_tets = 0;
  // Tets counted in the energies: [0, n_counted_tets), -1 = all free tets. A rank's part of
  // a distributed model (parallel/local_model.hpp) lists its home tets first, so that every
  // tet is counted once over the ranks although boundary tets are computed on several.
  std::int64_t n_counted_tets = -1;
  Vec3 gravity{0, 0, 0};
  double mass_damping = 0;

  ContactModel contact;  // surface topology and contact parameters (enabled when needed)

  // Dynamic relaxation (static mode) integrates with fictitious masses scaled per tet so
  // that every tet has the same stability limit relax_dt: the equilibrium does not depend
  // on the mass, but the iteration count does (small or distorted tets no longer set it).
  std::vector<double> relax_inv_mass;
  double relax_dt = 0;

  double dt_critical = 0;  // stability limit over free tets (and contact springs)
  std::int64_t dt_critical_tet = -1;

  std::int64_t n_vertices() const { return static_cast<std::int64_t>(X.size()); }
  std::int64_t n_tets() const { return static_cast<std::int64_t>(tets.size()); }
};

// Builds meshes, resolves regions, assembles mass and loads. Throws InputError naming the
// scene key or element when the input cannot make a valid model.
Model build_model(const Scene& scene);

}  // namespace qdemsph
