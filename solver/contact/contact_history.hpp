// The tangential history of the contact stage as plain host arrays: one entry per feature pair
// in contact at the last step, sorted by key (k1, k2), with its spring xi and the vertices of
// its record (side 1 then side 2, -1: unused). Keys and vertices use the uploaded model's
// indices (contact_record.hpp); a distributed run (parallel/distributed_backend.cpp) re-maps
// them to global ids when the decomposition changes, so the history survives migration.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph {

struct ContactHistory {
  std::vector<std::uint64_t> k1, k2;
  std::vector<Vec3> xi;
  std::vector<std::array<std::int32_t, 4>> v;
  std::size_t size() const { return k1.size(); }
};

}  // namespace qdemsph
