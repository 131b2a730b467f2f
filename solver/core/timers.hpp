// Named wall-clock accumulators for the phases of a run (elements, integration, output,
// contact.broad, ...). A Scope stops its timer on destruction; pass a sync function so device
// work is included. A launch() scope does not synchronise: it times the host's kernel launches
// only, and its device work counts in the next synchronised scope (for work that should overlap
// what follows, e.g. the interior tets with the halo exchange).
//
// NVTX: in a CUDA build every Scope is also an NVTX range of the same name (nvtx3, header-only,
// from the CUDA toolkit), so `nsys profile qdemsph run ...` shows the phases on its timeline.
// Without a profiler attached a range costs a few nanoseconds (a null-pointer check); without
// CUDA it is compiled out.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <string>

#if defined(QDEMSPH_HAVE_CUDA) && __has_include(<nvtx3/nvToolsExt.h>)
#include <nvtx3/nvToolsExt.h>
#define QDEMSPH_NVTX_PUSH(name) nvtxRangePushA(name)
#define QDEMSPH_NVTX_POP() nvtxRangePop()
#else
#define QDEMSPH_NVTX_PUSH(name) ((void)0)
#define QDEMSPH_NVTX_POP() ((void)0)
#endif

namespace qdemsph {

class PhaseTimers {
 public:
  explicit PhaseTimers(std::function<void()> sync = {}) : sync_(std::move(sync)) {}
  class Scope {
   public:
    Scope(PhaseTimers& t, const char* name, bool sync = true)
        : t_(t), name_(name), sync_(sync), start_(std::chrono::steady_clock::now()) {
      QDEMSPH_NVTX_PUSH(name);
    }
    ~Scope() {
      if (sync_ && t_.sync_) t_.sync_();
      QDEMSPH_NVTX_POP();
      t_.seconds_[name_] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

   private:
    PhaseTimers& t_;
    const char* name_;
    bool sync_;
    std::chrono::steady_clock::time_point start_;
  };
  Scope scope(const char* name) { return Scope(*this, name); }
  Scope launch(const char* name) { return Scope(*this, name, false); }
  const std::map<std::string, double>& seconds() const { return seconds_; }
  void clear() { seconds_.clear(); }
  // Drops every timer but `name` (set-up work reported apart from the steps').
  void clear_except(const std::string& name) {
    std::erase_if(seconds_, [&](const auto& e) { return e.first != name; });
  }

 private:
  std::function<void()> sync_;
  std::map<std::string, double> seconds_;
};

}  // namespace qdemsph
