#include "experiments/support/timing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stiffbench {

std::size_t uniform_index(std::mt19937_64& rng, std::size_t n) {
  // Rejection: draws above the largest multiple of n are redrawn, so every index is equally
  // likely (2^64 mod n of the 2^64 values are rejected).
  const std::uint64_t range = static_cast<std::uint64_t>(n);
  const std::uint64_t limit =
      std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % range;
  std::uint64_t x = rng();
  while (x >= limit) x = rng();
  return static_cast<std::size_t>(x % range);
}

std::vector<std::size_t> run_order(std::size_t n, std::uint64_t seed, std::uint64_t round) {
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(round), 0u};
  std::mt19937_64 rng(seq);
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[uniform_index(rng, i)]);
  return order;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  if (v.size() % 2 == 1) return v[m];
  const double hi = v[m];
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m));
  return 0.5 * (lo + hi);
}

TimingSpread timing_spread(const std::vector<double>& samples, std::uint64_t seed,
                           std::uint64_t stream, int resamples) {
  if (samples.empty()) throw std::logic_error("timing_spread: empty sample");
  if (resamples < 1) throw std::logic_error("timing_spread: resamples must be >= 1");
  TimingSpread t;
  t.repeats = static_cast<int>(samples.size());
  t.median = median_of(samples);
  t.min = *std::min_element(samples.begin(), samples.end());
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(stream), static_cast<std::uint32_t>(stream >> 32),
                    1u};
  std::mt19937_64 rng(seq);
  std::vector<double> medians(static_cast<std::size_t>(resamples)), draw(samples.size());
  for (auto& m : medians) {
    for (auto& d : draw) d = samples[uniform_index(rng, samples.size())];
    m = median_of(draw);
  }
  std::sort(medians.begin(), medians.end());
  // m_(ceil(q·B)), 1-based.
  const auto quantile = [&](double q) {
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(resamples) - 1e-9));
    return medians[std::clamp<std::size_t>(k, 1, medians.size()) - 1];
  };
  t.ci_low = quantile(0.025);
  t.ci_high = quantile(0.975);
  return t;
}

}  // namespace stiffbench
