// Progress lines on stderr for long experiment loops: "[label] done/total rows, elapsed, ~left:
// what". Silent for the first `quiet_s` seconds (short runs print nothing), then at most one
// line per `every_s` seconds, plus the last row.
#pragma once

#include <chrono>
#include <cstdio>
#include <ostream>
#include <string>

namespace stiffbench {

class Progress {
 public:
  Progress(std::ostream* out, std::string label, long total, double quiet_s = 2.0,
           double every_s = 2.0)
      : out_(out), label_(std::move(label)), total_(total), quiet_s_(quiet_s), every_s_(every_s) {}

  // One more row done; `what` names it (e.g. "rk4, h = 0.01").
  void tick(const std::string& what) {
    ++done_;
    if (!out_) return;
    const double el = elapsed();
    const bool last = done_ >= total_;
    if (el < quiet_s_ && !(last && printed_)) return;
    if (!last && el - last_print_ < every_s_ && printed_) return;
    last_print_ = el;
    printed_ = true;
    char buf[160];
    const double left = done_ > 0 ? el / static_cast<double>(done_) * (total_ - done_) : 0.0;
    std::snprintf(buf, sizeof buf, "[%s] %ld/%ld, %.1f s elapsed, ~%.0f s left: ", label_.c_str(),
                  done_, total_, el, left);
    *out_ << buf << what << "\n" << std::flush;
  }

  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::ostream* out_;
  std::string label_;
  long total_;
  double quiet_s_, every_s_;
  long done_ = 0;
  double last_print_ = 0.0;
  bool printed_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace stiffbench
