// Cost of one SPH right-hand-side evaluation (density pass, forces, neighbour-grid rebuild) on
// the dam-break and drop scenes, reported per particle ("ns_per_particle", the figure the PySPH
// compares with PySPH's 0.34-0.41 µs per particle-step on 2 threads). The thread count is
// OpenMP's (OMP_NUM_THREADS).
//
//   build/bench/stiffbench_bench_sph --benchmark_min_time=0.5
#include <benchmark/benchmark.h>
#include <omp.h>

#include "experiments/framework/catalog.hpp"

namespace {

using namespace stiffbench;

void sph_rhs(benchmark::State& state, const std::string& model, const std::string& n_key) {
  Params p;
  p.set(n_key, std::to_string(state.range(0)));
  const auto sys = model_registry().create(model, p);
  Vec y = sys->initial_state(), f(y.size());
  // 50 symplectic Euler steps at the suggested step (the dam break's column starts to fall), so
  // that the particles are off their initial lattice.
  const double h = sys->suggested_step()->h;
  const Index n = y.size() / 2;
  for (int k = 0; k < 50; ++k) {
    sys->rhs(0.0, y, f);
    y.tail(n) += h * f.tail(n);
    y.head(n) += h * y.tail(n);
  }
  for (auto _ : state) {
    sys->rhs(0.0, y, f);
    benchmark::DoNotOptimize(f.data());
  }
  const double particles = static_cast<double>(sys->as_mechanical()->dofs()) / 2.0;
  state.counters["particles"] = particles;
  state.counters["threads"] = omp_get_max_threads();
  state.counters["ns_per_particle"] =
      benchmark::Counter(particles * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_SphDamBreak2dRhs(benchmark::State& state) { sph_rhs(state, "sph_dam_break_2d", "n"); }
void BM_SphDrop2dRhs(benchmark::State& state) { sph_rhs(state, "sph_drop_2d", "n"); }

// 32 across: 2,048 fluid particles (the default); 45 across: 4,050 (PySPH's example has 3,938).
BENCHMARK(BM_SphDamBreak2dRhs)->Arg(32)->Arg(45)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SphDrop2dRhs)->Arg(50)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
