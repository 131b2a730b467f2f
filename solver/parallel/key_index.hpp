// Dense indices 0, 1, 2, ... of distinct 64-bit keys, in the order they were first inserted:
// an open-addressing hash table (linear probing, at most half full) whose storage is kept
// across clear(), so that a layout rebuild (fluid_exchange.cpp) neither sorts its band cells
// nor allocates a node per cell as std::unordered_map would.
#pragma once

#include <cstdint>
#include <vector>

namespace qdemsph {

class KeyIndex {
 public:
  void clear() {
    slots_.assign(slots_.size(), Slot{});
    n_ = 0;
  }
  std::int64_t size() const { return n_; }

  // The key's index; a new key gets size().
  std::int64_t insert(std::uint64_t key) {
    if (2 * (n_ + 1) > static_cast<std::int64_t>(slots_.size())) grow();
    Slot& s = slots_[probe(key)];
    if (s.index < 0) s = {key, n_++};
    return s.index;
  }
  // The key's index, or -1 when it was not inserted.
  std::int64_t find(std::uint64_t key) const {
    return slots_.empty() ? -1 : slots_[probe(key)].index;
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::int64_t index = -1;  // -1: empty
  };
  // The slot holding key, or the empty slot where it would go.
  std::size_t probe(std::uint64_t key) const {
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = (key * 0x9e3779b97f4a7c15ull) >> shift_;  // Fibonacci hashing
    while (slots_[i].index >= 0 && slots_[i].key != key) i = (i + 1) & mask;
    return i;
  }
  void grow() {
    std::vector<Slot> old(slots_.size() < 1024 ? 2048 : 2 * slots_.size());
    old.swap(slots_);
    shift_ = 64;
    for (std::size_t n = slots_.size(); n > 1; n >>= 1) --shift_;
    for (const Slot& s : old)
      if (s.index >= 0) slots_[probe(s.key)] = s;
  }

  std::vector<Slot> slots_;  // a power of two, 2^(64 - shift_)
  int shift_ = 64;
  std::int64_t n_ = 0;
};

}  // namespace qdemsph
