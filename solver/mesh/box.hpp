// Structured box mesh generator: a grid of hexahedra, each split into 12 tetrahedra around a
// body-centre vertex (the report's cube: 8x8x8 hexes -> 6,144 tets, 1,241 vertices, 386 on the
// surface). Neighbouring hexes conform: each face diagonal is chosen from the face alone.
#pragma once

#include <array>

#include "core/vec.hpp"
#include "mesh/tet_mesh.hpp"

namespace qdemsph {

// Box [origin, origin + size] with cells[d] >= 1 hexes along axis d.
// Vertex numbering: the (cells+1)^3 grid nodes first (i fastest, then j, then k), then the hex
// centres in the same order. Tets are listed hex by hex (same order), 12 per hex, all
// positively oriented. Throws InputError for non-positive sizes or cell counts.
TetMesh make_box(Vec3 origin, Vec3 size, std::array<int, 3> cells);

}  // namespace qdemsph
