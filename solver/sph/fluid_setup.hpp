// The fluid's initial particles and parameters on the host, built from the scene's `fluid:`
// section: fluid blocks, tanks (open-top containers of wall particles) and solid wall boxes on a
// lattice of pitch dx, the equation of state and the kernel; plus the boundary markers of the
// QDEM bodies the fluid is coupled to. Stages upload it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.hpp"
#include "io/scene.hpp"
#include "physics/sph_pair.hpp"
#include "sph/solid_markers.hpp"

namespace qdemsph {

// Particle types: fluid, fixed wall particle, boundary marker of a QDEM body (moves with it).
enum SphType : std::uint8_t { kSphFluid = 0, kSphWall = 1, kSphSolid = 2 };

struct FluidSetup {
  SphParams params;
  double dx = 0;                // particle spacing
  double height = 0;            // largest fluid block height along gravity (for auto c0)
  Vec3 lo{}, hi{};              // box the neighbour grid covers (all particles plus a margin)
  double z0 = 0, period_z = 0;  // periodic_z: [z0, z0 + period_z] (period_z 0: not periodic)
  std::vector<Vec3> x, v;
  std::vector<double> rho, p, m;
  std::vector<std::uint8_t> type;
  std::vector<std::uint64_t> gid;
  std::int64_t n_fluid = 0, n_wall = 0, n_marker = 0;
  SolidMarkers markers;  // particles [n_fluid + n_wall, size()), gid = their index
  std::int64_t size() const { return static_cast<std::int64_t>(x.size()); }
};

// Throws InputError for a fluid that cannot be set up (no gravity and no sound speed, no
// particle in a block, ...).
FluidSetup build_fluid(const FluidSpec& spec, Vec3 gravity);

// Adds the boundary markers of every body of the model (type kSphSolid, after the walls) and
// grows the neighbour box to cover them. Checks the kernel support against the contact cell
// width (InputError).
void add_solid_markers(FluidSetup& f, const Model& model);

// One line for `qdemsph info` / summary.json stages.
std::string describe_fluid(const FluidSetup& f);

}  // namespace qdemsph
