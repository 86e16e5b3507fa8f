// Timing with spread, shared by the studies that time repeated runs (work-precision, budget,
// recommend): the rounds' shuffled order, the repeat limits, the median with a bootstrap
// interval, and the column names of the timing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/params.hpp"

namespace stiffbench {

// Every point (one integrator at one h or tolerance) runs in round 1; in round k >= 2 it runs
// again while it has run fewer than `repeats` times, its first run took under kRepeatLongRun
// seconds and its runs so far took under kRepeatBudget seconds in total (a run of a second or
// more runs once). Each round visits its points in an order shuffled with the spec's seed
// (run_order), so methods are interleaved and slow drifts of the machine spread over all of
// them. A point whose run did not end ok is not repeated. Every repeat must reproduce the first
// run exactly (status, final state, every counter): a mismatch turns the row into status
// `error` naming the field (a nondeterministic method is a bug).
constexpr double kRepeatLongRun = 1.0;  // s: a first run this long is not repeated
constexpr double kRepeatBudget = 2.0;   // s: total of a point's runs before it stops repeating
constexpr int kBootstrapResamples = 2000;

// An integer uniform in [0, n) from rng by rejection (exact and the same on every standard
// library, unlike std::uniform_int_distribution). n >= 1.
std::size_t uniform_index(std::mt19937_64& rng, std::size_t n);
// The visiting order of round `round` over n points: a permutation of 0..n-1 by Fisher-Yates
// with std::mt19937_64 seeded by std::seed_seq{seed, round, 0}; the same for the same arguments.
std::vector<std::size_t> run_order(std::size_t n, std::uint64_t seed, std::uint64_t round);

// Median (mean of the two middle values for an even count); NaN for an empty sample.
double median_of(std::vector<double> v);

struct TimingSpread {
  double median = 0, min = 0, ci_low = 0, ci_high = 0;
  int repeats = 0;
};
// Median and minimum of the sample and the bootstrap 95% percentile interval of the median:
// `resamples` resamples of the sample's size drawn with replacement (uniform_index on
// std::mt19937_64 seeded by std::seed_seq{seed, stream, 1}); the interval is the 2.5% and 97.5%
// quantiles of their medians, each the order statistic m_(ceil(q·B)) of the B sorted medians.
// A sample of one value gives the value itself. `samples` must not be empty.
TimingSpread timing_spread(const std::vector<double>& samples, std::uint64_t seed,
                           std::uint64_t stream, int resamples = kBootstrapResamples);

// The timing columns of work_precision.csv, in order: the median, the fastest run, the
// bootstrap interval of the median and the number of runs (read by
// experiments/commands/compare.cpp).
struct TimingColumnNames {
  const char *median, *min, *ci_low, *ci_high, *runs;
};
inline constexpr TimingColumnNames kWallTimingColumns{"wall_s_median", "wall_s_min",
                                                      "wall_s_ci_low", "wall_s_ci_high", "repeats"};

// The option of the studies timed this way (work-precision, budget): the most runs per
// setting, declared once.
inline ParamSpec timing_repeats_option(const std::string& default_value) {
  return {"repeats", ParamType::integer, default_value,
          "most runs per setting (a first run of 1 s or more runs once; repeats stop once a "
          "setting's runs total 2 s); the time is their median, with a bootstrap 95% interval",
          Bounds::at_least(1)};
}

}  // namespace stiffbench
