// Exceptions must not cross a C library's frames (SUNDIALS, GSL). A callback body runs inside
// CallbackGuard::run: whatever it throws — the model's exception, or a stop request of
// core/run_control.hpp, including Interrupted, which is not a std::exception — is kept, and the
// library gets `failure` (an unrecoverable error code). The wrapper calls rethrow() when the
// library returns, so the driver ends the run exactly as for a hand-written method (status
// error or timeout, or the interruption).
#pragma once

#include <exception>
#include <type_traits>
#include <utility>

namespace stiffbench {

class CallbackGuard {
 public:
  // The body returns the library's code, or nothing (success: 0).
  template <class F>
  int run(F&& body, int failure) noexcept {
    try {
      if constexpr (std::is_void_v<decltype(body())>) {
        body();
        return 0;
      } else {
        return body();
      }
    } catch (...) {
      if (!pending_) pending_ = std::current_exception();
      return failure;
    }
  }
  void clear() { pending_ = nullptr; }
  void rethrow() {
    if (pending_) std::rethrow_exception(std::exchange(pending_, nullptr));
  }

 private:
  std::exception_ptr pending_;
};

}  // namespace stiffbench
