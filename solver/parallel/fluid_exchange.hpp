// The SPH fluid on several MPI ranks (docs/parallel.md, "Fluid"): the FluidExchange a rank's
// SphStage calls (sph/fluid_exchange.hpp), on MPI_COMM_WORLD.
//
// Ownership: a particle (fluid or wall) belongs to the rank whose piece of the space-filling
// curve holds its position (balance.hpp: the fluid's own cell tree, cut by particle cost:
// 1 per fluid particle, kFluidWallCost per wall particle). Each compute() migrates the owned
// particles to the owners of their new positions (MigratePlan) and rebuilds the ghosts
// (HaloPlan): a particle goes to every rank that owns a particle in the 5^3 band cells of
// half a kernel support around its own cell, i.e. to every rank with an owned particle within
// one support of it. The plans are rebuilt at every step (no skin: the fluid re-sorts every
// step anyway). Every rebalance_every steps the partition is cut again when the owned cost's
// max / mean - 1 exceeds rebalance_threshold.
#pragma once

#include <memory>

#include "parallel/distributed_backend.hpp"
#include "sph/fluid_exchange.hpp"

namespace qdemsph {

// A wall particle's cost next to a fluid particle's 1: one pass over its fluid neighbours
// (Adami) against a fluid particle's two passes over all neighbours.
inline constexpr double kFluidWallCost = 0.25;

// support: the kernel support 2h (the ghost band's width).
std::unique_ptr<FluidExchange> make_fluid_exchange(const ParallelOptions& options, double support);

}  // namespace qdemsph
