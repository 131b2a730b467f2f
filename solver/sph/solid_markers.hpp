// Boundary markers of QDEM bodies for the fluid (METHOD.md section 5): dummy particles that
// make a body's surface a moving Adami wall for the SPH fluid and carry the fluid's forces back
// to the body's vertices.
//
// Placement (host, once, reference configuration): per body, a lattice over its bounding box
// with the pitch closest to the fluid spacing dx that fits the box exactly (n_a = round(L_a /
// dx) points per axis at the cell centres, so a box body gets its first marker layer dx/2
// inside every face, like a tank's wall particles); only lattice points inside the body and
// closer to its surface than the kernel support 2h are kept (deeper ones never see fluid).
// Each marker is embedded in the tet that contains it: its position and velocity are the
// barycentric interpolation x_m = sum_c w_c x_{v_c} of the tet's 4 vertices, so markers follow
// the body's deformation. A force F on a marker goes to the vertices as w_c F (the transpose of
// the interpolation: sum_c w_c = 1, so momentum is passed on exactly).
//
// The same construction as a solid's dummy particles in Adami, Hu & Adams (2012) for moving
// walls and in SPH-solid FSI codes (e.g. SPHinXsys: Zhang, Rezavand & Hu 2021, J. Comput. Phys.
// 429), with the solid's particles replaced by points embedded in the tet mesh.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

struct Model;

struct SolidMarkers {
  std::vector<Vec3> x;                          // reference positions
  std::vector<std::array<std::int32_t, 4>> tv;  // the embedding tet's vertices (global ids)
  std::vector<std::array<double, 4>> w;         // barycentric weights (sum 1)
  std::vector<double> volume;                   // lattice cell volume [m^3]
  std::vector<std::int32_t> body;               // model body index
  // Vertex -> entries (marker k, weight w) in increasing k: the gather of marker forces.
  std::vector<std::int32_t> vertices;  // coupled vertices (global ids), increasing
  std::vector<std::int64_t> offset;    // size vertices + 1
  std::vector<std::int32_t> entry_marker;
  std::vector<double> entry_weight;
  std::int64_t size() const { return static_cast<std::int64_t>(x.size()); }
};

// Markers of every body of the model (fixed bodies too: they are walls that do not move).
// Throws InputError naming the body when its bounding box is less than two lattice layers
// thick along an axis, or when it gets no marker.
SolidMarkers build_solid_markers(const Model& model, double dx, double support);

// Contact cell width of the model's surface (report eq. 9-10 as contact/contact_stage.hpp
// builds it in the default polygon mode, reference configuration): 2 max r + D_DEM + skin.
double contact_cell_width(const Model& model);

// InputError when the kernel support 2h exceeds the contact cell width: the fluid and the
// contact search share cells and halo widths (METHOD.md section 5).
void check_kernel_within_contact_cell(const Model& model, double support, double dx,
                                      double smoothing);

}  // namespace qdemsph
