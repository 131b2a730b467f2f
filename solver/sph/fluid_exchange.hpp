// What the SPH stage needs from a distributed run (docs/parallel.md, "Fluid"), without MPI:
// the implementation is parallel/fluid_exchange.cpp; a one-rank stage has none.
//
// A rank's particles are its owned ones (fluid and walls, by the decomposition's owner of
// their position) followed by ghosts: copies of other ranks' particles within one kernel
// support of an owned particle. Ghost slots are refreshed from their owners after each pass
// that changes what the next pass reads (density, then wall pressure).
//
// Order key: every particle carries the key of its place in the order one rank would have it
// in (sph_stage.hpp: (group, cell) of the last sort, then its place in that cell; before the
// first sort its global id). A rank that holds every particle of a cell puts them in the
// one-rank order by sorting its particles by this key before the stable cell sort, so each
// particle sums its neighbours in the one-rank order and the run equals one rank bit for bit.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

// The per-particle fields that travel with a particle (x, v, rho, m carry state across
// steps; type, gid, key name it).
struct FluidParticles {
  std::vector<Vec3> x, v;
  std::vector<double> rho, m;
  std::vector<std::uint8_t> type;
  std::vector<std::uint64_t> gid, key;
  std::size_t size() const { return x.size(); }
};

class FluidExchange {
 public:
  virtual ~FluidExchange() = default;
  // In: this rank's owned particles. Out: the particles it owns now (migrated to the owner of
  // their position), then the ghosts it needs; returns the owned count. Collective.
  virtual std::int64_t distribute(FluidParticles& p) = 0;
  // Owned values -> ghost slots of the layout distribute() returned (fields of n_total
  // items, owned first). Collective.
  virtual void refresh(std::span<const std::span<double>> fields) = 0;
  // Reductions over the ranks, the same result on every rank. Collective.
  virtual void sum(std::span<double> v) = 0;
  virtual void max(std::span<double> v) = 0;
  // Every rank's items concatenated on rank 0 (empty elsewhere). Collective.
  virtual std::vector<Vec3> gather(const std::vector<Vec3>& mine) = 0;
  virtual std::vector<double> gather(const std::vector<double>& mine) = 0;
  virtual std::vector<std::uint8_t> gather(const std::vector<std::uint8_t>& mine) = 0;
  virtual std::vector<std::uint64_t> gather(const std::vector<std::uint64_t>& mine) = 0;
  virtual int rank() const = 0;
  virtual int size() const = 0;
};

}  // namespace qdemsph
