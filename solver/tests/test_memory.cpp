// Buffers keep their allocation within its capacity; indexed copies within a memory space
// (core/memory.hpp): known answers on the host, the same on a device (skipped without a GPU);
// staging bytes; the device pool and IPC bytes; the GPU of each rank.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "core/memory.hpp"
#include "core/timers.hpp"

namespace qdemsph {
namespace {

// A buffer's allocation grows only: sizes within the capacity keep the storage (resize still
// zero-fills, assign copies), a size beyond it reallocates with 1/8 headroom, and moving a buffer
// moves its storage. On a device the same (skipped without a GPU).
void check_capacity(Space s) {
  Buffer<double> b(s);
  b.assign({1, 2, 3, 4, 5, 6, 7, 8});
  const double* p = b.cview().p;
  EXPECT_EQ(b.capacity(), 8);  // a first allocation is exact
  b.resize(5);
  EXPECT_EQ(b.cview().p, p);
  EXPECT_EQ(b.size(), 5);
  EXPECT_EQ(b.to_host(), std::vector<double>(5, 0.0));
  b.assign({9, 8, 7});
  EXPECT_EQ(b.cview().p, p);
  EXPECT_EQ(b.to_host(), (std::vector<double>{9, 8, 7}));
  EXPECT_EQ(b.bytes(), 8 * sizeof(double));  // the allocation's, not the size's
  b.resize_for_overwrite(8);
  EXPECT_EQ(b.cview().p, p);
  EXPECT_EQ(b.size(), 8);
  b.resize(16);  // beyond the capacity: a new allocation, zero-filled, with room to grow
  EXPECT_EQ(b.capacity(), 18);
  EXPECT_EQ(b.to_host(), std::vector<double>(16, 0.0));
  const double* q = b.cview().p;
  Buffer<double> c(std::move(b));
  EXPECT_EQ(c.cview().p, q);
  EXPECT_EQ(c.capacity(), 18);
  EXPECT_EQ(b.capacity(), 0);
  b = Buffer<double>(s, 2);
  c = std::move(b);  // c takes the small one, b the large one (freed with b)
  EXPECT_EQ(c.capacity(), 2);
  EXPECT_EQ(b.cview().p, q);
}

TEST(Memory, BuffersKeepTheirAllocationWithinTheCapacity) { check_capacity(Space::Host); }

TEST(Memory, DeviceBuffersKeepTheirAllocationWithinTheCapacity) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  check_capacity(Space::Cuda);
}

// Device buffers come from the stream-ordered pool (memory_cuda.cu): a buffer freed and one of
// the same size allocated next get the same room, with no wait for the device between, and its
// earlier contents were copied out in stream order before. CUDA IPC cannot name pool memory, so
// a halo's send buffer is IpcDeviceBytes, which it can.
TEST(Memory, DeviceBuffersReuseFreedRoomAndIpcBytesAreShareable) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  const std::vector<double> v(1 << 20, 2.5);
  const double* p = nullptr;
  {
    Buffer<double> a(Space::Cuda);
    a.assign(v);
    p = a.cview().p;
    EXPECT_EQ(a.to_host(), v);
  }
  Buffer<double> b(Space::Cuda, static_cast<std::int64_t>(v.size()));
  EXPECT_EQ(b.cview().p, p);
  EXPECT_EQ(b.to_host(), std::vector<double>(v.size(), 0.0));  // zero-filled after the free
  EXPECT_THROW(cuda_ipc_handle(b.view().p), std::runtime_error);
  IpcDeviceBytes s;
  s.reserve(100);  // 1/8 more room from the first allocation
  EXPECT_EQ(s.capacity(), 112u);
  const std::byte* q = s.data();
  s.reserve(112);  // within the capacity: the same allocation
  EXPECT_EQ(s.data(), q);
  s.reserve(200);  // a growth takes 1/8 more room
  EXPECT_EQ(s.capacity(), 225u);
  EXPECT_NO_THROW(cuda_ipc_handle(s.data()));
  s.release();
  EXPECT_EQ(s.data(), nullptr);
}

// gather then scatter of doubles and bytes through buffers of space s; returns the results.
struct Copied {
  std::vector<double> gathered, scattered;
  std::vector<std::uint8_t> bytes;
};
Copied copy_in(Space s) {
  const std::vector<double> src = {10, 11, 12, 13, 14, 15};
  const std::vector<std::int64_t> idx = {5, 0, 3};
  Buffer<double> a(s), g(s, 3), d(s, 6);
  Buffer<std::int64_t> i(s);
  a.assign(src);
  i.assign(idx);
  space_gather(s, g.view().p, a.cview().p, i.cview().p, 3, 8);
  space_scatter(s, d.view().p, i.cview().p, g.cview().p, 3, 8);
  Buffer<std::uint8_t> b(s), bd(s, 6);
  b.assign({1, 2, 3});
  space_scatter(s, bd.view().p, i.cview().p, b.cview().p, 3, 1);
  return {g.to_host(), d.to_host(), bd.to_host()};
}

// Host work arrays and staging bytes grow as Buffers do: within the capacity the allocation
// stands; outgrowing it they take 1/8 more room (a vector copies nothing then).
TEST(Memory, HostWorkArraysGrowWithRoom) {
  std::vector<double> v(10, 1.0);
  resize_for_overwrite(v, 800);
  EXPECT_EQ(v.size(), 800u);
  EXPECT_EQ(v.capacity(), 900u);
  const double* p = v.data();
  resize_for_overwrite(v, 900);
  resize_for_overwrite(v, 5);
  EXPECT_EQ(v.data(), p);
  EXPECT_EQ(v.size(), 5u);
  StagingBytes b;
  b.resize(800);
  const std::byte* q = b.data();
  b.resize(900);  // within the 1/8 room
  EXPECT_EQ(b.data(), q);
  EXPECT_EQ(b.size(), 900u);
}

TEST(Memory, GatherAndScatterByIndex) {
  const Copied c = copy_in(Space::Host);
  EXPECT_EQ(c.gathered, (std::vector<double>{15, 10, 13}));
  EXPECT_EQ(c.scattered, (std::vector<double>{10, 0, 0, 13, 0, 15}));
  EXPECT_EQ(c.bytes, (std::vector<std::uint8_t>{2, 0, 0, 3, 0, 1}));
  EXPECT_THROW(space_gather(Space::Host, nullptr, nullptr, nullptr, 1, 2), std::logic_error);
}

TEST(Memory, GatherAndScatterOnTheDeviceMatchTheHost) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  const Copied h = copy_in(Space::Host), d = copy_in(Space::Cuda);
  EXPECT_EQ(d.gathered, h.gathered);
  EXPECT_EQ(d.scattered, h.scattered);
  EXPECT_EQ(d.bytes, h.bytes);
}

// Staging bytes (a GPU rank's MPI halo buffers): plain memory until the process uses a GPU,
// page-locked after; sizes grow without losing the storage's use, and device copies through
// them round-trip.
TEST(Memory, StagingBytesArePinnedOnceTheProcessUsesAGpu) {
  StagingBytes s;
  s.resize(16);
  EXPECT_EQ(s.size(), 16u);
  s[15] = std::byte{7};
  s.resize(4);  // shrinking keeps the storage
  EXPECT_EQ(s.size(), 4u);
  if (!cuda_available()) {
    s.resize(1 << 20);
    EXPECT_FALSE(s.pinned());
    GTEST_SKIP() << "no CUDA device: the page-locked half is not checked";
  }
  const std::vector<double> v = {1.5, -2.25, 3.0, 1e300};
  Buffer<double> d(Space::Cuda);
  d.assign(v);  // the process now uses a GPU
  StagingBytes t;
  t.resize(v.size() * sizeof(double));
  EXPECT_TRUE(t.pinned());
  space_copy(t.data(), Space::Host, d.cview().p, Space::Cuda, t.size());
  Buffer<double> back(Space::Cuda, v.size());
  space_copy(back.view().p, Space::Cuda, t.data(), Space::Host, t.size());
  EXPECT_EQ(back.to_host(), v);
}

// The copy stream (a GPU halo's peer copies): copies issued there are complete after
// cuda_copy_wait, whatever the default stream is still running.
TEST(Memory, CopyStreamCopiesAreDoneAfterTheWait) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  std::vector<double> v(1 << 16);
  for (std::size_t k = 0; k < v.size(); ++k) v[k] = 0.5 * static_cast<double>(k) - 7;
  Buffer<double> a(Space::Cuda), b(Space::Cuda, static_cast<std::int64_t>(v.size()));
  a.assign(v);
  cuda_sync();  // a's contents are there before the copy stream reads them
  cuda_copy_async(b.view().p, a.cview().p, v.size() * sizeof(double));
  cuda_copy_wait();
  EXPECT_EQ(b.to_host(), v);
}

// Two streams' order, seen by copies: a device buffer `a` of n doubles (-1 at first), a
// 256 MiB copy (~10 ms) from `load` into `slow` to put ahead of a write, page-locked `fill`
// (what the write puts in a) and `back` (what a later read of a got), and the count of
// `back`'s values other than fill's.
struct StreamOrder {
  static constexpr std::size_t n = std::size_t{1} << 16, bytes = n * sizeof(double);
  static constexpr std::size_t big = std::size_t{1} << 28;
  Buffer<double> a{Space::Cuda};
  Buffer<std::byte> slow{Space::Cuda, static_cast<std::int64_t>(big)};
  StagingBytes fill, back, load;
  StreamOrder() {
    a.assign(std::vector<double>(n, -1.0));
    fill.resize(bytes);
    back.resize(bytes);
    load.resize(big);
  }
  void set_fill(double value) {
    double* f = reinterpret_cast<double*>(fill.data());
    for (std::size_t k = 0; k < n; ++k) f[k] = value + static_cast<double>(k % 7);
  }
  std::size_t wrong(double value) const {
    const double* got = reinterpret_cast<const double*>(back.data());
    std::size_t w = 0;
    for (std::size_t k = 0; k < n; ++k) w += got[k] != value + static_cast<double>(k % 7);
    return w;
  }
};

// A SideQueue's work starts after the default stream's work queued before it, or before the
// DeviceMark it is given: its copy of a buffer that the default stream writes after a long copy
// (256 MiB, ~10 ms, into another buffer) reads the new contents, where a side stream that did
// not wait would read the old ones at once; work queued on the default stream after the mark
// does not matter. DeviceMark::wait returns once the side's work is done. Not nested.
TEST(Memory, SideQueueWorkFollowsTheForkPoint) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  StreamOrder t;
  for (const bool marked : {true, false}) {
    SCOPED_TRACE(marked ? "from a mark" : "from now");
    const double value = marked ? 2.5 : 4.0;
    t.set_fill(value);
    cuda_sync();
    cuda_copy_queued(t.slow.view().p, t.load.data(), t.big);
    cuda_copy_queued(t.a.view().p, t.fill.data(), t.bytes);
    DeviceMark filled, read;
    filled.record();
    if (marked) cuda_copy_queued(t.slow.view().p, t.load.data(), t.big);  // after the mark
    {
      SideQueue side(true, marked ? &filled : nullptr);
      EXPECT_THROW(SideQueue(true), std::logic_error);
      cuda_copy_queued(t.back.data(), t.a.cview().p, t.bytes);
      read.record();
    }
    read.wait();
    EXPECT_EQ(t.wrong(value), 0u);
    cuda_sync();
  }
}

// DeviceMark::follow: the default stream's work queued after it waits, on the device, for the
// side stream's work up to the mark: its copy of a buffer that the side stream writes after a
// long copy (256 MiB, ~10 ms) reads the new contents, where a default stream that did not wait
// would read the old ones at once. Before any record() it does nothing.
TEST(Memory, FollowJoinsTheSideStreamsWork) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  StreamOrder t;
  t.set_fill(3.5);
  DeviceMark unused;
  unused.follow();  // nothing recorded
  DeviceMark written, read;
  cuda_sync();
  {
    SideQueue side(true);
    cuda_copy_queued(t.slow.view().p, t.load.data(), t.big);
    cuda_copy_queued(t.a.view().p, t.fill.data(), t.bytes);
    written.record();
  }
  written.follow();
  cuda_copy_queued(t.back.data(), t.a.cview().p, t.bytes);
  read.record();
  read.wait();
  EXPECT_EQ(t.wrong(3.5), 0u);
  cuda_sync();
}

// Copies between the device and pageable host memory of 4 MiB and more go through two
// page-locked 8 MiB chunks (memory_cuda.cu): sizes around the threshold and the chunk, and
// several chunks with a partial last one, arrive whole both ways; a copy from page-locked
// memory (StagingBytes) takes the direct path and equals them.
TEST(Memory, LargeHostDeviceCopiesArriveWhole) {
  if (!cuda_available()) GTEST_SKIP() << "no CUDA device";
  constexpr std::int64_t kMiB = (1 << 20) / sizeof(double);
  for (const std::int64_t n : {4 * kMiB - 1, 4 * kMiB, 8 * kMiB + 3, 20 * kMiB + 5}) {
    std::vector<double> v(static_cast<std::size_t>(n));
    for (std::int64_t k = 0; k < n; ++k) v[k] = 0.25 * static_cast<double>(k) - 3 * (k % 7);
    Buffer<double> b(Space::Cuda);
    b.assign(v);
    EXPECT_EQ(b.to_host(), v) << n << " doubles";
    StagingBytes pinned;
    pinned.resize(v.size() * sizeof(double));
    b.zero();
    std::memcpy(pinned.data(), v.data(), pinned.size());
    b.assign(reinterpret_cast<const double*>(pinned.data()), n);
    EXPECT_EQ(b.to_host(), v) << n << " doubles from page-locked memory";
  }
}

// A scope synchronises before it stops its timer; a launch() scope does not (its device work
// counts in the next synchronised scope).
TEST(Memory, TimerScopesSynchroniseUnlessTheyOnlyLaunch) {
  int syncs = 0;
  PhaseTimers t([&] { ++syncs; });
  { auto s = t.scope("a"); }
  EXPECT_EQ(syncs, 1);
  { auto s = t.launch("b"); }
  EXPECT_EQ(syncs, 1);
  EXPECT_EQ(t.seconds().count("a") + t.seconds().count("b"), 2u);
}

// An MPI rank's GPU: its rank on the node modulo the node's GPUs (parallel/world.cpp).
TEST(Memory, RanksSpreadOverTheGpus) {
  EXPECT_EQ(cuda_device_for(0, 2), 0);
  EXPECT_EQ(cuda_device_for(1, 2), 1);
  EXPECT_EQ(cuda_device_for(2, 2), 0);
  EXPECT_EQ(cuda_device_for(7, 4), 3);
  EXPECT_EQ(cuda_device_for(3, 1), 0);
  EXPECT_EQ(cuda_device_for(3, 0), 0);
}

}  // namespace
}  // namespace qdemsph
