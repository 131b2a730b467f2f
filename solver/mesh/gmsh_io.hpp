// Gmsh .msh import (qdemsph's own reader, mesh/msh_reader.hpp: MSH 2.x and 4.1, ASCII and
// binary; no gmsh library) and export (MSH 4.1 ASCII, written as plain text), so that
// reference codes solve on the identical mesh (FEniCSx 0.5: gmsh.merge(path), then
// dolfinx.io.gmshio.model_to_mesh; 0.5.2's read_from_msh itself is broken).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/tet_mesh.hpp"

namespace qdemsph {

// Reads the linear tetrahedra (gmsh element type 4) of a .msh file; other element types are
// ignored. Vertices are the nodes used by at least one tet, renumbered compactly in node-tag
// order; tets in libgmsh's order (by volume entity, file order within one). Negatively
// oriented tets are reoriented (two vertices swapped). Throws InputError naming the path and
// the reason for a missing, unreadable, truncated or corrupt file (with the line or byte), a
// file without tetrahedra, or a degenerate tet (|volume| < 1e-12 * mean volume; the message
// names the element tag). The same mesh libgmsh's reader gave (test_msh_reader.cpp).
TetMesh read_gmsh(const std::filesystem::path& path);

// read_gmsh on the bytes of a file; `source` starts the messages.
TetMesh parse_gmsh(std::string_view bytes, const std::string& source);

// Writes `mesh` as Gmsh MSH 4.1 ASCII: node tags = index + 1, element tags = index + 1, one
// volume entity (tag 1) in the physical group 3/1 named "body". Throws InputError when the
// file cannot be written.
void write_gmsh(const std::filesystem::path& path, const TetMesh& mesh);

// Builds a TetMesh from gmsh's node and linear-tet arrays (as returned by
// gmsh::model::mesh::getNodes / getElementsByType(4)): used nodes renumbered compactly in tag
// order, negatively oriented tets reoriented. Throws InputError prefixed by `source` for no
// tets, a node tag given twice, a missing node or a degenerate tet (naming its element tag).
TetMesh tet_mesh_from_gmsh(const std::vector<std::size_t>& node_tags,
                           const std::vector<double>& coords,
                           const std::vector<std::size_t>& elem_tags,
                           const std::vector<std::size_t>& elem_nodes, const std::string& source);

}  // namespace qdemsph
