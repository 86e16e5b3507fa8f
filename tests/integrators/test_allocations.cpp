// No heap allocation inside a step of any hand-written integrator after the first:
// malloc, calloc, realloc and operator new (which calls malloc) are replaced in this test binary
// by versions that count while a CountAllocations scope is alive. glibc's __libc_* entry points
// do the work. Not built with the sanitizers, which replace the same functions (tests/CMakeLists).
//
// libgomp allocates a thread team each time it enters a parallel region with ONE thread (not
// with two), so the runs use two OpenMP threads; the large cloth takes the parallel paths of the
// network and of the velocity-form solver.
#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <cstdlib>

#include "core/driver.hpp"
#include "tests/test_support.hpp"

extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
}
}  // namespace

extern "C" void* malloc(std::size_t n) {
  count();
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t n, std::size_t size) {
  count();
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* p, std::size_t n) {
  count();
  return __libc_realloc(p, n);
}

namespace stiffbench {
namespace {

using testing_support::model;

struct CountAllocations {
  CountAllocations() {
    g_allocations = 0;
    g_counting = true;
  }
  ~CountAllocations() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};

// The counter sees allocations (a self-check, so that a silent counter cannot pass the test).
TEST(Allocations, CounterCounts) {
  long seen = 0;
  {
    CountAllocations c;
    Vec v(1000);
    v.setOnes();
    std::vector<int> w(10);
    seen = c.count() + static_cast<long>(v.sum() + w.size()) * 0;
  }
  EXPECT_GE(seen, 2);
}

// Every registered fixed-step integrator of the explicit, symplectic, implicit and graphics
// families that can run on the model: reset, two steps (workspaces may grow), then ten steps with
// no allocation. Models: a damped pinned cloth small (ldlt, serial) and large (cg, OpenMP paths),
// and an undamped chain for the velocity-independent methods.
TEST(Allocations, NoneInsideSteps) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
  const std::vector<std::pair<std::string, std::vector<std::string>>> models = {
      {"cloth", {"n=8", "damping=0.1"}},
      {"cloth", {"n=48", "damping=0.1"}},
      {"spring_chain", {"n=20"}}};
  int checked = 0;
  for (const auto& [name, params] : models) {
    auto sys = model(name, params);
    for (const auto& entry : integrator_registry().entries()) {
      const Family f = entry.info.family;
      if (f != Family::explicit_rk && f != Family::symplectic && f != Family::implicit &&
          f != Family::graphics)
        continue;
      auto integ = integrator_registry().create(entry.info.name, Params());
      if (!integ->supports_fixed_step()) continue;
      // radau5, gauss4 and gauss6 above 200 unknowns take the sparse path, covered on smaller
      // cloths below (NoneInsideSparse…; its LU on the cloth 48² would make this test slow);
      // their dense path is covered here (spring_chain) and in NoneInsideAdaptiveSteps.
      const std::string& nm = entry.info.name;
      if ((nm == "radau5" || nm == "gauss4" || nm == "gauss6") && sys->dimension() > 200) continue;
      try {
        check_compatible(integ->info(), *sys);
      } catch (const BadInput&) {
        continue;
      }
      Vec y = sys->initial_state();
      SolveStats stats;
      const double h = 1e-3;
      integ->reset(*sys, 0.0, y);
      for (int i = 0; i < 2; ++i)
        ASSERT_EQ(integ->step(*sys, h * i, y, h, stats), Status::ok) << entry.info.name;
      long allocations = 0;
      {
        CountAllocations c;
        for (int i = 2; i < 12; ++i) integ->step(*sys, h * i, y, h, stats);
        allocations = c.count();
      }
      EXPECT_EQ(allocations, 0) << entry.info.name << " on " << name << " " << params[0];
      ++checked;
    }
  }
  omp_set_num_threads(threads);
  EXPECT_GE(checked, 30);  // every family is covered (about 24 methods on three models)
}

// Steps of `name` with linear_solver=sparse_lu after a first one (the symbolic analysis and the
// pivoting factorisation): allocations in two further steps, which refactorise.
long sparse_lu_step_allocations(const OdeSystem& sys, const std::string& name) {
  auto integ =
      integrator_registry().create(name, Params::from_assignments({"linear_solver=sparse_lu"}));
  Vec y = sys.initial_state();
  SolveStats stats;
  const double h = 1e-3;
  integ->reset(sys, 0.0, y);
  EXPECT_EQ(integ->step(sys, 0.0, y, h, stats), Status::ok) << name;
  const long setups = stats.linear_setups;
  long allocations = 0;
  {
    CountAllocations c;
    for (int i = 1; i < 3; ++i) integ->step(sys, h * i, y, h, stats);
    allocations = c.count();
  }
  EXPECT_GT(stats.linear_setups, setups) << name;  // the steps refactorised
  return allocations;
}

// radau5 and gauss6 on their sparse path (linear_solver=sparse_lu) on the cloth 32² (6144
// unknowns); before SparseRefactorLu (Eigen's SparseLU) 82 a step each.
TEST(Allocations, NoneInsideSparseImplicitSteps) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
  auto sys = model("cloth", {"n=32"});
  for (const std::string name : {"radau5", "gauss6"})
    EXPECT_EQ(sparse_lu_step_allocations(*sys, name), 0) << name;
  omp_set_num_threads(threads);
}

// gauss4 shares gauss6's sparse path (its ShiftedSolver on SparseRefactorLu), on a cloth 12²
// (864 unknowns, above the dense limit of 200); before SparseRefactorLu 64 a step on the cloth
// 32². The other implicit methods' LinearSolver (linear_solver.hpp) keeps Eigen's supernodal
// SparseLU, which allocates (16 to 43 a step on the cloth 32²) but refactorises real matrices
// about 1.3x faster than SparseRefactorLu; it is not covered here.
TEST(Allocations, NoneInsideGauss4SparseSteps) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
  auto sys = model("cloth", {"n=12"});
  EXPECT_EQ(sparse_lu_step_allocations(*sys, "gauss4"), 0);
  omp_set_num_threads(threads);
}

// The adaptive methods (integrators/adaptive/; radau5 on its dense path, the Rosenbrock pairs
// ros3p, rodas4 on their default velocity-form LDLT path and the ESDIRK pairs trbdf2, esdirk43 on
// their default velocity-form solver, on the spring chain whose force Jacobians are written
// without allocation, unlike Kepler's): after a first
// advance_to (workspaces, starting step), further output intervals with their accepted and
// rejected trials allocate nothing.
TEST(Allocations, NoneInsideAdaptiveSteps) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
  auto kepler = model("kepler", {"e=0.5"});
  auto chain = model("spring_chain", {"n=20"});
  for (const std::string name :
       {"bs3", "dopri5", "cash_karp", "rkf45", "radau5", "ros3p", "rodas4", "trbdf2", "esdirk43"}) {
    const bool implicit = name == "radau5" || name == "ros3p" || name == "rodas4" ||
                          name == "trbdf2" || name == "esdirk43";
    const OdeSystem& sys = implicit ? *chain : *kepler;
    // ros3p's error estimate vanishes on a linear autonomous model like this chain
    // (rosenbrock.hpp), so only h_max keeps its steps small enough to count.
    auto integ = integrator_registry().create(
        name, Params::from_assignments({"rtol=1e-8", name == "ros3p" ? "h_max=0.05" : "h0=0"}));
    Vec y = sys.initial_state();
    SolveStats stats;
    integ->reset(sys, 0.0, y);
    ASSERT_EQ(integ->advance_to(sys, 0.5, y, stats), Status::ok) << name;
    long allocations = 0;
    Status st = Status::ok;
    {
      CountAllocations c;
      for (int i = 2; i <= 10 && st == Status::ok; ++i)
        st = integ->advance_to(sys, 0.5 * i, y, stats);
      allocations = c.count();
    }
    EXPECT_EQ(st, Status::ok) << name;
    EXPECT_GT(stats.steps, 20) << name;
    EXPECT_EQ(allocations, 0) << name;
  }
  omp_set_num_threads(threads);
}

// The adaptive driver computes its equally spaced output stops one at a time: the allocations up
// to the first observer call (at t0) are the same for 1 output and for 10^8 (before, it built the
// list of stops first, 800 MB at 10^8 and about 27 reallocations on the way). The observer ends
// the run at its first call by throwing.
TEST(Allocations, AdaptiveOutputStopsCostNoMemory) {
  struct Stop {};
  const auto allocations_before_first_output = [](long outputs) {
    auto sys = model("kaps", {});
    auto integ = testing_support::make("dopri5", {});
    CountAllocations c;
    try {
      run_adaptive(*sys, *integ, {1.0, outputs}, [](double, CVecRef) { throw Stop{}; });
    } catch (const Stop&) {
    }
    return c.count();
  };
  EXPECT_EQ(allocations_before_first_output(100'000'000), allocations_before_first_output(1));
}

}  // namespace
}  // namespace stiffbench
