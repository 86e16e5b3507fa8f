// The spring kernel of MassSpringNetwork's right-hand side (network.hpp's header comment,
// "Right-hand side"): the portable build, its AVX2 build and the AVX-512 runs, chosen at run time.
#include "models/mass_spring/network_parts.hpp"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

namespace stiffbench {

namespace detail {

namespace {

constexpr int kBlock = 128;

template <int D, bool Dashpots>
[[gnu::always_inline]] inline void spring_range_impl(const SpringArgs& s, Index e0, Index e1,
                                                     const double* x, const double* v, double* f) {
  alignas(64) double cr[D][kBlock];
  for (Index b0 = e0; b0 < e1; b0 += kBlock) {
    const int nb = static_cast<int>(std::min<Index>(kBlock, e1 - b0));
    const std::int32_t* si = s.i + b0;
    const std::int32_t* sj = s.j + b0;
    const std::int32_t* kind = s.kind + b0;
#pragma omp simd
    for (int b = 0; b < nb; ++b) {
      const Index pi = si[b], pj = sj[b];
      double r[D], l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        r[c] = x[pj + c] - x[pi + c];
        l2 += r[c] * r[c];
      }
      const double l = std::sqrt(l2);
      double coef = s.k[kind[b]] * (l - s.rest[kind[b]]) / l;
      if constexpr (Dashpots) {
        double ur = 0.0;
        for (int c = 0; c < D; ++c) ur += (v[pj + c] - v[pi + c]) * r[c];
        const double cd = s.damping[b0 + b];
        coef += cd != 0.0 ? cd * ur / l2 : 0.0;
      }
      for (int c = 0; c < D; ++c) cr[c][b] = coef * r[c];
    }
    // The additions, in spring order. Consecutive springs with the same first end (a point's
    // springs are listed together) keep f_i in registers: the same additions in the same order
    // as through memory, without waiting for each store to reach the next load.
    Index cur = -1;
    double fc[D] = {};
    for (int b = 0; b < nb; ++b) {
      if (s.implicit && s.implicit[b0 + b] != s.want) continue;
      const Index pi = si[b];
      if (pi != cur) {
        if (cur >= 0)
          for (int c = 0; c < D; ++c) f[cur + c] = fc[c];
        cur = pi;
        for (int c = 0; c < D; ++c) fc[c] = f[cur + c];
      }
      double* fj = f + sj[b];
      for (int c = 0; c < D; ++c) {
        fc[c] += cr[c][b];
        fj[c] -= cr[c][b];
      }
    }
    if (cur >= 0)
      for (int c = 0; c < D; ++c) f[cur + c] = fc[c];
  }
}

// A run (detail::SpringRun): the same c r as spring_range_impl, from contiguous coordinates
// (the compiler vectorises the stride-D loads and stores with permutes), then f_i += c r for
// the block's springs and f_j -= c r, each a loop over distinct points. Every point's additions
// run in an order fixed by the packing, whatever the vector width.
template <int D, bool Dashpots>
[[gnu::always_inline]] inline void spring_run_impl(const SpringArgs& s,
                                                   const detail::SpringRun& run, const double* x,
                                                   const double* v, double* f) {
  if (s.implicit && run.implicit != s.want) return;
  const double k = s.k[run.kind], rest = s.rest[run.kind];
  alignas(64) double cr[D][kBlock];
  for (Index b0 = 0; b0 < run.n; b0 += kBlock) {
    const int nb = static_cast<int>(std::min<Index>(kBlock, run.n - b0));
    const Index oi = run.i + D * b0, oj = run.j + D * b0;
    const double* xi = x + oi;
    const double* xj = x + oj;
#pragma omp simd
    for (int b = 0; b < nb; ++b) {
      double r[D], l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        r[c] = xj[D * b + c] - xi[D * b + c];
        l2 += r[c] * r[c];
      }
      const double l = std::sqrt(l2);
      double coef = k * (l - rest) / l;
      if constexpr (Dashpots) {
        double ur = 0.0;
        for (int c = 0; c < D; ++c) ur += (v[oj + D * b + c] - v[oi + D * b + c]) * r[c];
        const double cd = s.damping[run.first + b0 + b];
        coef += cd != 0.0 ? cd * ur / l2 : 0.0;
      }
      for (int c = 0; c < D; ++c) cr[c][b] = coef * r[c];
    }
    double* fi = f + oi;
#pragma omp simd
    for (int b = 0; b < nb; ++b)
      for (int c = 0; c < D; ++c) fi[D * b + c] += cr[c][b];
    double* fj = f + oj;
#pragma omp simd
    for (int b = 0; b < nb; ++b)
      for (int c = 0; c < D; ++c) fj[D * b + c] -= cr[c][b];
  }
}

// Group G of the packing: its runs, then its loose springs.
template <int D, bool Dashpots>
[[gnu::always_inline]] inline void spring_group_impl(const SpringArgs& s, Index r0, Index r1,
                                                     Index e0, Index e1, const double* x,
                                                     const double* v, double* f) {
  for (Index r = r0; r < r1; ++r) spring_run_impl<D, Dashpots>(s, s.runs[r], x, v, f);
  spring_range_impl<D, Dashpots>(s, e0, e1, x, v, f);
}

template <int D>
void spring_group_portable(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1,
                           const double* x, const double* v, double* f) {
  if (s.damping)
    spring_group_impl<D, true>(s, r0, r1, e0, e1, x, v, f);
  else
    spring_group_impl<D, false>(s, r0, r1, e0, e1, x, v, f);
}

// A build for AVX2 or better (-march, e.g. STIFFBENCH_NATIVE) uses the portable kernel as is.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__AVX2__)
#define STIFFBENCH_SPRING_AVX2_DISPATCH 1
// The same kernel compiled for AVX2 (4 springs per vector; GCC loads a loose spring's end points
// lane by lane: its vgatherdpd version measured 25% slower on the project's AMD EPYC), chosen at
// run time when the processor has it. With -ffp-contract=off (CMakeLists.txt) the compiler fuses
// no multiply-add, and sqrt and division are correctly rounded, so both versions give the same
// bits.
template <int D>
__attribute__((target("avx2"))) void spring_group_avx2(const SpringArgs& s, Index r0, Index r1,
                                                       Index e0, Index e1, const double* x,
                                                       const double* v, double* f) {
  if (s.damping)
    spring_group_impl<D, true>(s, r0, r1, e0, e1, x, v, f);
  else
    spring_group_impl<D, false>(s, r0, r1, e0, e1, x, v, f);
}
#endif

#if defined(__GNUC__) && defined(__x86_64__)
#define STIFFBENCH_SPRING_AVX512_DISPATCH 1
// A 3D run in AVX-512 (explicit intrinsics, chosen at run time on processors with AVX-512F, in
// any build). The compiler's version of spring_run_impl spends most of its time on permutes: it
// transposes each spring's interleaved (x, y, z) into one vector per coordinate on the way in, and
// back on the way out. Here eight springs' coordinates are three contiguous 512-bit loads per
// end; r = x_j - x_i and r² stay interleaved, and only two things are permuted: the squares into
// one vector per coordinate (two two-source permutes each) for l², and the eight coefficients
// back into the interleaved order of r (one permute per vector). c r is stored interleaved, so
// the additions f_i += c r and f_j -= c r are contiguous vector loops over the block. Every
// operation is spring_run_impl's, in its order (l² = (r_x² + r_y²) + r_z², (u·r) summed from
// +0.0, the additions of f_i before those of f_j within a block of kBlock springs), and sqrt and
// division are correctly rounded, so the bits are the portable kernel's
// (tests/models/test_spring_kernel.cpp compares the builds). The masked forms of sqrt and of the
// one-source permute (all lanes kept) stand for the plain ones, whose GCC 12 versions trip
// -Wmaybe-uninitialized inside avx512fintrin.h (GCC bug 105593).
alignas(64) constexpr std::int64_t kPermIdx[8][8] = {
    {0, 3, 6, 9, 12, 15, 0, 0},  // x components from the first two vectors
    {0, 1, 2, 3, 4, 5, 10, 13},  // ... and the third
    {1, 4, 7, 10, 13, 0, 0, 0},  // y
    {0, 1, 2, 3, 4, 8, 11, 14},
    {2, 5, 8, 11, 14, 0, 0, 0},  // z
    {0, 1, 2, 3, 4, 9, 12, 15},
    {0, 0, 0, 1, 1, 1, 2, 2},  // coefficients 0..7 spread over interleaved elements 0..7
    {2, 3, 3, 3, 4, 4, 4, 5},  // ... 8..15
};
alignas(64) constexpr std::int64_t kSpreadLast[8] = {5, 5, 6, 6, 6, 7, 7, 7};  // ... 16..23

// Σ_c of interleaved triples q0 q1 q2 (eight springs' (x, y, z)), as ((start + q_x) + q_y) + q_z.
__attribute__((target("avx512f"))) inline __m512d sum_triples(__m512d q0, __m512d q1, __m512d q2,
                                                              __m512d start) {
  __m512i idx[6];
  for (int row = 0; row < 6; ++row) idx[row] = _mm512_load_si512(kPermIdx[row]);
  const __m512d qx = _mm512_permutex2var_pd(_mm512_permutex2var_pd(q0, idx[0], q1), idx[1], q2);
  const __m512d qy = _mm512_permutex2var_pd(_mm512_permutex2var_pd(q0, idx[2], q1), idx[3], q2);
  const __m512d qz = _mm512_permutex2var_pd(_mm512_permutex2var_pd(q0, idx[4], q1), idx[5], q2);
  return _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(start, qx), qy), qz);
}

// One spring of a run, spring_run_impl's operations, into the interleaved cr.
template <bool Dashpots>
[[gnu::always_inline]] inline void run_spring_scalar(const double* xi, const double* xj,
                                                     const double* vi, const double* vj, double k,
                                                     double rest, double cd, double* cr) {
  double r[3], l2 = 0.0;
  for (int c = 0; c < 3; ++c) {
    r[c] = xj[c] - xi[c];
    l2 += r[c] * r[c];
  }
  const double l = std::sqrt(l2);
  double coef = k * (l - rest) / l;
  if constexpr (Dashpots) {
    double ur = 0.0;
    for (int c = 0; c < 3; ++c) ur += (vj[c] - vi[c]) * r[c];
    coef += cd != 0.0 ? cd * ur / l2 : 0.0;
  }
  for (int c = 0; c < 3; ++c) cr[c] = coef * r[c];
}

// dst[t] += c[t] (Minus: -=) for t < n, eight at a time.
template <bool Minus>
__attribute__((target("avx512f"))) inline void add_interleaved(double* dst, const double* c,
                                                               int n) {
  int t = 0;
  for (; t + 8 <= n; t += 8) {
    const __m512d a = _mm512_loadu_pd(dst + t), b = _mm512_load_pd(c + t);
    _mm512_storeu_pd(dst + t, Minus ? _mm512_sub_pd(a, b) : _mm512_add_pd(a, b));
  }
  if (t < n) {
    const auto m = static_cast<__mmask8>((1u << (n - t)) - 1u);
    const __m512d a = _mm512_maskz_loadu_pd(m, dst + t), b = _mm512_maskz_load_pd(m, c + t);
    _mm512_mask_storeu_pd(dst + t, m, Minus ? _mm512_sub_pd(a, b) : _mm512_add_pd(a, b));
  }
}

template <bool Dashpots>
__attribute__((target("avx512f"))) void spring_run_avx512(const SpringArgs& s,
                                                          const detail::SpringRun& run,
                                                          const double* x, const double* v,
                                                          double* f) {
  if (s.implicit && run.implicit != s.want) return;
  const double k = s.k[run.kind], rest = s.rest[run.kind];
  const __m512d vk = _mm512_set1_pd(k), vrest = _mm512_set1_pd(rest), zero = _mm512_setzero_pd();
  const __m512i spread0 = _mm512_load_si512(kPermIdx[6]), spread1 = _mm512_load_si512(kPermIdx[7]),
                spread2 = _mm512_load_si512(kSpreadLast);
  alignas(64) double cr[3 * kBlock];
  for (Index b0 = 0; b0 < run.n; b0 += kBlock) {
    const int nb = static_cast<int>(std::min<Index>(kBlock, run.n - b0));
    const Index oi = run.i + 3 * b0, oj = run.j + 3 * b0;
    const double* xi = x + oi;
    const double* xj = x + oj;
    const double* cd = Dashpots ? s.damping + run.first + b0 : nullptr;
    int b = 0;
    for (; b + 8 <= nb; b += 8) {
      const double* pi = xi + 3 * b;
      const double* pj = xj + 3 * b;
      const __m512d r0 = _mm512_sub_pd(_mm512_loadu_pd(pj), _mm512_loadu_pd(pi));
      const __m512d r1 = _mm512_sub_pd(_mm512_loadu_pd(pj + 8), _mm512_loadu_pd(pi + 8));
      const __m512d r2 = _mm512_sub_pd(_mm512_loadu_pd(pj + 16), _mm512_loadu_pd(pi + 16));
      // l² from +0.0 adds nothing to spring_run_impl's sum: r_x² is never -0.0.
      const __m512d l2 =
          sum_triples(_mm512_mul_pd(r0, r0), _mm512_mul_pd(r1, r1), _mm512_mul_pd(r2, r2), zero);
      const __m512d l = _mm512_maskz_sqrt_pd(0xFF, l2);
      __m512d coef = _mm512_div_pd(_mm512_mul_pd(vk, _mm512_sub_pd(l, vrest)), l);
      if constexpr (Dashpots) {
        const double* ui = v + oi + 3 * b;
        const double* uj = v + oj + 3 * b;
        const __m512d u0 = _mm512_sub_pd(_mm512_loadu_pd(uj), _mm512_loadu_pd(ui));
        const __m512d u1 = _mm512_sub_pd(_mm512_loadu_pd(uj + 8), _mm512_loadu_pd(ui + 8));
        const __m512d u2 = _mm512_sub_pd(_mm512_loadu_pd(uj + 16), _mm512_loadu_pd(ui + 16));
        const __m512d ur =
            sum_triples(_mm512_mul_pd(u0, r0), _mm512_mul_pd(u1, r1), _mm512_mul_pd(u2, r2), zero);
        const __m512d c = _mm512_loadu_pd(cd + b);
        const __mmask8 has = _mm512_cmp_pd_mask(c, zero, _CMP_NEQ_UQ);
        coef =
            _mm512_add_pd(coef, _mm512_maskz_mov_pd(has, _mm512_div_pd(_mm512_mul_pd(c, ur), l2)));
      }
      double* out = cr + 3 * b;
      _mm512_store_pd(out, _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xFF, spread0, coef), r0));
      _mm512_store_pd(out + 8, _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xFF, spread1, coef), r1));
      _mm512_store_pd(out + 16,
                      _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xFF, spread2, coef), r2));
    }
    for (; b < nb; ++b)
      run_spring_scalar<Dashpots>(xi + 3 * b, xj + 3 * b, v + oi + 3 * b, v + oj + 3 * b, k, rest,
                                  Dashpots ? cd[b] : 0.0, cr + 3 * b);
    // f_i += c r over the block, then f_j -= c r (each a set of distinct points).
    add_interleaved<false>(f + oi, cr, 3 * nb);
    add_interleaved<true>(f + oj, cr, 3 * nb);
  }
}

// The runs [r0, r1) of a group in 3D on an AVX-512 processor (its loose springs: spring_group).
__attribute__((target("avx512f"))) void spring_runs_avx512(const SpringArgs& s, Index r0, Index r1,
                                                           const double* x, const double* v,
                                                           double* f) {
  for (Index r = r0; r < r1; ++r) {
    if (s.damping)
      spring_run_avx512<true>(s, s.runs[r], x, v, f);
    else
      spring_run_avx512<false>(s, s.runs[r], x, v, f);
  }
}
#endif

// The widest build of the kernel in use (MassSpringNetwork::kernel_isa), at most the processor's
// and at most the process-wide limit set by MassSpringNetwork::limit_kernel_isa.
std::atomic<int> g_isa_limit{static_cast<int>(SpringKernelIsa::avx512)};

SpringKernelIsa processor_isa() {
  static const SpringKernelIsa isa = [] {
#if defined(STIFFBENCH_SPRING_AVX512_DISPATCH)
    if (__builtin_cpu_supports("avx512f")) return SpringKernelIsa::avx512;
#endif
#if defined(STIFFBENCH_SPRING_AVX2_DISPATCH)
    if (__builtin_cpu_supports("avx2")) return SpringKernelIsa::avx2;
#elif defined(__AVX2__)
    return SpringKernelIsa::avx2;  // the portable build is compiled for AVX2 or better
#endif
    return SpringKernelIsa::portable;
  }();
  return isa;
}

}  // namespace

SpringKernelIsa kernel_isa_in_use() {
  return static_cast<SpringKernelIsa>(
      std::min(static_cast<int>(processor_isa()), g_isa_limit.load(std::memory_order_relaxed)));
}

template <int D>
void spring_group(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1, const double* x,
                  const double* v, double* f, SpringKernelIsa isa) {
#ifdef STIFFBENCH_SPRING_AVX512_DISPATCH
  if (D == 3 && isa == SpringKernelIsa::avx512) {
    spring_runs_avx512(s, r0, r1, x, v, f);
    r0 = r1;  // the loose springs below
  }
#endif
#ifdef STIFFBENCH_SPRING_AVX2_DISPATCH
  if (isa != SpringKernelIsa::portable) {
    spring_group_avx2<D>(s, r0, r1, e0, e1, x, v, f);
    return;
  }
#endif
  (void)isa;
  spring_group_portable<D>(s, r0, r1, e0, e1, x, v, f);
}

template void spring_group<1>(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1,
                              const double* x, const double* v, double* f, SpringKernelIsa isa);
template void spring_group<2>(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1,
                              const double* x, const double* v, double* f, SpringKernelIsa isa);
template void spring_group<3>(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1,
                              const double* x, const double* v, double* f, SpringKernelIsa isa);

}  // namespace detail

const char* to_string(SpringKernelIsa isa) {
  switch (isa) {
    case SpringKernelIsa::portable:
      return "portable";
    case SpringKernelIsa::avx2:
      return "avx2";
    case SpringKernelIsa::avx512:
      return "avx512";
  }
  return "?";
}

SpringKernelIsa MassSpringNetwork::kernel_isa() { return detail::kernel_isa_in_use(); }

void MassSpringNetwork::limit_kernel_isa(SpringKernelIsa widest) {
  detail::g_isa_limit.store(static_cast<int>(widest), std::memory_order_relaxed);
}

}  // namespace stiffbench
