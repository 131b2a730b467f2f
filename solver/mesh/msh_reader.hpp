// qdemsph's own reader of Gmsh .msh files: MSH 2.x and 4.1, ASCII and binary (little-endian,
// as gmsh writes them). It returns the nodes and the linear tetrahedra (element type 4)
// exactly as libgmsh's getNodes / getElementsByType(4) would after gmsh::merge (tests compare
// the two), without the library: the GPU machines have no gmsh, and libgmsh 4.8 crashed or
// allocated without bound on corrupt files.
//
// Robustness contract: any byte string gives either data or an InputError "SOURCE: truncated
// or corrupt: REASON (line L)" (ASCII) / "(byte B)" (binary data). Every count a file declares
// is checked against the bytes left before anything is allocated for it, so memory stays
// within a small multiple of the file size.
//
// Sections read: $MeshFormat, $Nodes, $Elements; others ($PhysicalNames, $Entities,
// $Periodic, $NodeData, ...) are skipped to their $End line. Elements of other types are
// skipped; their node counts come from gmsh's table (types 1-31, 92, 93); an unknown type is
// an error, as in gmsh.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace qdemsph {

struct MshData {
  std::vector<std::size_t> node_tags;  // every node of the file
  std::vector<double> coords;          // x, y, z per node
  // Linear tets in libgmsh's order: grouped by volume entity (ascending tag), file order
  // within an entity; 4 node tags each.
  std::vector<std::size_t> tet_tags, tet_nodes;
};

// `source` starts every message (e.g. "mesh file 'beam.msh'").
MshData parse_msh(std::string_view bytes, const std::string& source);

}  // namespace qdemsph
