// Neighbour search on a uniform grid of cubic cells (a dense box grid or a hashed cell list),
// built by a counting sort (O(n) time; O(n) memory in the hashed mode).
//
// build(x, n, radius) maps each point to the integer cell floor(x / cell), cell = radius (1 + 1e-6)
// (per coordinate, clamped to ±kCellLimit so that points far away or non-finite never overflow;
// clamping only merges cells, never separates true neighbours), hashes the cell to one of B buckets
// (B a power of two >= 2n) and sorts the points by bucket with a stable counting sort, so within a
// bucket the points stay in index order. Each sorted entry keeps its cell key and a copy of its
// coordinates.
//
// for_each_neighbour(q, radius), radius <= the radius given to build(), visits the 3^D cells around
// q's cell in a fixed order, and in each the entries of the cell's bucket whose key is that cell
// (other cells hashed to the same bucket are skipped), calling f(j, r², d) for every point j with
// r² = |q - x_j|² < radius² and d = q - x_j. The visiting order depends only on the positions, so a
// sum over the neighbours of one point is the same, bit for bit, whichever thread computes it.
// Coincident points (r = 0) and the query point itself, when it is in the set, are visited.
//
// When the cells' bounding box holds at most 8n + 64 cells (the usual case: a fluid in a tank),
// build() uses a dense row-major grid over the box instead of the hash, so that each row of 3
// cells is one contiguous range of slots (one look-up instead of three, no key checks: the 2D
// dam break's right-hand side went from 0.62-0.68 to 0.47-0.50 µs per particle on one thread).
// Within a cell, points stay in index order in both modes, and the mode depends on the positions
// only.
//
// order() lists the points cell by cell (bucket order): iterating in that order touches memory
// of nearby points together. The caller's own arrays are never reordered.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace stiffbench::sph {

template <int D>
class NeighbourGrid {
 public:
  static constexpr std::int64_t kCellLimit = (std::int64_t{1} << 20) - 2;

  // x: n points, D coordinates each (interleaved); radius > 0 the largest search radius. The
  // cells are a hair larger than the radius (factor 1 + 1e-6): floor(x / cell) is computed as
  // floor(x · (1/cell)), whose rounding could otherwise put two points just under one cell
  // apart into cells two apart (found by the brute-force test), and the 3^D search would miss
  // them. The margin exceeds that rounding for every coordinate below the clamp limit.
  void build(const double* x, Index n, double radius) {
    inv_cell_ = 1.0 / (radius * (1.0 + 1e-6));
    n_ = n;
    const std::size_t nu = static_cast<std::size_t>(n);
    keys_.resize(nu);
    point_key_.resize(nu);
    order_.resize(nu);
    pos_.resize(nu * D);
    point_cell_.resize(nu * D);
    // Dense mode when the cells' bounding box is small (at most 8n + 64 cells): a cell is a
    // row-major index into the box, so the 3 cells of a row are one contiguous range of slots.
    // Otherwise (points far apart, non-finite coordinates) the hashed mode.
    for (int d = 0; d < D; ++d) {
      lo_[d] = kCellLimit;
      hi_[d] = -kCellLimit;
    }
    for (std::size_t i = 0; i < nu; ++i) {
      const auto c = cell_of(x + D * i);
      for (int d = 0; d < D; ++d) {
        point_cell_[i * D + d] = c[d];
        lo_[d] = std::min(lo_[d], c[d]);
        hi_[d] = std::max(hi_[d], c[d]);
      }
    }
    double box = 1.0;
    for (int d = 0; d < D; ++d) box *= n > 0 ? static_cast<double>(hi_[d] - lo_[d] + 1) : 1.0;
    dense_ = n > 0 && box <= 8.0 * static_cast<double>(n) + 64.0;
    std::size_t slots_of_index = 0;
    if (dense_) {
      std::int64_t stride = 1;
      for (int d = 0; d < D; ++d) {
        stride_[d] = stride;
        stride *= hi_[d] - lo_[d] + 1;
      }
      slots_of_index = static_cast<std::size_t>(stride);
    } else {
      std::size_t buckets = 16;
      shift_ = 60;
      while (buckets < 2 * nu) {
        buckets *= 2;
        --shift_;
      }
      slots_of_index = buckets;
    }
    start_.assign(slots_of_index + 1, 0);
    for (std::size_t i = 0; i < nu; ++i) {
      std::array<std::int64_t, D> c;
      for (int d = 0; d < D; ++d) c[d] = point_cell_[i * D + d];
      const std::uint64_t key = dense_ ? dense_index(c) : pack(c);
      point_key_[i] = key;
      ++start_[(dense_ ? static_cast<std::size_t>(key) : bucket(key)) + 1];
    }
    for (std::size_t b = 0; b < slots_of_index; ++b) start_[b + 1] += start_[b];
    fill_ = start_;
    for (std::size_t i = 0; i < nu; ++i) {
      const std::uint64_t key = point_key_[i];
      const std::size_t slot = fill_[dense_ ? static_cast<std::size_t>(key) : bucket(key)]++;
      order_[slot] = static_cast<Index>(i);
      keys_[slot] = key;
      for (int d = 0; d < D; ++d) pos_[slot * D + d] = x[D * i + d];
    }
  }

  Index size() const { return n_; }
  const std::vector<Index>& order() const { return order_; }
  // Coordinates in cell order (D per point): positions()[D·slot + d] = x[D·order()[slot] + d].
  const double* positions() const { return pos_.data(); }

  template <class F>
  void for_each_neighbour(const double* q, double radius, F&& f) const {
    for_each_neighbour_slot(
        q, radius, [&](std::size_t slot, double r2, const auto& d) { f(order_[slot], r2, d); });
  }

  // The same, passing the neighbour's slot in cell order (order()[slot] is its index, and
  // positions() + D·slot its coordinates): callers that keep their per-point data in cell order
  // read neighbours from nearby memory.
  template <class F>
  void for_each_neighbour_slot(const double* q, double radius, F&& f) const {
    const double r2max = radius * radius;
    const auto c = cell_of(q);
    if (dense_) {
      // Rows of 3 cells along x, for each of the 3^(D-1) (y, z) offsets.
      const std::int64_t xa = std::max(c[0] - 1, lo_[0]), xb = std::min(c[0] + 1, hi_[0]);
      if (xa > xb) return;
      for (int k = 0; k < ipow3() / 3; ++k) {
        std::int64_t base = 0;
        bool inside = true;
        int rest = k;
        for (int d = 1; d < D; ++d) {
          const std::int64_t cd = c[d] + rest % 3 - 1;
          rest /= 3;
          inside = inside && cd >= lo_[d] && cd <= hi_[d];
          base += (cd - lo_[d]) * stride_[d];
        }
        if (!inside) continue;
        const std::size_t first = start_[static_cast<std::size_t>(base + xa - lo_[0])];
        const std::size_t last = start_[static_cast<std::size_t>(base + xb - lo_[0]) + 1];
        visit_range(q, r2max, first, last, f);
      }
      return;
    }
    // Near the clamp limit two offsets can name the same (clamped) cell: visit it once.
    bool near_limit = false;
    for (int d = 0; d < D; ++d) near_limit |= std::abs(c[d]) >= kCellLimit - 1;
    std::array<std::uint64_t, ipow3()> visited{};
    int n_visited = 0;
    std::array<std::int64_t, D> o{};
    for (int k = 0; k < ipow3(); ++k) {
      int rest = k;
      for (int d = 0; d < D; ++d) {
        o[d] = std::clamp<std::int64_t>(c[d] + rest % 3 - 1, -kCellLimit, kCellLimit);
        rest /= 3;
      }
      const std::uint64_t key = pack(o);
      if (near_limit) {
        if (std::find(visited.begin(), visited.begin() + n_visited, key) !=
            visited.begin() + n_visited)
          continue;
        visited[static_cast<std::size_t>(n_visited++)] = key;
      }
      const std::size_t b = bucket(key);
      for (std::size_t s = start_[b]; s < start_[b + 1]; ++s) {
        if (keys_[s] != key) continue;
        visit_range(q, r2max, s, s + 1, f);
      }
    }
  }

  // True when the last build used the dense bounding-box grid (else the hashed one).
  bool dense() const { return dense_; }

 private:
  static constexpr int ipow3() { return D == 1 ? 3 : D == 2 ? 9 : 27; }

  template <class F>
  void visit_range(const double* q, double r2max, std::size_t first, std::size_t last, F& f) const {
    for (std::size_t s = first; s < last; ++s) {
      std::array<double, D> dx;
      double r2 = 0.0;
      for (int d = 0; d < D; ++d) {
        dx[d] = q[d] - pos_[s * D + d];
        r2 += dx[d] * dx[d];
      }
      if (r2 < r2max) f(s, r2, dx);
    }
  }

  std::uint64_t dense_index(const std::array<std::int64_t, D>& c) const {
    std::int64_t idx = 0;
    for (int d = 0; d < D; ++d) idx += (c[d] - lo_[d]) * stride_[d];
    return static_cast<std::uint64_t>(idx);
  }

  std::array<std::int64_t, D> cell_of(const double* x) const {
    std::array<std::int64_t, D> c;
    for (int d = 0; d < D; ++d) {
      const double s = std::floor(x[d] * inv_cell_);
      // NaN and ±inf land in the limit cell; their distance test always fails.
      c[d] = !(s > -static_cast<double>(kCellLimit))  ? -kCellLimit
             : !(s < static_cast<double>(kCellLimit)) ? kCellLimit
                                                      : static_cast<std::int64_t>(s);
    }
    return c;
  }

  static std::uint64_t pack(const std::array<std::int64_t, D>& c) {
    std::uint64_t key = 0;
    for (int d = 0; d < D; ++d)
      key = (key << 21) | static_cast<std::uint64_t>(c[d] + kCellLimit + 1);
    return key;
  }

  std::size_t bucket(std::uint64_t key) const {
    // Fibonacci hashing: the top log2(B) bits of key·2^64/φ spread neighbouring cells across
    // the buckets.
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }

  double inv_cell_ = 1.0;
  bool dense_ = false;
  std::array<std::int64_t, D> lo_{}, hi_{}, stride_{};
  std::vector<std::int64_t> point_cell_;
  Index n_ = 0;
  int shift_ = 60;
  std::vector<std::size_t> start_, fill_;
  std::vector<std::uint64_t> keys_, point_key_;
  std::vector<Index> order_;
  std::vector<double> pos_;
};

}  // namespace stiffbench::sph
