// Shogi piece generator (BENCHMARKS.md section 5): front view a pentagon (base corners 81 deg,
// shoulders 117 deg, apex at the top), side view a wedge thickest at the base. Meshed with the
// gmsh OpenCASCADE kernel. Lengths in metres.
#pragma once

#include <array>

#include "mesh/tet_mesh.hpp"

namespace qdemsph {

struct ShogiSize {
  double height = 0.032;             // base to apex, along +z
  double width = 0.0287;             // base width, along x
  double thickness = 0.0097;         // at the base, along y
  double top_thickness_ratio = 0.6;  // thickness at the apex height / thickness at the base

  static ShogiSize king() { return {0.032, 0.0287, 0.0097, 0.6}; }
  static ShogiSize rook() { return {0.031, 0.0277, 0.0093, 0.6}; }  // also bishop
  static ShogiSize gold() { return {0.030, 0.0267, 0.0088, 0.6}; }  // also silver
  static ShogiSize knight() { return {0.029, 0.0255, 0.0083, 0.6}; }
  static ShogiSize lance() { return {0.028, 0.0235, 0.0080, 0.6}; }
  static ShogiSize pawn() { return {0.027, 0.0225, 0.0075, 0.6}; }
};

// The front-view pentagon (x, z), counter-clockwise from the base's left corner: base
// (-w/2, 0), (w/2, 0), right shoulder, apex (0, h), left shoulder. Throws InputError when the
// sizes admit no such pentagon (shoulders below the base or above the apex).
std::array<std::array<double, 2>, 5> shogi_outline(const ShogiSize& size);

// Volume of the solid: the pentagon extruded symmetrically in y with thickness
// t(z) = thickness * (1 - (1 - ratio) z / height).
double shogi_volume(const ShogiSize& size);

// Mesh size (target edge length, metres) giving about 2,500 tets for `size` (the report's
// pieces have 2,566); scales with the piece.
double shogi_default_mesh_size(const ShogiSize& size);

// Tet mesh of the piece: base centred at the origin on z = 0, height along +z, thickness
// along y (front face y > 0). `mesh_size` is the target edge length; <= 0 picks
// shogi_default_mesh_size. Deterministic (single-threaded meshing).
TetMesh make_shogi_piece(const ShogiSize& size, double mesh_size = 0.0);

}  // namespace qdemsph
