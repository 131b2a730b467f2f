// The SPH fluid on several MPI ranks (docs/parallel.md, "Fluid"): the FluidExchange a rank's
// SphStage calls (sph/fluid_exchange.hpp), on MPI_COMM_WORLD.
//
// Ownership: a particle (fluid or wall) belongs to the rank whose piece of the space-filling
// curve holds its position (balance.hpp: the fluid's own cell tree, cut by particle cost: the
// neighbour candidates each particle visited in the last evaluation, sph_stage.hpp; before
// any, 1 per fluid particle and kFluidWallCost per wall particle). distribute() migrates the owned
// particles to the owners of their positions (MigratePlan) and builds the ghosts (HaloPlan):
// a particle goes to every rank that owns a particle in the 5^3 band cells of half a kernel
// support + skin around its own cell, i.e. to every rank with an owned particle within
// support + skin of it. The stage calls distribute() only when keep() says the layout no
// longer holds: some particle moved more than its reach since (one MPI_Allreduce of the
// largest displacement as a multiple of the reach per step; the reach is skin / 2 where another
// rank's particles are within the ghost band, up to ~4 band cells where none is within 8), or
// the partition is cut again (every rebalance_every steps, when the owned cost's max / mean - 1
// exceeds rebalance_threshold); between, the ghosts' x and v are refreshed through the same
// HaloPlan at each step.
#pragma once

#include <memory>

#include "parallel/distributed_backend.hpp"
#include "parallel/rebuild_policy.hpp"
#include "sph/fluid_exchange.hpp"
#include "sph/fluid_setup.hpp"

namespace qdemsph {

// A wall particle's cost next to a fluid particle's 1 before any is measured: one pass over
// its fluid neighbours (Adami) against a fluid particle's two passes over all neighbours.
inline constexpr double kFluidWallCost = 0.25;

// The ghost band's skin as a fraction of the kernel support: a wider band holds more ghosts
// (band volume ~ (support + skin)^3 around a piece), a narrower one is rebuilt more often.
// The first layout's; a run whose rebuilds cost more than 10 % of its stepping widens it at a
// rebuild (widened_margin), up to kMaxMarginGrowth x (parallel.fluid_skin in summary.json).
// A quarter support (h / 2, ~25 % more band width) lasts at least ~11 steps: at the CFL limit
// (dt = 0.25 h / (c + v), c >= 10 v) a particle moves < 0.023 h per step, skin / 2 = h / 4;
// the 3,280-particle test dam break (test_distributed_fluid.cpp) rebuilds after 37-133 steps.
inline constexpr double kFluidSkin = 0.25;
// The most the skin widens at a rebuild (widened_margin): a ghost carries the SPH passes, so a
// wider band costs every step. Unbounded, the dam break (scaling/, 4 x H100) widened its skin
// at once to 0.0105-0.0111 m instead of 0.0065 (2 x): the same one layout in the run, 20-25 %
// more ghost traffic, and a step of 5.10-5.17 ms instead of 4.98-5.01.
inline constexpr double kFluidSkinStep = 2;

// For the stage of `fluid`, whose arrays live in `space`: the ghost band is its kernel
// support 2h x (1 + kFluidSkin) wide, and wraps its periodic z (fluid.periodic_z).
std::unique_ptr<FluidExchange> make_fluid_exchange(const ParallelOptions& options,
                                                   const FluidSetup& fluid,
                                                   Space space = Space::Host);

}  // namespace qdemsph
