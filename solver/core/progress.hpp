// A one-line progress report for long runs (simulated time, steps/s, ETA), redrawn at most
// twice a second on stderr, and silent when stderr is not a terminal (CI logs stay clean).
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>

namespace qdemsph {

class ProgressLine {
 public:
  explicit ProgressLine(bool enabled = isatty(STDERR_FILENO) != 0) : enabled_(enabled) {}
  ~ProgressLine() { finish(); }
  // fraction in [0, 1]; label e.g. "t = 0.12 s".
  void update(double fraction, std::int64_t steps, const char* label) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(500)) return;
    last_ = now;
    const double el = std::chrono::duration<double>(now - start_).count();
    const double rate = el > 0 ? steps / el : 0;
    const double eta = fraction > 0 ? el * (1 - fraction) / fraction : 0;
    std::fprintf(stderr, "\r%5.1f%%  %s  %lld steps  %.0f steps/s  ETA %.0f s   ", 100 * fraction,
                 label, static_cast<long long>(steps), rate, eta);
    std::fflush(stderr);
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::fputc('\n', stderr);
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace qdemsph
