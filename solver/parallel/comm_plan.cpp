#include "parallel/comm_plan.hpp"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "core/exec_host.hpp"
#include "core/select_host.hpp"
#include "neighbor/scan.hpp"

namespace qdemsph {

namespace {

constexpr int kTag = 7301;

void check_fields(std::span<const CommField> f, std::int64_t min_items, const char* what) {
  for (std::size_t j = 0; j < f.size(); ++j)
    if (f[j].n < min_items || (min_items > 0 && f[j].data == nullptr))
      throw std::invalid_argument(std::string("comm plan: ") + what + " field " +
                                  std::to_string(j) + " has " + std::to_string(f[j].n) +
                                  " items, needs " + std::to_string(min_items));
}

// f(first, last) over the slots [0, n) of a message buffer, less this rank's own [b, e) unless
// `self`.
template <class F>
void for_slots(std::int64_t n, std::int64_t b, std::int64_t e, bool self, F f) {
  if (self) return f(std::int64_t{0}, n);
  f(std::int64_t{0}, b);
  f(e, n);
}

int as_count(std::int64_t bytes) {
  if (bytes > INT_MAX)
    throw std::runtime_error("comm plan: message of " + std::to_string(bytes) +
                             " bytes exceeds the MPI int count");
  return static_cast<int>(bytes);
}

}  // namespace

CommEngine::CommEngine(MPI_Comm comm, std::span<const std::int64_t> dest_offsets,
                       std::span<const int> dest_ranks, std::int64_t recv_base) {
  MPI_Comm_dup(comm, &comm_);
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  replan(dest_offsets, dest_ranks, recv_base);
}

void CommEngine::replan(std::span<const std::int64_t> dest_offsets, std::span<const int> dest_ranks,
                        std::int64_t recv_base) {
  if (in_flight_) throw std::logic_error("comm plan: replan() in flight");
  settle_copied();
  recv_base_ = recv_base;
  n_items_ = static_cast<std::int64_t>(dest_offsets.size()) - 1;
  const std::int64_t n_items = n_items_;
  // Send slots: the destination entries by rank, each rank's in item order (a stable counting
  // sort on the threads, select_host.hpp), then each entry's item.
  const auto n_entries = static_cast<std::int64_t>(dest_ranks.size());
  if (dest_offsets.empty() || dest_offsets.back() != n_entries)
    throw std::invalid_argument("comm plan: destination offsets do not end at the entries' count");
  const Buckets by_rank =
      bucket_indices(HostExec{}, n_entries, size_, [&](std::int64_t k) { return dest_ranks[k]; });
  if (by_rank.start[size_] != n_entries) {
    const int r = *std::find_if(dest_ranks.begin(), dest_ranks.end(),
                                [&](int d) { return d < 0 || d >= size_; });
    throw std::invalid_argument("comm plan: destination rank " + std::to_string(r) +
                                " outside [0, " + std::to_string(size_) + ")");
  }
  send_off_.assign(by_rank.start.begin(), by_rank.start.end());
  std::vector<std::int64_t> count(size_);
  for (int r = 0; r < size_; ++r) count[r] = send_off_[r + 1] - send_off_[r];
  item_of_.resize(n_entries);
  for_each(HostExec{}, n_items, [&](std::int64_t i) {
    for (std::int64_t k = dest_offsets[i]; k < dest_offsets[i + 1]; ++k) item_of_[k] = i;
  });
  send_index_.resize(n_entries);
  for_each(HostExec{}, n_entries,
           [&](std::int64_t j) { send_index_[j] = item_of_[by_rank.index[j]]; });
  // Receive counts: one all-to-all of counts (O(ranks) memory; a sparse exchange is the
  // next step at large rank counts).
  std::vector<std::int64_t> rcount(size_, 0);
  MPI_Alltoall(count.data(), 1, MPI_INT64_T, rcount.data(), 1, MPI_INT64_T, comm_);
  recv_off_.assign(size_ + 1, 0);
  for (int r = 0; r < size_; ++r) recv_off_[r + 1] = recv_off_[r] + rcount[r];
  nbrs_.clear();
  for (int r = 0; r < size_; ++r)
    if (r != rank_ && (count[r] > 0 || rcount[r] > 0)) nbrs_.push_back(r);
  if (device_) remap_device();
}

CommEngine::~CommEngine() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && comm_ != MPI_COMM_NULL) {
    if (in_flight_ || exchanging_)
      MPI_Waitall(static_cast<int>(reqs_.size()), reqs_.data(), MPI_STATUSES_IGNORE);
    settle_copied();
    if (device_) unmap_peers();  // no neighbour maps this rank's buffers when they are freed
    MPI_Comm_free(&comm_);
  }
}

bool CommEngine::use_device(bool want, std::size_t max_stride) {
  if (device_) throw std::logic_error("comm plan: use_device() called twice");
  const char* env = std::getenv("QDEMSPH_DEVICE_HALO");
  const bool ok = want && !(env && std::strcmp(env, "0") == 0);
  {  // which ranks share this node
    MPI_Comm node;
    MPI_Comm_split_type(comm_, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
    MPI_Group all, local;
    MPI_Comm_group(comm_, &all);
    MPI_Comm_group(node, &local);
    on_node_.assign(size_, 0);
    for (int r = 0; r < size_; ++r) {
      int there = MPI_UNDEFINED;
      MPI_Group_translate_ranks(all, 1, &r, local, &there);
      on_node_[r] = there != MPI_UNDEFINED;
    }
    MPI_Group_free(&all);
    MPI_Group_free(&local);
    MPI_Comm_free(&node);
  }
  if (!all_ranks(ok && neighbours_on_node())) return false;
  max_stride_ = max_stride;
  peer_.assign(size_, nullptr);
  peer_off_.assign(size_, 0);
  if (!all_ranks(map_peers())) {
    drop_device();
    return false;
  }
  device_ = true;
  return true;
}

bool CommEngine::all_ranks(bool mine) {
  int m = mine ? 1 : 0, a = 0;
  MPI_Allreduce(&m, &a, 1, MPI_INT, MPI_LAND, comm_);
  return a != 0;
}

bool CommEngine::neighbours_on_node() const {
  for (int r : nbrs_)
    if (!on_node_[r]) return false;
  return true;
}

// The device buffers sized for the lists, and each sender's buffer mapped where this rank's
// records are (peer_, peer_off_): every sender tells the neighbours it sends to its buffer's
// IPC handle and the item their block starts at; a receiver opens the handles of the senders
// it has no mapping of. False on a failure here (a GPU pair without peer access).
bool CommEngine::map_peers() {
  struct Where {
    CudaIpcHandle h;
    std::int64_t first;
  };
  std::vector<Where> out(size_), in(size_);
  try {
    dsend_.reserve(std::max<std::size_t>(1, max_stride_ * n_send()));
    drecv_.reserve(std::max<std::size_t>(1, max_stride_ * n_recv()));
    const CudaIpcHandle h = cuda_ipc_handle(dsend_.data());
    std::vector<MPI_Request> req;
    for (int r : nbrs_) {
      if (recv_off_[r + 1] > recv_off_[r]) {
        req.emplace_back();
        MPI_Irecv(&in[r], sizeof(Where), MPI_BYTE, r, kTag + 3, comm_, &req.back());
      }
      if (send_off_[r + 1] > send_off_[r]) {
        out[r] = {h, send_off_[r]};
        req.emplace_back();
        MPI_Isend(&out[r], sizeof(Where), MPI_BYTE, r, kTag + 3, comm_, &req.back());
      }
    }
    MPI_Waitall(static_cast<int>(req.size()), req.data(), MPI_STATUSES_IGNORE);
    for (int r : nbrs_)
      if (recv_off_[r + 1] > recv_off_[r]) {
        if (!peer_[r]) peer_[r] = static_cast<std::byte*>(cuda_ipc_open(in[r].h));
        peer_off_[r] = in[r].first;
      }
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

// Every mapping closed (after the barrier no rank maps this rank's buffers).
void CommEngine::unmap_peers() {
  for (std::byte*& p : peer_) cuda_ipc_close(p), p = nullptr;
  MPI_Barrier(comm_);
}

void CommEngine::drop_device() {
  unmap_peers();
  dsend_.release();
  drecv_.release();
  device_ = false;
}

// replan() on device buffers: the senders' mappings stand but those of ranks whose send buffer
// must grow (a new allocation: every rank closes its mapping of such a buffer first, so none
// outlives it; the others are not opened again, cudaIpcOpenMemHandle being slow); host staging
// again when a neighbour is off this node now.
void CommEngine::remap_device() {
  if (!all_ranks(neighbours_on_node())) return drop_device();
  int grow = max_stride_ * n_send() > dsend_.capacity();
  std::vector<int> grows(size_);
  MPI_Allgather(&grow, 1, MPI_INT, grows.data(), 1, MPI_INT, comm_);
  if (std::find(grows.begin(), grows.end(), 1) != grows.end()) {
    for (int r = 0; r < size_; ++r)
      if (grows[r] && peer_[r]) cuda_ipc_close(peer_[r]), peer_[r] = nullptr;
    MPI_Barrier(comm_);
  }
  if (!all_ranks(map_peers())) drop_device();
}

void CommEngine::mark_packed() {
  if (!device_) return;
  packed_.record();
  marked_ = true;
}

void CommEngine::post_device() {
  no_exchange_in_flight();
  settle_copied();
  // The caller's records are in dsend_ before any receiver copies them.
  if (marked_)
    packed_.wait();
  else
    cuda_sync();
  marked_ = false;
  reqs_.clear();
  ready_.clear();
  last_bytes_ = 0;
  for (int r : nbrs_) {
    if (recv_off_[r + 1] > recv_off_[r]) {
      ready_.emplace_back();
      MPI_Irecv(nullptr, 0, MPI_BYTE, r, kTag + 4, comm_, &ready_.back());
    }
    const std::int64_t n = send_off_[r + 1] - send_off_[r];
    if (n == 0) continue;
    reqs_.emplace_back();
    MPI_Isend(nullptr, 0, MPI_BYTE, r, kTag + 4, comm_, &reqs_.back());
    reqs_.emplace_back();
    MPI_Irecv(nullptr, 0, MPI_BYTE, r, kTag + 5, comm_, &reqs_.back());  // "copied"
    last_bytes_ += n * static_cast<std::int64_t>(stride_);
  }
  total_bytes_ += last_bytes_;
  dir_ = Dir::Forward;
  in_flight_ = true;
}

std::span<const std::byte> CommEngine::finish_device() {
  const double t0 = MPI_Wtime();
  MPI_Waitall(static_cast<int>(ready_.size()), ready_.data(), MPI_STATUSES_IGNORE);
  // On the copy stream: the kernels the caller queued meanwhile (the interior tets) run on.
  std::byte* const recv = drecv_.data();
  for (int r : nbrs_) {
    const std::int64_t n = recv_off_[r + 1] - recv_off_[r];
    if (n > 0)
      cuda_copy_async(recv + recv_off_[r] * stride_, peer_[r] + peer_off_[r] * stride_,
                      n * stride_);
  }
  const std::int64_t nself = send_off_[rank_ + 1] - send_off_[rank_];
  if (nself > 0)
    cuda_copy_async(recv + recv_off_[rank_] * stride_, dsend_.data() + send_off_[rank_] * stride_,
                    nself * stride_);
  cuda_copy_wait();
  for (int r : nbrs_)
    if (recv_off_[r + 1] > recv_off_[r]) {
      reqs_.emplace_back();
      MPI_Isend(nullptr, 0, MPI_BYTE, r, kTag + 5, comm_, &reqs_.back());
    }
  copied_.insert(copied_.end(), reqs_.begin(), reqs_.end());  // settled before the next pack
  reqs_.clear();
  in_flight_ = false;
  seconds_.wait += MPI_Wtime() - t0;
  return {recv, stride_ * static_cast<std::size_t>(n_recv())};
}

// The halo's exchanges and exchange_begin's share reqs_: one at a time.
void CommEngine::no_exchange_in_flight() const {
  if (exchanging_)
    throw std::logic_error("comm plan: a halo exchange while exchange_begin()'s is in flight");
}

void CommEngine::settle_copied() {
  if (copied_.empty()) return;
  const double t0 = MPI_Wtime();
  MPI_Waitall(static_cast<int>(copied_.size()), copied_.data(), MPI_STATUSES_IGNORE);
  copied_.clear();
  seconds_.wait += MPI_Wtime() - t0;
}

void CommEngine::begin(std::span<const CommField> src, Dir dir) {
  pack(src, dir, true);
  post(dir, true);
}

void CommEngine::finish(std::span<const CommField> dst, Dir dir) { unpack(dst, dir, true); }

void CommEngine::forward(std::span<const CommField> src, std::span<const CommField> dst) {
  bool same = src.size() == dst.size();
  for (std::size_t j = 0; same && j < src.size(); ++j) same = src[j].elem == dst[j].elem;
  if (!same) throw std::invalid_argument("comm plan: forward() fields differ");
  check_fields(dst, recv_base_ + n_recv(), "destination");
  pack(src, Dir::Forward, false);
  post(Dir::Forward, false);
  // This rank's own items, while the others are in flight.
  const double t0 = MPI_Wtime();
  const std::int64_t from = send_off_[rank_], to = recv_base_ + recv_off_[rank_];
  for (std::size_t j = 0; j < src.size(); ++j)
    copy_each(
        0, send_off_[rank_ + 1] - from, src[j].elem,
        [&](std::int64_t k) { return dst[j].data + (to + k) * dst[j].elem; },
        [&](std::int64_t k) { return src[j].data + send_index_[from + k] * src[j].elem; });
  seconds_.unpack += MPI_Wtime() - t0;
  unpack(dst, Dir::Forward, false);
}

void CommEngine::pack(std::span<const CommField> src, Dir dir, bool self) {
  if (in_flight_) throw std::logic_error("comm plan: begin() while an exchange is in flight");
  const double t0 = MPI_Wtime();
  stride_ = 0;
  for (const CommField& f : src) stride_ += f.elem;
  const bool fwd = dir == Dir::Forward;
  // Forward sends along send_off_ and receives along recv_off_; reverse swaps them.
  const std::vector<std::int64_t>& so = fwd ? send_off_ : recv_off_;
  check_fields(src, fwd ? n_items_ : recv_base_ + n_recv(), "source");
  sendbuf_.resize(stride_ * buffer_slot(so[size_], so, self));
  // Pack, item-major. Bytes: stride per slot each way.
  std::size_t off = 0;
  for (const CommField& f : src) {
    for_slots(so[size_], so[rank_], so[rank_ + 1], self, [&](std::int64_t b, std::int64_t e) {
      copy_each(
          b, e, f.elem,
          [&](std::int64_t k) { return &sendbuf_[buffer_slot(k, so, self) * stride_ + off]; },
          [&](std::int64_t k) {
            return f.data + (fwd ? send_index_[k] : recv_base_ + k) * f.elem;
          });
    });
    off += f.elem;
  }
  seconds_.pack += MPI_Wtime() - t0;
}

std::int64_t CommEngine::buffer_slot(std::int64_t k, const std::vector<std::int64_t>& off,
                                     bool self) const {
  return self || k <= off[rank_] ? k : k - (off[rank_ + 1] - off[rank_]);
}

void CommEngine::post(Dir dir, bool self) {
  no_exchange_in_flight();
  const double t0 = MPI_Wtime();
  const bool fwd = dir == Dir::Forward;
  const std::vector<std::int64_t>& so = fwd ? send_off_ : recv_off_;
  const std::vector<std::int64_t>& ro = fwd ? recv_off_ : send_off_;
  recvbuf_.resize(stride_ * buffer_slot(ro[size_], ro, self));
  // Post receives first, then sends; the self part is a copy (unless forward() copies it).
  reqs_.clear();
  last_bytes_ = 0;
  for (int r : nbrs_) {
    const std::int64_t n = ro[r + 1] - ro[r];
    if (n == 0) continue;
    reqs_.emplace_back();
    MPI_Irecv(recvbuf_.data() + buffer_slot(ro[r], ro, self) * stride_, as_count(n * stride_),
              MPI_BYTE, r, kTag, comm_, &reqs_.back());
  }
  for (int r : nbrs_) {
    const std::int64_t n = so[r + 1] - so[r];
    if (n == 0) continue;
    reqs_.emplace_back();
    MPI_Isend(sendbuf_.data() + buffer_slot(so[r], so, self) * stride_, as_count(n * stride_),
              MPI_BYTE, r, kTag, comm_, &reqs_.back());
    last_bytes_ += n * stride_;
  }
  const std::int64_t nself = so[rank_ + 1] - so[rank_];
  if (self && nself > 0)
    std::memcpy(recvbuf_.data() + ro[rank_] * stride_, sendbuf_.data() + so[rank_] * stride_,
                nself * stride_);
  total_bytes_ += last_bytes_;
  seconds_.pack += MPI_Wtime() - t0;
  dir_ = dir;
  in_flight_ = true;
}

std::span<std::byte> CommEngine::packed_send_buffer(std::size_t stride) {
  if (in_flight_) throw std::logic_error("comm plan: packing while an exchange is in flight");
  settle_copied();  // no neighbour reads the buffer any more
  stride_ = stride;
  const std::size_t n = stride_ * send_off_[size_];
  if (device_) {
    if (stride > max_stride_)
      throw std::logic_error("comm plan: records of " + std::to_string(stride) +
                             " bytes, the device buffers hold " + std::to_string(max_stride_));
    return {dsend_.data(), n};
  }
  sendbuf_.resize(n);
  return {sendbuf_.data(), sendbuf_.size()};
}

void CommEngine::begin_packed() {
  if (in_flight_) throw std::logic_error("comm plan: begin() while an exchange is in flight");
  if (device_)
    post_device();
  else
    post(Dir::Forward, true);
}

std::span<const std::byte> CommEngine::finish_packed() {
  if (!in_flight_) throw std::logic_error("comm plan: finish() without begin()");
  if (dir_ != Dir::Forward) throw std::logic_error("comm plan: finish() in another direction");
  if (device_) return finish_device();
  const double t0 = MPI_Wtime();
  MPI_Waitall(static_cast<int>(reqs_.size()), reqs_.data(), MPI_STATUSES_IGNORE);
  in_flight_ = false;
  seconds_.wait += MPI_Wtime() - t0;
  return {recvbuf_.data(), stride_ * static_cast<std::size_t>(n_recv())};
}

void CommEngine::unpack(std::span<const CommField> dst, Dir dir, bool self) {
  if (!in_flight_) throw std::logic_error("comm plan: finish() without begin()");
  if (dir != dir_) throw std::logic_error("comm plan: finish() in another direction");
  std::size_t stride = 0;
  for (const CommField& f : dst) stride += f.elem;
  const double t0 = MPI_Wtime();
  MPI_Waitall(static_cast<int>(reqs_.size()), reqs_.data(), MPI_STATUSES_IGNORE);
  in_flight_ = false;
  const double t1 = MPI_Wtime();
  seconds_.wait += t1 - t0;
  if (stride != stride_)
    throw std::invalid_argument("comm plan: finish() fields differ from begin()'s");
  const bool fwd = dir == Dir::Forward;
  check_fields(dst, fwd ? recv_base_ + n_recv() : n_items_, "destination");
  std::size_t off = 0;
  if (fwd) {
    for (const CommField& f : dst) {
      for_slots(n_recv(), recv_off_[rank_], recv_off_[rank_ + 1], self,
                [&](std::int64_t b, std::int64_t e) {
                  copy_each(
                      b, e, f.elem,
                      [&](std::int64_t k) { return f.data + (recv_base_ + k) * f.elem; },
                      [&](std::int64_t k) {
                        return &recvbuf_[buffer_slot(k, recv_off_, self) * stride_ + off];
                      });
                });
      off += f.elem;
    }
  } else {
    // Sums in slot order (source rank, then sender order): deterministic.
    const std::int64_t nr = n_send();
    for (const CommField& f : dst) {
      if (f.add == nullptr)
        throw std::invalid_argument("comm plan: scatter-add on a non-arithmetic field");
      for (std::int64_t k = 0; k < nr; ++k)
        f.add(f.data + send_index_[k] * f.elem, &recvbuf_[k * stride_ + off]);
      off += f.elem;
    }
  }
  seconds_.unpack += MPI_Wtime() - t1;
}

void CommEngine::exchange_begin(std::span<const std::byte> send,
                                std::span<const std::int64_t> send_off, std::size_t stride) {
  if (in_flight_ || exchanging_)
    throw std::logic_error("comm plan: exchange_begin() while an exchange is in flight");
  if (static_cast<int>(send_off.size()) != size_ + 1 ||
      static_cast<std::size_t>(send_off[size_]) * stride != send.size())
    throw std::invalid_argument(
        "comm plan: exchange_begin() needs size() + 1 offsets over the records");
  const auto is_nbr = [&](int r) { return std::binary_search(nbrs_.begin(), nbrs_.end(), r); };
  for (int r = 0; r < size_; ++r)
    if (send_off[r + 1] > send_off[r] && r != rank_ && !is_nbr(r))
      throw std::invalid_argument("comm plan: exchange_begin() to rank " + std::to_string(r) +
                                  ", not a neighbour");
  // One message a neighbour, of the size its sender knows; the receiver learns it by a matched
  // probe: a single round where counts, then records, took two (on a GPU rank the contact shares
  // end the step this way).
  reqs_.clear();
  last_bytes_ = 0;
  for (const int r : nbrs_) {
    const std::int64_t n = send_off[r + 1] - send_off[r];
    reqs_.emplace_back();
    MPI_Isend(send.data() + send_off[r] * stride, as_count(n * stride), MPI_BYTE, r, kTag + 2,
              comm_, &reqs_.back());
    last_bytes_ += n * static_cast<std::int64_t>(stride);
  }
  xself_ = send.subspan(send_off[rank_] * stride, (send_off[rank_ + 1] - send_off[rank_]) * stride);
  xstride_ = stride;
  exchanging_ = true;
}

std::vector<std::byte> CommEngine::exchange_finish() {
  if (!exchanging_) throw std::logic_error("comm plan: exchange_finish() without exchange_begin()");
  const std::size_t nn = nbrs_.size(), stride = xstride_;
  std::vector<MPI_Message> msg(nn);
  std::vector<std::int64_t> roff(size_ + 1, 0);
  roff[rank_ + 1] = static_cast<std::int64_t>(xself_.size() / stride);
  for (std::size_t k = 0; k < nn; ++k) {
    MPI_Status st;
    MPI_Mprobe(nbrs_[k], kTag + 2, comm_, &msg[k], &st);
    int bytes = 0;
    MPI_Get_count(&st, MPI_BYTE, &bytes);
    if (bytes % static_cast<int>(stride) != 0)
      throw std::logic_error("comm plan: exchange_finish() got " + std::to_string(bytes) +
                             " bytes from rank " + std::to_string(nbrs_[k]) + ", not records of " +
                             std::to_string(stride));
    roff[nbrs_[k] + 1] = bytes / static_cast<std::int64_t>(stride);
  }
  for (int r = 0; r < size_; ++r) roff[r + 1] += roff[r];
  std::vector<std::byte> out(roff[size_] * stride);
  for (std::size_t k = 0; k < nn; ++k) {
    const int r = nbrs_[k];
    reqs_.emplace_back();
    MPI_Imrecv(out.data() + roff[r] * stride, as_count((roff[r + 1] - roff[r]) * stride), MPI_BYTE,
               &msg[k], &reqs_.back());
  }
  if (!xself_.empty()) std::memcpy(out.data() + roff[rank_] * stride, xself_.data(), xself_.size());
  MPI_Waitall(static_cast<int>(reqs_.size()), reqs_.data(), MPI_STATUSES_IGNORE);
  reqs_.clear();
  exchanging_ = false;
  total_bytes_ += last_bytes_;
  return out;
}

MigratePlan::MigratePlan(MPI_Comm comm, std::span<const int> dest,
                         std::span<const std::uint64_t> gid) {
  if (gid.size() != dest.size())
    throw std::invalid_argument("MigratePlan: " + std::to_string(dest.size()) +
                                " destinations but " + std::to_string(gid.size()) + " ids");
  engine_ = std::make_unique<CommEngine>(comm, offsets_for(dest), dest, 0);
  new_gids_.resize(engine_->n_recv());
  const CommField s = comm_field(const_cast<std::uint64_t*>(gid.data()), n_old_);
  const CommField d = comm_field(new_gids_);
  move({&s, 1}, {&d, 1});
}

MigratePlan::MigratePlan(MPI_Comm comm, std::span<const int> dest)
    : engine_(std::make_unique<CommEngine>(comm, offsets_for(dest), dest, 0)) {}

void MigratePlan::replan(std::span<const int> dest) {
  engine_->replan(offsets_for(dest), dest, 0);
  new_gids_.clear();
}

std::span<const std::int64_t> MigratePlan::offsets_for(std::span<const int> dest) {
  n_old_ = static_cast<std::int64_t>(dest.size());
  const std::int64_t had = static_cast<std::int64_t>(offsets_.size());
  offsets_.resize(n_old_ + 1);
  for (std::int64_t i = had; i <= n_old_; ++i) offsets_[i] = i;
  return offsets_;
}

HaloPlan::HaloPlan(MPI_Comm comm, std::int64_t n_owned, std::span<const std::int64_t> offsets,
                   std::span<const int> ranks, std::span<const std::uint64_t> gid) {
  MPI_Comm_rank(comm, &me_);
  const std::span<const std::int64_t> off = lists(n_owned, offsets, ranks);
  engine_ = std::make_unique<CommEngine>(comm, off, dst_, n_owned);
  gather_ids(gid);
}

void HaloPlan::replan(std::int64_t n_owned, std::span<const std::int64_t> offsets,
                      std::span<const int> ranks, std::span<const std::uint64_t> gid) {
  const std::span<const std::int64_t> off = lists(n_owned, offsets, ranks);
  engine_->replan(off, dst_, n_owned);
  gather_ids(gid);
}

// Each item's list without this rank and repeats (counted, then written, on the threads). A
// list that is already so (increasing, without this rank: the fluid's ghost lists) is copied
// as it is; only the others are sorted, in a scratch array allocated for them alone.
std::span<const std::int64_t> HaloPlan::lists(std::int64_t n_owned,
                                              std::span<const std::int64_t> offsets,
                                              std::span<const int> ranks) {
  if (static_cast<std::int64_t>(offsets.size()) != n_owned + 1)
    throw std::invalid_argument("HaloPlan: offsets need n_owned + 1 entries");
  n_owned_ = n_owned;
  auto clean = [&](std::int64_t i) {
    for (std::int64_t k = offsets[i]; k < offsets[i + 1]; ++k)
      if (ranks[k] == me_ || (k > offsets[i] && ranks[k] <= ranks[k - 1])) return false;
    return true;
  };
  auto list = [&](std::int64_t i, int* r) {  // item i's ranks into r (at most its list's size)
    std::int64_t n = 0;
    for (std::int64_t k = offsets[i]; k < offsets[i + 1]; ++k)
      if (ranks[k] != me_) r[n++] = ranks[k];
    std::sort(r, r + n);
    return static_cast<std::int64_t>(std::unique(r, r + n) - r);
  };
  resize_for_overwrite(off_, static_cast<std::size_t>(n_owned + 1));
  for_each(HostExec{}, n_owned, [&](std::int64_t i) {
    const std::int64_t m = offsets[i + 1] - offsets[i];
    if (m == 0 || clean(i)) {
      off_[i] = m;
      return;
    }
    std::vector<int> r(m);
    off_[i] = list(i, r.data());
  });
  exclusive_scan(HostExec{}, View<std::int64_t>{off_.data(), n_owned + 1}, n_owned);
  resize_for_overwrite(dst_, static_cast<std::size_t>(off_[n_owned]));
  for_each(HostExec{}, n_owned, [&](std::int64_t i) {
    const std::int64_t m = offsets[i + 1] - offsets[i];
    if (m == 0) return;
    if (clean(i)) {
      std::copy(ranks.begin() + offsets[i], ranks.begin() + offsets[i + 1], dst_.begin() + off_[i]);
      return;
    }
    std::vector<int> r(m);
    list(i, r.data());
    std::copy(r.begin(), r.begin() + (off_[i + 1] - off_[i]), dst_.begin() + off_[i]);
  });
  return off_;
}

// Ghost ids (when given): a gather of the id field into a scratch array of n_total items.
void HaloPlan::gather_ids(std::span<const std::uint64_t> gid) {
  ghost_gids_.clear();
  if (gid.empty()) return;
  if (static_cast<std::int64_t>(gid.size()) < n_owned_)
    throw std::invalid_argument("HaloPlan: ids need n_owned entries");
  std::vector<std::uint64_t> ids(n_total(), 0);
  std::copy(gid.begin(), gid.begin() + n_owned_, ids.begin());
  const CommField f = comm_field(ids);
  gather_begin({&f, 1});
  gather_finish({&f, 1});
  ghost_gids_.assign(ids.begin() + n_owned_, ids.end());
}

}  // namespace qdemsph
