// Hands out the blocks [0, n) of a parallel loop so that each thread works on a contiguous
// stretch and the threads still finish together. The blocks are cut into one contiguous segment
// per thread; thread t takes the blocks of its own segment from the front, and when that is
// empty takes blocks from the back of the other segments (the classic work-stealing split).
//
// Why not OpenMP's schedule(dynamic): it gives consecutive blocks to alternating threads, so a
// pass reads neighbour data (positions, densities, pressures) that the other core wrote in the
// previous pass, and every such cache line moves between the cores. With equal cores the SPH
// passes ran 20-25% slower that way than with schedule(static) (2 threads,
// bench/bench_sph.cpp). Why not schedule(static): the two vCPUs of the development machine at
// times differ by up to 1.7x in speed, and equal static shares then wait for the slower one.
// Here the split follows the cores' speeds and moves only at the segments' tails.
//
// The order in which the blocks are processed never affects the results when, as in the SPH
// passes, each block's outputs depend only on the pass's inputs.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

namespace stiffbench::sph {

class BlockQueue {
 public:
  BlockQueue() = default;
  // A copy starts empty (reset() fills it before each loop).
  BlockQueue(const BlockQueue&) {}
  BlockQueue& operator=(const BlockQueue&) { return *this; }

  // Blocks [0, blocks) in `segments` contiguous segments, segment s the s-th of equal shares
  // (the split of OpenMP's schedule(static) over as many threads). Not thread-safe: call it
  // before the parallel region.
  void reset(std::int64_t blocks, int segments) {
    if (segments < 1) segments = 1;
    if (segments != segments_) {
      seg_ = std::make_unique<Segment[]>(static_cast<std::size_t>(segments));
      segments_ = segments;
    }
    for (int s = 0; s < segments; ++s) {
      const std::int64_t first = blocks * s / segments, last = blocks * (s + 1) / segments;
      seg_[static_cast<std::size_t>(s)].range.store(pack(first, last), std::memory_order_relaxed);
    }
  }

  // The next block for thread t (its own segment's front first, then the other segments' backs
  // in turn), or -1 when every block has been handed out. t >= 0; threads t >= segments only
  // steal.
  std::int64_t next(int t) {
    if (t < segments_) {
      const std::int64_t b = take(seg_[static_cast<std::size_t>(t)], true);
      if (b >= 0) return b;
    }
    for (int k = 1; k <= segments_; ++k) {
      const int s = (t + k) % segments_;
      if (s == t) continue;
      const std::int64_t b = take(seg_[static_cast<std::size_t>(s)], false);
      if (b >= 0) return b;
    }
    return -1;
  }

 private:
  // [front, back) of one segment in one word, so that a take is one compare-and-swap.
  struct alignas(64) Segment {
    std::atomic<std::uint64_t> range{0};
  };

  static std::uint64_t pack(std::int64_t front, std::int64_t back) {
    return static_cast<std::uint64_t>(front) | (static_cast<std::uint64_t>(back) << 32);
  }

  static std::int64_t take(Segment& s, bool from_front) {
    std::uint64_t r = s.range.load(std::memory_order_relaxed);
    while (true) {
      const auto front = static_cast<std::int64_t>(r & 0xffffffffu);
      const auto back = static_cast<std::int64_t>(r >> 32);
      if (front >= back) return -1;
      const std::uint64_t want = from_front ? pack(front + 1, back) : pack(front, back - 1);
      if (s.range.compare_exchange_weak(r, want, std::memory_order_relaxed))
        return from_front ? front : back - 1;
    }
  }

  std::unique_ptr<Segment[]> seg_;
  int segments_ = 0;
};

}  // namespace stiffbench::sph
