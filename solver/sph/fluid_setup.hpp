// The fluid's initial particles and parameters on the host, built from the scene's `fluid:`
// section: fluid blocks, tanks (open-top containers of wall particles) and solid wall boxes on a
// lattice of pitch dx, the equation of state and the kernel. Stages upload it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.hpp"
#include "io/scene.hpp"
#include "physics/sph_pair.hpp"

namespace qdemsph {

enum SphType : std::uint8_t { kSphFluid = 0, kSphWall = 1 };

struct FluidSetup {
  SphParams params;
  double dx = 0;      // particle spacing
  double height = 0;  // largest fluid block height along gravity (for auto c0)
  Vec3 lo{}, hi{};    // box the neighbour grid covers (all particles plus a margin)
  std::vector<Vec3> x, v;
  std::vector<double> rho, p, m;
  std::vector<std::uint8_t> type;
  std::vector<std::uint64_t> gid;
  std::int64_t n_fluid = 0, n_wall = 0;
  std::int64_t size() const { return static_cast<std::int64_t>(x.size()); }
};

// Throws InputError for a fluid that cannot be set up (no gravity and no sound speed, no
// particle in a block, ...).
FluidSetup build_fluid(const FluidSpec& spec, Vec3 gravity);

// One line for `qdemsph info` / summary.json stages.
std::string describe_fluid(const FluidSetup& f);

}  // namespace qdemsph
