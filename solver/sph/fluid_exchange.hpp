// What the SPH stage needs from a distributed run (docs/parallel.md, "Fluid"), without MPI:
// the implementation is parallel/fluid_exchange.cpp; a one-rank stage has none.
//
// A rank's particles are its owned ones (fluid and walls, by the decomposition's owner of
// their position at the last distribute()) followed by ghosts: copies of other ranks'
// particles within one kernel support + skin of an owned particle then. The layout (who owns
// what, who holds which ghosts) stands while keep() says so: while no particle has moved more
// than its reach since distribute() (skin / 2 near another rank's particles, more deeper in
// the rank's piece: reach()), every particle within one support of an owned particle is still
// held. Meanwhile ghost slots are refreshed from their owners: positions and velocities at each
// step, then after each pass that changes what the next pass reads (density, then wall
// pressure).
//
// Order key: every particle carries the key of its place in the order one rank would have it
// in (sph_stage.hpp: (group, cell) of the last sort, then its place in that cell; before the
// first sort its global id). A rank that holds every particle of a cell puts them in the
// one-rank order by sorting its particles by this key before the stable cell sort, so each
// particle sums its neighbours in the one-rank order and the run equals one rank bit for bit.
// While the layout stands the rank's stable cell sort keeps that order by itself (its order
// within a cell is the one-rank order restricted to the particles it holds, and a stable sort
// of such an order by the new cells is again one), so only distribute() needs the keys.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/memory.hpp"
#include "core/timers.hpp"
#include "core/vec.hpp"

namespace qdemsph {

// The per-particle fields that travel with a particle (x, v, rho, m carry state across
// steps; type, gid, key name it), and two that do not: what each cost in the last evaluation
// (empty: not measured yet) and its owned slot in the layout the last distribute() returned
// (empty: none, as at the first one).
struct FluidParticles {
  std::vector<Vec3> x, v;
  std::vector<double> rho, m;
  std::vector<std::uint8_t> type;
  std::vector<std::uint64_t> gid, key;
  std::vector<double> cost;
  std::vector<std::int64_t> slot;
  std::size_t size() const { return x.size(); }
};

// What a distributed fluid sent between ranks so far, summed over the ranks (summary.json
// `parallel`: docs/parallel.md, "Records"). Bytes sent to another rank; a rank's copies to
// itself are not counted.
struct FluidTraffic {
  std::int64_t evaluations = 0;     // fluid evaluations (SphStage::compute() calls)
  std::int64_t rebuilds = 0;        // distribute() calls
  std::int64_t recuts = 0;          // of them, those that cut the partition again
  std::int64_t halo_bytes = 0;      // ghost slots filled at each distribute() and refreshed
  std::int64_t migrated_bytes = 0;  // particles moved to new owners at each distribute()
  std::int64_t band_bytes = 0;      // border band cells allgathered at each distribute()
  double skin = 0;                  // the ghost band's skin at the end [m] (it may widen)
};

class FluidExchange {
 public:
  virtual ~FluidExchange() = default;
  // In: this rank's owned particles, with their costs when measured (a new partition weights
  // them) and their slots in the last layout when it had one (a rebuild on the standing cut
  // then skips the owner search for particles deep inside this rank's piece). Out: the
  // particles it owns now (migrated to the owner of their position), then the ghosts it needs
  // (cost and slot empty); returns the owned count. Its parts are timed into `timers`
  // (sph.rebuild.owners, .migrate, .ghosts, .halo). Collective.
  virtual std::int64_t distribute(FluidParticles& p, PhaseTimers& timers) = 0;
  // At each step after the first distribute(): true when the layout still holds, given this
  // rank's largest displacement of an owned particle since distribute() as a multiple of its
  // reach (`reached`) and its owned particles' cost in the last evaluation (0: not measured)
  // (false: some particle over the ranks has moved more than its reach, or the partition is due
  // to be cut again; call distribute()). The same answer on every rank. Collective.
  virtual bool keep(double reached, double load) = 0;
  // Whether the next keep() reads `load` (a measurement is due); otherwise 0 will do.
  virtual bool wants_load() const = 0;
  // The ghost band's margin beyond the kernel support.
  virtual double skin() const = 0;
  // Per owned layout slot of the last distribute(): how far the particle may move while the
  // layout stands (skin() / 2 where another rank's particles are within the ghost band, more
  // where none is for several band cells around).
  virtual const std::vector<double>& reach() const = 0;
  // Per owned layout slot of the last distribute(): the depth of its band cell in this rank's
  // piece, 0 where another rank's particle may come within the kernel support while the layout
  // stands (every send_slots() entry is such a slot); elsewhere no ghost comes that near.
  virtual const std::vector<std::uint8_t>& depth() const = 0;
  // Owned values -> ghost slots of the layout distribute() returned, in records the caller
  // packs where its arrays live (a GPU stage on the device): fill send_buffer(stride) with
  // one record of `stride` bytes per entry of send_slots() (owned layout slots; they stand
  // until the next distribute()), then begin_refresh() and finish_refresh(), which returns the
  // records received, the k-th for the ghost in layout slot n_owned + k. Work queued between
  // the two runs while the records travel. Both buffers are in buffer_space(): host memory, or
  // a GPU stage's device memory when the ranks' GPUs share a node (records of at most 6
  // doubles; parallel/comm_plan.hpp, CommEngine::use_device). There, mark_packed() after
  // queueing the pack makes begin_refresh() wait for the device work queued up to it only.
  // Collective.
  virtual const std::vector<std::int64_t>& send_slots() const = 0;
  virtual std::span<std::byte> send_buffer(std::size_t stride) = 0;
  virtual void mark_packed() = 0;
  virtual void begin_refresh() = 0;
  virtual std::span<const std::byte> finish_refresh() = 0;
  virtual Space buffer_space() const = 0;
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
  // The traffic so far, the same on every rank. Collective.
  virtual FluidTraffic traffic() = 0;
};

}  // namespace qdemsph
