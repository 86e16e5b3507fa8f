// Per-step cost of integrators:
//   step/<integrator>/cloth:<n>/omp:<t>   every fixed-step hand-written integrator, one step() per
//       iteration after an untimed first step (start-up, workspaces), with counters f/step (the
//       system's f evaluations per step), overhead = step time / (f/step × time of one
//       acceleration() on the same state), and allocs/step (heap allocations inside the timed
//       steps, alloc_count.hpp);
//   solve/<integrator>/cloth:512/omp:<t>  the same method through the fixed-step driver
//       (run_fixed_step_from, 20 steps per iteration: what `stiffbench solve` runs, including
//       the driver's blow-up check after each step and its reset per run);
//   paired/rk4_vs_4_symplectic_euler/{step,driver}/cloth:512/omp:2  the two methods in
//       alternating rounds, each round's ratio rk4 step / (4 × symplectic_euler step) kept for
//       the summary (paired_rounds, bench_common.hpp);
//   peer/<library>_rk4/cloth:512/omp:<t>  classic RK4 of Boost.Odeint (runge_kutta4 over
//       std::vector<double>), GSL (gsl_odeiv2_step_rk4 through gsl_odeiv2_driver_apply_fixed_step;
//       GSL's rk4 estimates its error by step doubling and returns two steps of h/2, so one of its
//       steps is three RK4 steps of work: compare per f evaluation) and SUNDIALS ARKODE ERKStep
//       (the classic RK4 Butcher table built with ARKodeButcherTable_Create — SUNDIALS 6.4 ships
//       no classic RK4 ERK table — without an embedding, at ERKStepSetFixedStep), each calling
//       the testbed's rhs() on the same cloth and the same contiguous state layout, one step per
//       iteration, each first checked against the testbed's rk4 (peer_check).
#include <arkode/arkode_erkstep.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <boost/numeric/odeint/stepper/runge_kutta4.hpp>
#include <cmath>
#include <cstdio>

#include "bench/alloc_count.hpp"
#include "bench/bench_common.hpp"
#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "models/mass_spring/network.hpp"

namespace stiffbench::bench {

namespace {

std::string omp_suffix(int threads) { return "/omp:" + std::to_string(threads); }

}  // namespace

// Shared with bench_implicit.cpp.
void integrator_step(benchmark::State& st, long side, const std::string& name, const Params& params,
                     double h, int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model("cloth", {{"n", std::to_string(side)}});
  const OdeSystem& sys = *cm.sys;
  const auto* mech = sys.as_mechanical();
  const Index n = mech->dofs();
  std::unique_ptr<Integrator> integ;
  try {
    integ = integrator_registry().create(name, params);
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  Vec y = cm.warm;
  double t = 0.0;
  SolveStats stats;
  Status status = Status::ok;
  try {
    integ->reset(sys, t, y);
    status = integ->step(sys, t, y, h, stats);
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  if (status != Status::ok) {
    st.SkipWithError(("first step: " + to_string(status) + " " + stats.message).c_str());
    return;
  }
  t += h;
  Vec a(n);
  const double f_time =
      best_seconds_per_call([&] { mech->acceleration(t, y.head(n), y.tail(n), a); }, 3);
  sys.reset_counters();
  const long jac_before = stats.jac_evals, krylov_before = stats.linear_iters,
             newton_before = stats.newton_iters;
  long steps = 0;
  const double start = now_seconds();
  alloc_count_start();
  try {
    for (auto _ : st) {
      status = integ->step(sys, t, y, h, stats);
      t += h;
      ++steps;
      if (status != Status::ok) {
        st.SkipWithError((to_string(status) + " " + stats.message).c_str());
        break;
      }
    }
  } catch (const std::exception& e) {
    alloc_count_stop();
    st.SkipWithError(e.what());
    return;
  }
  const long allocs = alloc_count_stop();
  const double elapsed = now_seconds() - start;
  if (status != Status::ok) return;
  const double per_step = elapsed / static_cast<double>(steps);
  const double f_per_step =
      static_cast<double>(sys.counters().f_evals) / static_cast<double>(steps);
  st.counters["f/step"] = f_per_step;
  st.counters["jac/step"] =
      static_cast<double>(stats.jac_evals - jac_before + sys.counters().jac_evals) /
      static_cast<double>(steps);
  if (stats.newton_iters > newton_before)
    st.counters["newton/step"] =
        static_cast<double>(stats.newton_iters - newton_before) / static_cast<double>(steps);
  if (stats.linear_iters > krylov_before)
    st.counters["krylov/step"] =
        static_cast<double>(stats.linear_iters - krylov_before) / static_cast<double>(steps);
  st.counters["f_time"] = f_time;
  st.counters["overhead"] = f_per_step > 0 ? per_step / (f_per_step * f_time) : 0.0;
  st.counters["allocs/step"] = static_cast<double>(allocs) / static_cast<double>(steps);
  st.counters["threads"] = threads;
}

namespace {

// K steps per iteration through the fixed-step driver.
void driver_steps(benchmark::State& st, long side, const std::string& name, double h, int threads,
                  long k) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model("cloth", {{"n", std::to_string(side)}});
  const OdeSystem& sys = *cm.sys;
  auto integ = integrator_registry().create(name, Params{});
  Vec y = cm.warm;
  double t = 0.0;
  // One run of k steps from (t, y), continuing there; false (the benchmark skipped) on failure.
  const auto run = [&] {
    const std::string error = driver_run(sys, *integ, t, y, h, k);
    if (!error.empty()) st.SkipWithError(error.c_str());
    return error.empty();
  };
  try {
    // One untimed run first, as the direct step rows take an untimed first step: it allocates
    // and first touches the integrator's workspaces (rk4's stage matrix is 50 MB on the 512²
    // cloth, whose page faults cost about 100 ms on the project's virtual machine), which a run
    // of 20 steps would otherwise charge to its steps when Google Benchmark times one run.
    if (!run()) return;
    for (auto _ : st)
      if (!run()) break;
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  st.counters["steps/iter"] = static_cast<double>(k);
  st.counters["springs/s"] = benchmark::Counter(
      static_cast<double>(dynamic_cast<const MassSpringNetwork&>(sys).springs().size()) *
          static_cast<double>(k * st.iterations()),
      benchmark::Counter::kIsRate);
  st.counters["threads"] = threads;
}

// The peers' classic RK4, one object per run: construct at y0 (t = 0), step(h), y().
class OdeintRk4 {
 public:
  static constexpr int kSubsteps = 1;
  OdeintRk4(const OdeSystem& sys, const Vec& y0)
      : sys_(sys), n_(sys.dimension()), x_(y0.data(), y0.data() + n_) {}
  bool step(double h) {
    auto f = [this](const State& xs, State& dxdt, double t) {
      const Eigen::Map<const Vec> xm(xs.data(), n_);
      Eigen::Map<Vec> dm(dxdt.data(), n_);
      sys_.rhs(t, xm, dm);
    };
    stepper_.do_step(f, x_, t_, h);
    t_ += h;
    return true;
  }
  const double* y() const { return x_.data(); }
  std::string error() const { return ""; }

 private:
  using State = std::vector<double>;
  const OdeSystem& sys_;
  Index n_;
  State x_;
  double t_ = 0.0;
  boost::numeric::odeint::runge_kutta4<State> stepper_;
};

struct RhsContext {
  const OdeSystem* sys;
  Index n;
};

int gsl_rhs(double t, const double y[], double f[], void* p) {
  const auto* c = static_cast<const RhsContext*>(p);
  const Eigen::Map<const Vec> ym(y, c->n);
  Eigen::Map<Vec> fm(f, c->n);
  c->sys->rhs(t, ym, fm);
  return GSL_SUCCESS;
}

// gsl_odeiv2_step_rk4 estimates its error by step doubling: it takes the step with h and again
// as two steps of h/2, and returns the two half steps (12 f evaluations, or 11 when the driver
// passes f(t_n, y_n) in). So one GSL step of h is compared with two testbed rk4 steps of h/2.
class GslRk4 {
 public:
  static constexpr int kSubsteps = 2;
  GslRk4(const OdeSystem& sys, const Vec& y0) : ctx_{&sys, sys.dimension()}, y_(y0) {
    gs_ = {gsl_rhs, nullptr, static_cast<std::size_t>(ctx_.n), &ctx_};
  }
  ~GslRk4() {
    if (d_) gsl_odeiv2_driver_free(d_);
  }
  GslRk4(const GslRk4&) = delete;
  GslRk4& operator=(const GslRk4&) = delete;
  bool step(double h) {
    // The driver's error control would refuse fixed steps whose step-doubling estimate exceeds
    // its tolerance (GSL_FAILURE): tolerances so large that it never does.
    if (!d_) d_ = gsl_odeiv2_driver_alloc_y_new(&gs_, gsl_odeiv2_step_rk4, h, 1e100, 1e100);
    rc_ = gsl_odeiv2_driver_apply_fixed_step(d_, &t_, h, 1, y_.data());
    return rc_ == GSL_SUCCESS;
  }
  const double* y() const { return y_.data(); }
  std::string error() const {
    return "gsl_odeiv2_driver_apply_fixed_step returned " + std::to_string(rc_);
  }

 private:
  RhsContext ctx_;
  gsl_odeiv2_system gs_{};
  gsl_odeiv2_driver* d_ = nullptr;
  Vec y_;
  double t_ = 0.0;
  int rc_ = GSL_SUCCESS;
};

int arkode_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
  const auto* c = static_cast<const RhsContext*>(user);
  const Eigen::Map<const Vec> ym(N_VGetArrayPointer(y), c->n);
  Eigen::Map<Vec> fm(N_VGetArrayPointer(ydot), c->n);
  c->sys->rhs(t, ym, fm);
  return 0;
}

// ERKStep one step at a time (ARK_ONE_STEP) at a fixed step. SUNDIALS 6.4 treats any table
// whose last node is c_s = 1 as first-same-as-last and reuses the last stage's f as
// f(t_{n+1}, y_{n+1}) (llnl/sundials#311, fixed in a later release), which is wrong for
// classic RK4: from the second step on, it takes 3 evaluations a step and the result differs
// from RK4 by O(h^2) per step (measured on y' = y, h = 0.1: 1.5e-6 after two steps). So the
// table below has c_4 = 0.999 instead of 1; the cloth is autonomous, so stage times do not enter
// the results, and the check against the testbed's rk4 (peer_check) passes.
class ArkodeRk4 {
 public:
  static constexpr int kSubsteps = 1;
  ArkodeRk4(const OdeSystem& sys, const Vec& y0) : ctx_{&sys, sys.dimension()}, y_(y0) {
    SUNContext_Create(nullptr, &sun_);
    nv_ = N_VMake_Serial(static_cast<sunindextype>(ctx_.n), y_.data(), sun_);
    mem_ = ERKStepCreate(arkode_rhs, 0.0, nv_, sun_);
    // Classic RK4: c = (0, 1/2, 1/2, 1), a21 = a32 = 1/2, a43 = 1, b = (1, 2, 2, 1)/6 (c_4: see
    // above).
    double c[4] = {0.0, 0.5, 0.5, 0.999};
    double a[16] = {0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1.0, 0};
    double b[4] = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};
    table_ = ARKodeButcherTable_Create(4, 4, 0, c, a, b, nullptr);
    rc_ = ERKStepSetUserData(mem_, &ctx_);
    if (rc_ == 0) rc_ = ERKStepSetTable(mem_, table_);
    if (rc_ == 0) rc_ = ERKStepSetMaxNumSteps(mem_, 1000000000L);
  }
  ~ArkodeRk4() {
    ERKStepFree(&mem_);
    ARKodeButcherTable_Free(table_);
    N_VDestroy(nv_);
    SUNContext_Free(&sun_);
  }
  ArkodeRk4(const ArkodeRk4&) = delete;
  ArkodeRk4& operator=(const ArkodeRk4&) = delete;
  bool step(double h) {
    if (rc_ < 0) return false;
    if (h != h_) {
      rc_ = ERKStepSetFixedStep(mem_, h);
      h_ = h;
      if (rc_ < 0) return false;
    }
    rc_ = ERKStepEvolve(mem_, t_ + h, nv_, &t_, ARK_ONE_STEP);
    return rc_ >= 0;
  }
  const double* y() const { return y_.data(); }
  std::string error() const { return "ARKODE ERKStep returned " + std::to_string(rc_); }

 private:
  RhsContext ctx_;
  Vec y_;
  SUNContext sun_ = nullptr;
  N_Vector nv_ = nullptr;
  void* mem_ = nullptr;
  ARKodeButcherTable table_ = nullptr;
  double t_ = 0.0, h_ = 0.0;
  int rc_ = 0;
};

// Checks, once per peer, that 3 of its steps reproduce 3 steps of the testbed's rk4 (or 6 of h/2
// for GSL) on a 16² cloth at h = 0.01 (h ω_max = 0.72: another fourth-order method would differ by
// its local error, ~1e-6 here; the same method differs by round-off only: max |diff| <= 1e-10 max
// |y|).
template <class Peer>
std::string peer_check() {
  static std::string verdict = [] {
    Params p;
    p.set("n", "16");
    const auto sys = model_registry().create("cloth", p);
    const Vec y0 = sys->initial_state();
    const double h = 0.01;
    Vec ref = y0;
    auto rk4 = integrator_registry().create("rk4", Params{});
    rk4->reset(*sys, 0.0, ref);
    SolveStats stats;
    const double hs = h / Peer::kSubsteps;
    for (int k = 0; k < 3 * Peer::kSubsteps; ++k) rk4->step(*sys, k * hs, ref, hs, stats);
    Peer peer(*sys, y0);
    for (int k = 0; k < 3; ++k)
      if (!peer.step(h)) return "check run failed: " + peer.error();
    const Eigen::Map<const Vec> got(peer.y(), y0.size());
    const double diff = (got - ref).cwiseAbs().maxCoeff();
    if (!(diff <= 1e-10 * ref.cwiseAbs().maxCoeff())) {
      char msg[128];
      std::snprintf(msg, sizeof msg, "does not reproduce the testbed's rk4 (max |diff| %.3g)",
                    diff);
      return std::string(msg);
    }
    return std::string();
  }();
  return verdict;
}

template <class Peer>
void peer_rk4(benchmark::State& st, long side, double h, int threads) {
  if (const std::string bad = peer_check<Peer>(); !bad.empty()) {
    st.SkipWithError(bad.c_str());
    return;
  }
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model("cloth", {{"n", std::to_string(side)}});
  const OdeSystem& sys = *cm.sys;
  Peer peer(sys, cm.warm);
  if (!peer.step(h)) {  // first step: the peer sizes its work vectors
    st.SkipWithError(peer.error().c_str());
    return;
  }
  sys.reset_counters();
  for (auto _ : st) {
    if (!peer.step(h)) {
      st.SkipWithError(peer.error().c_str());
      break;
    }
  }
  st.counters["f/step"] =
      static_cast<double>(sys.counters().f_evals) / static_cast<double>(st.iterations());
  st.counters["threads"] = threads;
}

// The rk4 ratio measured in interleaved rounds (paired_rounds): each round times k rk4
// steps, then 4k symplectic_euler steps, each side after one untimed step of its own, each
// method on its own copy of the warm 512² cloth. The round's ratio is (rk4 time / k) /
// (4 × symplectic_euler time / 4k), the rows' ratio step/rk4 / (4 × step/symplectic_euler) taken
// side by side. With `driver`, each block is one run_fixed_step_from run of k steps (rk4) or 4k
// steps (symplectic_euler) after an untimed one-step run.
void paired_rk4_se(benchmark::State& st, const std::string& name, bool driver, int threads,
                   double h, int k) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model("cloth", {{"n", "512"}});
  const OdeSystem& sys = *cm.sys;
  struct Side {
    std::unique_ptr<Integrator> integ;
    Vec y;
    double t = 0.0;
  };
  Side rk{integrator_registry().create("rk4", Params{}), cm.warm};
  Side se{integrator_registry().create("symplectic_euler", Params{}), cm.warm};
  bool failed = false;
  SolveStats stats;
  // Untimed warm-up, then `steps` timed steps; seconds per 4 / per rk4 step come from the caller.
  const auto block = [&](Side& s, long steps) {
    if (failed) return 0.0;
    const auto advance = [&](long count) {
      if (driver) return driver_run(sys, *s.integ, s.t, s.y, h, count).empty();
      for (long i = 0; i < count; ++i, s.t += h)
        if (s.integ->step(sys, s.t, s.y, h, stats) != Status::ok) return false;
      return true;
    };
    if (!advance(1)) return failed = true, 0.0;
    const double t0 = now_seconds();
    if (!advance(steps)) return failed = true, 0.0;
    return now_seconds() - t0;
  };
  try {
    rk.integ->reset(sys, rk.t, rk.y);
    se.integ->reset(sys, se.t, se.y);
    paired_rounds(
        st, name, [&] { return block(rk, k); }, [&] { return block(se, 4L * k); });
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  if (failed) st.SkipWithError("a step failed");
  st.counters["threads"] = threads;
}

}  // namespace

void register_step_benchmarks(const Config& cfg) {
  using benchmark::kMicrosecond;
  using benchmark::kMillisecond;
  // Every fixed-step hand-written integrator on the same cloth (32² in --quick, where today's
  // implicit steps take seconds at 64²; 64² in the full run), h = 1e-3 (hω_max = 0.07: every
  // explicit method is stable).
  const long side = cfg.quick ? 32 : 64;
  const double h = 1e-3;
  for (const auto& e : integrator_registry().entries()) {
    if (e.info.family == Family::reference) continue;
    if (e.info.requires_.grid_fluid) continue;  // stable_fluids: grid fluids only, not cloth
    const std::string name = e.info.name;
    add(
        "step/" + name + "/cloth:" + std::to_string(side) + omp_suffix(2),
        [side, name, h](benchmark::State& st) { integrator_step(st, side, name, Params{}, h, 2); },
        e.info.family == Family::implicit ? kMillisecond : kMicrosecond);
  }
  // cloth 512²: symplectic Euler and RK4 directly and through the driver, then the peers' RK4.
  // The driver rows run at 1 thread too, also with --quick: on a loaded machine the 1-thread
  // ratios are the less distorted ones.
  for (const int t : {1, 2}) {
    const bool all = !cfg.quick || t == 2;
    for (const std::string name : {"symplectic_euler", "rk4"}) {
      if (all)
        add("step/" + name + "/cloth:512" + omp_suffix(t),
            [name, t, h](benchmark::State& st) { integrator_step(st, 512, name, Params{}, h, t); });
      add("solve/" + name + "/cloth:512" + omp_suffix(t),
          [name, t, h](benchmark::State& st) { driver_steps(st, 512, name, h, t, 20); });
    }
    // The rk4 ratio side by side: 10 rounds a repetition (about 1 s direct, 2 s driver).
    for (const bool driver : {false, true}) {
      if (t != 2) break;
      const std::string pname = std::string("paired/rk4_vs_4_symplectic_euler/") +
                                (driver ? "driver" : "step") + "/cloth:512" + omp_suffix(t);
      add(pname, [pname, driver, t, h](benchmark::State& st) {
        paired_rk4_se(st, pname, driver, t, h, driver ? 5 : 2);
      })->Iterations(10);
    }
    if (!all) continue;
    // 4 steps each (one step of GSL's is 12 evaluations: Google Benchmark would stop at one).
    add("peer/odeint_rk4/cloth:512" + omp_suffix(t), [t, h](benchmark::State& st) {
      peer_rk4<OdeintRk4>(st, 512, h, t);
    })->Iterations(4);
    add("peer/gsl_rk4/cloth:512" + omp_suffix(t), [t, h](benchmark::State& st) {
      peer_rk4<GslRk4>(st, 512, h, t);
    })->Iterations(4);
    add("peer/arkode_rk4/cloth:512" + omp_suffix(t), [t, h](benchmark::State& st) {
      peer_rk4<ArkodeRk4>(st, 512, h, t);
    })->Iterations(4);
  }
}

}  // namespace stiffbench::bench
