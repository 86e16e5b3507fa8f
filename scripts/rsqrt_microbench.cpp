// The divider lever (docs/performance.md, "Mass-spring right-hand side"): one
// √ and one division per lane (what an SPH pair and a spring cost the divider) against two
// divider-light forms of the same r = √(r²) and c/r, over 4,096 independent values in L1:
//   exact     vsqrtpd + vdivpd (ymm), what the kernels compute;
//   seeded2   1/√ seeded in float (vsqrtps + vdivps, correctly rounded, so processor-independent)
//             and refined by two Newton steps in double (within 4e-16 of √, not bit-equal);
//   rsqrtps3  1/√ from vrsqrtps (about 12 bits, implementation-defined: results would depend on
//             the processor) and three Newton steps.
// Build and run (AVX2, no FMA, as the project's AVX2 path):
//   c++ -O2 -mavx2 -ffp-contract=off -std=c++20 scripts/rsqrt_microbench.cpp -o /tmp/rsqrt
//   /tmp/rsqrt
#include <immintrin.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <type_traits>
#include <vector>
int main() {
  const int n = 1 << 12;  // 32 KiB of r²: in L1, so the arithmetic is what is timed
  std::vector<double> r2(n), out(n);
  std::mt19937_64 g(1);
  std::uniform_real_distribution<double> u(0.01, 1.0);
  for (auto& x : r2) x = u(g);
  auto timeit = [&](auto f, const char* name) {
    double best = 1e9;
    for (int rep = 0; rep < 2000; ++rep) {
      auto t0 = std::chrono::steady_clock::now();
      f();
      double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      best = std::min(best, s);
    }
    double sum = 0;
    for (double x : out) sum += x;
    std::printf("%-10s %.3f ns a value (checksum %.17g)\n", name, best / n * 1e9, sum);
  };
  const __m256d c = _mm256_set1_pd(0.7);
  timeit(
      [&] {
        for (int i = 0; i < n; i += 4) {
          __m256d x = _mm256_loadu_pd(&r2[i]);
          __m256d r = _mm256_sqrt_pd(x);
          __m256d q = _mm256_div_pd(c, r);
          _mm256_storeu_pd(&out[i], _mm256_add_pd(r, q));
        }
      },
      "exact");
  const __m256d half = _mm256_set1_pd(0.5), th = _mm256_set1_pd(1.5);
  const __m128 onef = _mm_set1_ps(1.0f);
  // A seed y ~ 1/sqrt(x), Steps Newton steps y <- y (3/2 - (x/2) y^2) (multiplications only),
  // then r = x y and c/r = c y, stored as r + c/r like the exact loop.
  const auto seeded = [&]<int Steps>(auto seed, std::integral_constant<int, Steps>) {
    return [&, seed] {
      for (int i = 0; i < n; i += 4) {
        const __m256d x = _mm256_loadu_pd(&r2[i]);
        __m256d y = seed(x);
        const __m256d hx = _mm256_mul_pd(half, x);
        for (int s = 0; s < Steps; ++s)
          y = _mm256_mul_pd(y, _mm256_sub_pd(th, _mm256_mul_pd(hx, _mm256_mul_pd(y, y))));
        _mm256_storeu_pd(&out[i], _mm256_add_pd(_mm256_mul_pd(x, y), _mm256_mul_pd(c, y)));
      }
    };
  };
  timeit(seeded(
             [&](__m256d x) {
               return _mm256_cvtps_pd(_mm_div_ps(onef, _mm_sqrt_ps(_mm256_cvtpd_ps(x))));
             },
             std::integral_constant<int, 2>{}),
         "seeded2");
  timeit(seeded([](__m256d x) { return _mm256_cvtps_pd(_mm_rsqrt_ps(_mm256_cvtpd_ps(x))); },
                std::integral_constant<int, 3>{}),
         "rsqrtps3");
  // accuracy of seeded vs exact
  double maxrel = 0;
  int notexact = 0;
  for (int i = 0; i < n; ++i) {
    float xf = (float)r2[i];
    double y = (double)(1.0f / std::sqrt(xf));
    double hx = 0.5 * r2[i];
    y = y * (1.5 - hx * (y * y));
    y = y * (1.5 - hx * (y * y));
    double r = r2[i] * y, re = std::sqrt(r2[i]);
    maxrel = std::max(maxrel, std::abs(r - re) / re);
    notexact += (r != re);
  }
  std::printf("seeded2 r vs sqrt: max rel %.3g, %d of %d not bit-equal\n", maxrel, notexact, n);
}
