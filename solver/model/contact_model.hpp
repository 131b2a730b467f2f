// Host-side contact topology and parameters, built once from the assembled Model
// (METHOD.md section 3). The contact stage (contact/contact_stage.hpp) uploads it.
//
// Features: surface triangles (outward), their unique edges and vertices. Every surface
// vertex and edge is *owned* by exactly one triangle (the lowest-numbered one containing it),
// so a triangle pair (a, b) tests owned(a) x b, owned(b) x a (point-face) and
// owned-edges(a) x owned-edges(b) (edge-edge): each feature pair is tested once.
// Primitives registered in the cell list (report Fig. 7 modes):
//   all_tets       every tet, with the surface triangles it owns (A)
//   surface_tets   tets touching the surface by an edge (report: 2,028 per 8^3 cube) (B)
//   polygons       surface triangles themselves (C, default)
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

struct Model;
struct Scene;

enum class BroadPhase : int { AllTets = 0, SurfaceTets = 1, Polygons = 2 };
const char* broad_phase_name(BroadPhase b);

struct ContactWall {
  Vec3 point, normal;  // normal: unit, pointing into the free half-space
  double mu = 0, zeta = 0;
  double stiffness = 0;  // [N/m]; 0: default from the touching body's E and mesh size
};

struct ContactModel {
  bool enabled = false;
  BroadPhase mode = BroadPhase::Polygons;
  double d_dem = 0;  // virtual DEM particle diameter [m]
  bool self_contact = false;
  double kn_factor = 0.1;  // default k_n = kn_factor * E_pair * h_pair
  double kt_ratio = 2.0 / 7.0;
  double skin = -1;            // pair-list Verlet skin [m]; < 0: auto (D_DEM + max r / 4)
  double max_penetration = 0;  // penetration guard [m]; 0: half the pair's mean surface edge

  // Surface triangles (global vertex ids), owning body; unique edges; ownership CSR.
  std::vector<std::array<std::int32_t, 3>> tri_v;
  std::vector<std::int32_t> tri_body;
  std::vector<std::array<std::int32_t, 2>> edges;     // (a, b), a < b, sorted
  std::vector<std::array<std::int32_t, 2>> edge_tri;  // the edge's two triangles (-1: none)
  std::vector<std::int64_t> own_v_off, own_e_off;     // size n_tri + 1
  std::vector<std::int32_t> own_v, own_e;             // vertex ids / edge ids

  // Primitives of the broad phase: up to 4 vertices (-1 padded), body, owned triangles.
  std::vector<std::array<std::int32_t, 4>> prim_v;
  std::vector<std::int32_t> prim_body;
  std::vector<std::int64_t> prim_tri_off;
  std::vector<std::int32_t> prim_tri;
  std::int64_t n_free_prims = 0;  // primitives of free bodies come first (model ordering)

  std::vector<std::int32_t> wall_vertices;  // free surface vertices (tested against walls)
  std::vector<ContactWall> walls;

  // Per body and per material pair (n_mat x n_mat, symmetric).
  std::vector<double> body_h;  // mean surface edge length [m]
  std::vector<std::uint8_t> body_fixed;
  std::vector<std::int32_t> body_mat;
  // A distributed rank's part only (else empty): per body, BodyWhole (contact_record.hpp).
  std::vector<std::uint8_t> body_whole;
  int n_mat = 0;
  std::vector<double> pair_mu, pair_zeta, pair_kn, pair_E;

  std::int64_t n_surface_tets = 0;  // edge rule, all bodies
  double dt_limit = 0;              // contact stability estimate sqrt(m_min / k_n) (0: none)
};

// Fills model.contact from the scene (contact:, walls:) when the scene needs contact: two or
// more bodies of which one is free, walls with a free body, or self_contact.
void build_contact_model(const Scene& scene, Model& model,
                         const std::vector<std::uint8_t>& tet_is_surface);

// "contact: N surface tets, M surface triangles" or "no contact: one body".
std::string describe_contact(const Model& model);

}  // namespace qdemsph
