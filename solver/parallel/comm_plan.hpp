// Communication as plans (STYLE.md item 6): MigratePlan moves items to new owner ranks,
// HaloPlan gives neighbour ranks copies of the items in the halo band (gather) and adds the
// copies' contributions back to the owners (scatter-add). Both are built per decomposition
// from (item -> destination ranks) lists (a layout rebuild plans them again on the same engine,
// replan()) and applied to any number of fields every step; both run on one pack/send/unpack
// engine (CommEngine).
//
// Overlap: begin() packs and posts non-blocking sends and receives, finish() waits and
// unpacks; interior work that does not touch the destination slots goes in between. One
// exchange per plan may be in flight at a time; plans are independent of each other (each
// has its own duplicated communicator), so a migration and a halo exchange may overlap.
//
// Identity: items carry 64-bit global ids; a plan exchanges them when it is built, so the
// receiver knows which item each new slot holds (MigratePlan::new_gids,
// HaloPlan::ghost_gids) and re-maps connectivity by id, never by a sender's local index.
//
// Order: received items are laid out by source rank, then by the sender's local order, so
// layouts and the order of scatter-add sums are deterministic for a given decomposition.
//
// Fields are arrays of trivially copyable elements in host memory, one per SoA component
// (a Vec3Buffer is three fields). The engine packs item-major (all fields of one item
// together) so that each message is one contiguous block.
//
// This folder is the only place that includes <mpi.h>.
#pragma once

// The C API only (no deprecated C++ bindings).
#ifndef OMPI_SKIP_MPICXX
#define OMPI_SKIP_MPICXX 1
#endif
#ifndef MPICH_SKIP_MPICXX
#define MPICH_SKIP_MPICXX 1
#endif
#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

#include "core/exec_host.hpp"
#include "core/memory.hpp"

namespace qdemsph {

// A type-erased view of one field: n items of `elem` bytes each.
struct CommField {
  std::byte* data = nullptr;
  std::int64_t n = 0;
  std::size_t elem = 0;
  void (*add)(std::byte* dst, const std::byte* src) = nullptr;  // dst += src; null: no sum
};

namespace detail {
template <class T>
void comm_add(std::byte* dst, const std::byte* src) {
  T a, b;
  std::memcpy(&a, dst, sizeof(T));
  std::memcpy(&b, src, sizeof(T));
  a += b;
  std::memcpy(dst, &a, sizeof(T));
}
template <class T>
constexpr auto comm_add_fn() {
  if constexpr (std::is_arithmetic_v<T>)
    return &comm_add<T>;
  else
    return static_cast<void (*)(std::byte*, const std::byte*)>(nullptr);
}
}  // namespace detail

// dst(k) <- src(k), elements of `elem` bytes, for k in [first, last), on the host's threads
// (independent copies: items into and out of message buffers, a layout's items). The common
// sizes (a byte, a double or id, a Vec3) are copies of a constant size, not a call to memcpy
// each.
template <class D, class S>
void copy_each(std::int64_t first, std::int64_t last, std::size_t elem, D dst, S src) {
  auto copy = [&](auto bytes) {
    for_each(HostExec{}, last - first, [&](std::int64_t i) {
      const std::int64_t k = first + i;
      std::memcpy(dst(k), src(k), bytes);
    });
  };
  switch (elem) {
    case 1:
      return copy(std::integral_constant<std::size_t, 1>{});
    case 8:
      return copy(std::integral_constant<std::size_t, 8>{});
    case 24:
      return copy(std::integral_constant<std::size_t, 24>{});
    default:
      return copy(elem);
  }
}

template <class T>
CommField comm_field(T* p, std::int64_t n) {
  static_assert(std::is_trivially_copyable_v<T>);
  return {reinterpret_cast<std::byte*>(p), n, sizeof(T), detail::comm_add_fn<T>()};
}
template <class T>
CommField comm_field(std::vector<T>& v) {
  return comm_field(v.data(), static_cast<std::int64_t>(v.size()));
}
template <class T>
CommField comm_field(View<T> v) {
  return comm_field(v.p, v.n);
}

// The pack/send/unpack engine. Send slots: the local items listed per destination rank
// (send_index, grouped by rank); receive slots: recv_base + k for the k-th received item.
// Forward: pack items at send_index, unpack into receive slots (assign).
// Reverse: pack receive slots, unpack into send_index items (add): the transpose.
class CommEngine {
 public:
  // dest_offsets (n_items + 1 entries) and dest_ranks: item i goes to ranks
  // dest_ranks[dest_offsets[i] .. dest_offsets[i + 1]). Collective over comm.
  CommEngine(MPI_Comm comm, std::span<const std::int64_t> dest_offsets,
             std::span<const int> dest_ranks, std::int64_t recv_base);
  // New lists, as a new engine would have them, keeping the duplicated communicator, the host
  // message buffers and, after use_device(), the device buffers and the mapped neighbours'
  // buffers (a caller that plans again allocates and maps them once): a sender's buffer is
  // mapped again only when some rank's must grow, or for a new neighbour; host staging again
  // when a neighbour is off this node now. Collective; none in flight.
  void replan(std::span<const std::int64_t> dest_offsets, std::span<const int> dest_ranks,
              std::int64_t recv_base);
  ~CommEngine();
  CommEngine(const CommEngine&) = delete;
  CommEngine& operator=(const CommEngine&) = delete;

  enum class Dir { Forward, Reverse };
  void begin(std::span<const CommField> src, Dir dir);
  void finish(std::span<const CommField> dst, Dir dir);
  // begin(src, Forward) and finish(dst, Forward) in one, the items this rank sends to itself
  // copied from src to dst directly while the others are in flight, not through the message
  // buffers (a migration keeps most items where they are).
  void forward(std::span<const CommField> src, std::span<const CommField> dst);
  bool in_flight() const { return in_flight_; }

  // Packed forward exchange, for callers that pack their own records (a GPU backend packs
  // on the device): fill packed_send_buffer(stride) with one record of `stride` bytes per
  // send slot, in send_index() order, then begin_packed(); finish_packed() waits and returns
  // the received records in receive-slot order (recv_base() + k for record k).
  const std::vector<std::int64_t>& send_index() const { return send_index_; }
  std::span<std::byte> packed_send_buffer(std::size_t stride);
  void begin_packed();
  std::span<const std::byte> finish_packed();

  // Device-resident packed exchange (GPU ranks of one node): once use_device() returned true,
  // packed_send_buffer() and finish_packed() are device memory of this process
  // (packed_space() == Space::Cuda) and no record passes through the host: a receiver copies
  // each sender's records straight out of the sender's device buffer, mapped by CUDA IPC
  // (over NVLink between the GPUs of an H100 host: 1 MB in 10 us against ~150 us through
  // host memory and MPI, scaling/probes/devicecomm.cu). Two empty messages per neighbour
  // order the copies: "packed" (begin_packed first waits for the device, or for its work up to
  // mark_packed(), so the records are there) and "copied" (waited for before the buffer is
  // packed again, packed_send_buffer, or replanned: finish_packed returns once this rank has
  // its records, and a rank that got them first goes on while its neighbours copy theirs; it
  // had waited for every neighbour's copy, cube block at 2 GPUs: the ranks got their records
  // together ~15-20 us after the earlier one could have). The copies run on the copy stream
  // (cuda_copy_async): kernels queued between begin_packed and finish_packed (the interior tets) go
  // on meanwhile, and the records are in finish_packed's buffer for every kernel queued after it.
  // Collective; true only when every rank asks (`want`), every neighbour is on this node and
  // QDEMSPH_DEVICE_HALO is not 0; otherwise records are staged through host memory as before.
  // Records of at most max_stride bytes.
  bool use_device(bool want, std::size_t max_stride);
  Space packed_space() const { return device_ ? Space::Cuda : Space::Host; }
  // Device-resident mode, after the pack is queued: begin_packed then waits for the device work
  // queued up to this point only (a DeviceMark), not for kernels queued between the two (the
  // interior tets, which so run while the exchange is posted). No-op in host mode.
  void mark_packed();

  // Variable-length exchange with the neighbours() (none in flight): records of `stride` bytes
  // in `send`, grouped by destination rank by send_off (size() + 1 entries); every destination
  // must be a neighbour or this rank. exchange_begin posts the sends (`send` must stay valid
  // until exchange_finish; other work goes on between, e.g. while the neighbours get there),
  // exchange_finish returns the records received, by source rank, then sender order.
  // last_bytes() becomes the bytes sent.
  void exchange_begin(std::span<const std::byte> send, std::span<const std::int64_t> send_off,
                      std::size_t stride);
  std::vector<std::byte> exchange_finish();

  std::int64_t n_send() const { return static_cast<std::int64_t>(send_index_.size()); }
  std::int64_t n_recv() const { return recv_off_.back(); }
  std::int64_t recv_base() const { return recv_base_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  // Ranks exchanged with (either direction), excluding this rank.
  const std::vector<int>& neighbours() const { return nbrs_; }
  // Bytes sent to other ranks by the last begin() and in total.
  std::int64_t last_bytes() const { return last_bytes_; }
  std::int64_t total_bytes() const { return total_bytes_; }
  // Wall seconds spent, summed over all exchanges: packing and posting (begin), waiting
  // for messages and unpacking (finish). Time between begin and finish is not counted.
  struct Seconds {
    double pack = 0, wait = 0, unpack = 0;
  };
  const Seconds& seconds() const { return seconds_; }

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  std::int64_t n_items_ = 0;  // local items the send lists index
  std::int64_t recv_base_ = 0;
  std::vector<std::int64_t> send_off_, recv_off_;  // per rank, size + 1 entries
  std::vector<std::int64_t> send_index_;
  std::vector<std::int64_t> item_of_;  // replan()'s work array: each destination entry's item
  std::vector<int> nbrs_;
  StagingBytes sendbuf_, recvbuf_;  // page-locked on a GPU rank (core/memory.hpp)
  std::vector<MPI_Request> reqs_;
  // Device-resident mode (use_device): this rank's device buffers, and per rank the mapped
  // send buffer of a neighbour that sends here, with the item where this rank's records start.
  bool device_ = false, marked_ = false;  // marked_: mark_packed() since the last post
  DeviceMark packed_;
  std::size_t max_stride_ = 0;
  IpcDeviceBytes dsend_, drecv_;
  std::vector<std::byte*> peer_;
  std::vector<std::int64_t> peer_off_;
  std::vector<MPI_Request> ready_;  // "packed" from the senders to this rank
  // The last device exchange's "packed" and "copied" messages still in flight (finish_device),
  // and the wait for them (the neighbours have copied this rank's records).
  std::vector<MPI_Request> copied_;
  void settle_copied();
  void no_exchange_in_flight() const;
  std::vector<char> on_node_;  // per rank: on this node (use_device)
  bool all_ranks(bool mine);   // mine on every rank (collective)
  bool neighbours_on_node() const;
  bool map_peers();
  void unmap_peers();
  void drop_device();
  void remap_device();
  void post_device();
  std::span<const std::byte> finish_device();
  std::size_t stride_ = 0;
  // begin() and finish() without this rank's own slots when not `self` (forward()): packs
  // src, posts receives and sends of the packed sendbuf_, waits and unpacks into dst. The
  // message buffers then leave those slots out: slot k of a buffer laid out along `off` (send
  // or receive offsets per rank) is record buffer_slot(k, off, self) (a migration keeps most
  // items, and a buffer of them all would be as large as the arrays).
  std::int64_t buffer_slot(std::int64_t k, const std::vector<std::int64_t>& off, bool self) const;
  void pack(std::span<const CommField> src, Dir dir, bool self);
  void post(Dir dir, bool self);
  void unpack(std::span<const CommField> dst, Dir dir, bool self);
  bool in_flight_ = false;
  Dir dir_ = Dir::Forward;
  // exchange_begin's: this rank's own records and the record size (exchanging_ until finish).
  bool exchanging_ = false;
  std::span<const std::byte> xself_;
  std::size_t xstride_ = 0;
  std::int64_t last_bytes_ = 0, total_bytes_ = 0;
  Seconds seconds_;
};

// Moves every item to one destination rank (possibly its own). After finish the local
// arrays hold n_new() items: those received, by source rank, then sender order.
class MigratePlan {
 public:
  // gid: the items' ids, sent along so that new_gids() names the received items.
  MigratePlan(MPI_Comm comm, std::span<const int> dest, std::span<const std::uint64_t> gid);
  // Without ids (a caller that migrates them as one of its fields): new_gids() empty.
  MigratePlan(MPI_Comm comm, std::span<const int> dest);
  // A plan for new destinations (without ids) on the same engine: a caller that migrates
  // repeatedly (a layout rebuild) keeps its communicator and message buffers. Collective.
  void replan(std::span<const int> dest);
  std::int64_t n_old() const { return n_old_; }
  std::int64_t n_new() const { return engine_->n_recv(); }
  const std::vector<std::uint64_t>& new_gids() const { return new_gids_; }

  // src fields have n_old() items, dst fields n_new(); they must be different arrays.
  void begin(std::span<const CommField> src) { engine_->begin(src, CommEngine::Dir::Forward); }
  void finish(std::span<const CommField> dst) { engine_->finish(dst, CommEngine::Dir::Forward); }
  // Both in one; the items that stay are copied directly (CommEngine::forward).
  void move(std::span<const CommField> src, std::span<const CommField> dst) {
    engine_->forward(src, dst);
  }
  // Blocking convenience: replaces v by its migrated contents.
  template <class T>
  void apply(std::vector<T>& v) {
    std::vector<T> out(static_cast<std::size_t>(n_new()));
    const CommField s = comm_field(v), d = comm_field(out);
    move({&s, 1}, {&d, 1});
    v.swap(out);
  }
  const CommEngine& engine() const { return *engine_; }

 private:
  // The engine's lists for dest: one destination per item (offsets 0, 1, ..., n_old_, kept).
  std::span<const std::int64_t> offsets_for(std::span<const int> dest);
  std::int64_t n_old_ = 0;
  std::vector<std::int64_t> offsets_;
  std::unique_ptr<CommEngine> engine_;
  std::vector<std::uint64_t> new_gids_;
};

// Ghost copies of owned items on neighbour ranks. Local arrays hold the n_owned owned items
// first, then n_ghost() ghosts (by source rank, then the owner's order). Item i's copies go
// to the ranks in dest_ranks[dest_offsets[i] .. dest_offsets[i + 1]) (this rank and
// repeats are ignored).
class HaloPlan {
 public:
  // gid: the owned items' ids, gathered so that ghost_gids() names the ghosts; without them
  // (a caller that gathers ids as one of its fields) ghost_gids() is empty.
  HaloPlan(MPI_Comm comm, std::int64_t n_owned, std::span<const std::int64_t> dest_offsets,
           std::span<const int> dest_ranks, std::span<const std::uint64_t> gid = {});
  // A plan for new lists on the same engine (CommEngine::replan: a caller that rebuilds its
  // layout keeps the communicator, message buffers and device mappings). Collective.
  void replan(std::int64_t n_owned, std::span<const std::int64_t> dest_offsets,
              std::span<const int> dest_ranks, std::span<const std::uint64_t> gid = {});
  std::int64_t n_owned() const { return n_owned_; }
  std::int64_t n_ghost() const { return engine_->n_recv(); }
  std::int64_t n_total() const { return n_owned_ + n_ghost(); }
  const std::vector<std::uint64_t>& ghost_gids() const { return ghost_gids_; }

  // Owned values -> ghost slots. Fields have n_total() items.
  void gather_begin(std::span<const CommField> f) { engine_->begin(f, CommEngine::Dir::Forward); }
  void gather_finish(std::span<const CommField> f) { engine_->finish(f, CommEngine::Dir::Forward); }
  // Ghost values added into their owners' slots (arithmetic fields only).
  void scatter_add_begin(std::span<const CommField> f) {
    engine_->begin(f, CommEngine::Dir::Reverse);
  }
  void scatter_add_finish(std::span<const CommField> f) {
    engine_->finish(f, CommEngine::Dir::Reverse);
  }
  const CommEngine& engine() const { return *engine_; }
  CommEngine& engine() { return *engine_; }  // packed exchanges (CommEngine::begin_packed)

 private:
  std::span<const std::int64_t> lists(std::int64_t n_owned, std::span<const std::int64_t> offsets,
                                      std::span<const int> ranks);
  void gather_ids(std::span<const std::uint64_t> gid);
  int me_ = 0;
  std::int64_t n_owned_ = 0;
  std::vector<std::int64_t> off_;  // the engine's lists (kept for a replan)
  std::vector<int> dst_;
  std::unique_ptr<CommEngine> engine_;
  std::vector<std::uint64_t> ghost_gids_;
};

}  // namespace qdemsph
