// Orchestration twin (host): sorts contact records by key. The CUDA twin
// (contact_sort_cuda.cuh) sorts the same records on the device.
#pragma once

#include <algorithm>
#include <cstdint>

#include "contact/contact_record.hpp"
#include "core/exec_host.hpp"
#include "core/memory.hpp"

namespace qdemsph {

inline void sort_records(HostExec, View<ContactRecord> r, std::int64_t n) {
  std::sort(r.p, r.p + n,
            [](const ContactRecord& a, const ContactRecord& b) { return key_less(a, b); });
}

}  // namespace qdemsph
