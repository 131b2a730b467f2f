// Named wall-clock accumulators for the phases of a run (elements, integration, output,
// ...). A Scope stops its timer on destruction; pass a sync function so device work is
// included (on CUDA the phases also appear as NVTX ranges when profiling).
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <string>

namespace qdemsph {

class PhaseTimers {
 public:
  explicit PhaseTimers(std::function<void()> sync = {}) : sync_(std::move(sync)) {}
  class Scope {
   public:
    Scope(PhaseTimers& t, const char* name)
        : t_(t), name_(name), start_(std::chrono::steady_clock::now()) {}
    ~Scope() {
      if (t_.sync_) t_.sync_();
      t_.seconds_[name_] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

   private:
    PhaseTimers& t_;
    const char* name_;
    std::chrono::steady_clock::time_point start_;
  };
  Scope scope(const char* name) { return Scope(*this, name); }
  const std::map<std::string, double>& seconds() const { return seconds_; }

 private:
  std::function<void()> sync_;
  std::map<std::string, double> seconds_;
};

}  // namespace qdemsph
