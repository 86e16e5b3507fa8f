// Heap allocation counting for the benchmark binary. The bench links alloc_count.cpp, which
// replaces malloc, calloc, realloc, posix_memalign, aligned_alloc and memalign (forwarding to
// glibc's __libc_* entry points) and the global operator new family: Eigen allocates its
// vectors with malloc, not operator new, so counting only operator new would miss a temporary
// Eigen vector inside a step. Every call made while counting is active — on any thread, so
// OpenMP workers count too — increments one counter; calls outside an active region cost one
// relaxed atomic load.
#pragma once

namespace stiffbench::bench {

// Starts counting (resets the counter to zero).
void alloc_count_start();
// Stops counting and returns the number of allocations since alloc_count_start().
long alloc_count_stop();

// RAII: counts allocations during its lifetime; count() reads the total so far.
class AllocCounter {
 public:
  AllocCounter() { alloc_count_start(); }
  ~AllocCounter() {
    if (!stopped_) alloc_count_stop();
  }
  AllocCounter(const AllocCounter&) = delete;
  AllocCounter& operator=(const AllocCounter&) = delete;
  long stop() {
    stopped_ = true;
    total_ = alloc_count_stop();
    return total_;
  }

 private:
  bool stopped_ = false;
  long total_ = 0;
};

}  // namespace stiffbench::bench
