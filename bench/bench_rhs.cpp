// Right-hand-side cost per model and size: the testbed's
// MechanicalSystem::acceleration (the force computation of rhs(), without rhs()'s copy x' = v)
// on spring_chain, cloth and the SPH scenes; the plain cloth gather (plain_cloth.hpp) on the
// same cloth; and the SPH neighbour search on its own (models/sph/neighbour_grid.hpp: grid
// build, and build plus one visit of every neighbour pair within the support radius in cell
// order — the search a density or force pass does). Each at 1 and 2 OpenMP threads where the
// thread scaling is asked for. Paired benchmarks (paired_rounds, bench_common.hpp) time
// the cloth and SPH ratios side by side: a symplectic_euler driver step against the plain cloth
// gather, the plain 3D SPH gather against the testbed's right-hand side, and the SPH
// right-hand sides at 1 thread against 2 (paired/sph_threads/..., their speed-ups).
#include <omp.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "bench/bench_common.hpp"
#include "bench/plain_cloth.hpp"
#include "bench/plain_sph.hpp"
#include "experiments/framework/catalog.hpp"
#include "models/sph/neighbour_grid.hpp"
#include "models/sph/sph_fluid.hpp"

namespace stiffbench::bench {

namespace {

using Kv = std::vector<std::pair<std::string, std::string>>;

std::string omp_suffix(int threads) { return "/omp:" + std::to_string(threads); }

void set_rate(benchmark::State& st, const std::string& name, double per_iteration) {
  st.counters[name] = benchmark::Counter(per_iteration * static_cast<double>(st.iterations()),
                                         benchmark::Counter::kIsRate);
}

// Time per item (seconds, shown with an SI prefix: 300n = 300 ns).
void set_time_per(benchmark::State& st, const std::string& name, double items) {
  st.counters[name] = benchmark::Counter(items * static_cast<double>(st.iterations()),
                                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The timing loop of a right-hand-side benchmark: `evaluate` once per iteration, after a probe
// of the CPUs' speeds (cpu_speed.hpp; on the project's VM their ratio drifts by the minute).
// A 1-thread loop runs pinned to the CPU found fastest, so a 2-thread speed-up is taken against
// the best 1-thread time and a slow CPU never inflates it. Adds the counters the summary reads,
// cpu_attainable and cpu_pinned. Call it after any set-up that may start OpenMP threads (they
// would inherit the one-CPU mask).
template <class Evaluate>
void time_on_fastest_cpu(benchmark::State& st, int threads, Evaluate&& evaluate) {
  const CpuSpeeds cpu = measure_cpu_speeds(0.03);
  bool pinned = false;
  {
    const PinCurrentThread pin(threads == 1 ? cpu.fastest() : -1);
    pinned = pin.pinned();
    for (auto _ : st) {
      evaluate();
      benchmark::ClobberMemory();
    }
  }
  if (!cpu.valid()) return;
  st.counters["cpu_attainable"] = cpu.attainable();
  st.counters["cpu_pinned"] = pinned ? cpu.fastest() : -1;
}

void network_rhs(benchmark::State& st, const std::string& model, const Kv& params, int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model(model, params);
  const auto* net = dynamic_cast<const MassSpringNetwork*>(cm.sys.get());
  const Index n = net->dofs();
  Vec a(n);
  const auto x = cm.warm.head(n), v = cm.warm.tail(n);
  net->acceleration(0.0, x, v, a);  // a first call outside the pinned loop
  time_on_fastest_cpu(st, threads, [&] {
    net->acceleration(0.0, x, v, a);
    benchmark::DoNotOptimize(a.data());
  });
  set_rate(st, "springs/s", static_cast<double>(net->springs().size()));
  st.counters["points"] = static_cast<double>(net->num_points());
  st.counters["springs"] = static_cast<double>(net->springs().size());
  st.counters["threads"] = threads;
}

// The plain gather on the cached cloth of this size, built once per size (it copies what it
// needs from the network) and checked then against the testbed's acceleration at the same state
// (the two sum the same spring forces in different orders: agreement to round-off); nullptr
// when the check fails.
const PlainClothRhs* checked_plain_cloth(const CachedModel& cm, long side) {
  static std::unique_ptr<PlainClothRhs> plain;
  static long owner = 0;
  if (owner != side) {
    const auto* net = dynamic_cast<const MassSpringNetwork*>(cm.sys.get());
    const Index n = net->dofs();
    Vec a(n), ref(n);
    plain = std::make_unique<PlainClothRhs>(*net);
    owner = side;
    plain->acceleration(cm.warm.data(), a.data());
    net->acceleration(0.0, cm.warm.head(n), cm.warm.tail(n), ref);
    const double diff = (a - ref).cwiseAbs().maxCoeff();
    if (!(diff <= 1e-12 * std::max(1.0, ref.cwiseAbs().maxCoeff()))) owner = 0;
  }
  return owner == side ? plain.get() : nullptr;
}

void plain_cloth_rhs(benchmark::State& st, long side, int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model("cloth", {{"n", std::to_string(side)}});
  const PlainClothRhs* plain = checked_plain_cloth(cm, side);
  if (!plain) {
    st.SkipWithError("plain cloth RHS differs from the testbed's acceleration");
    return;
  }
  Vec a(cm.sys->as_mechanical()->dofs());
  plain->acceleration(cm.warm.data(), a.data());  // a first call outside the pinned loop
  time_on_fastest_cpu(st, threads, [&] {
    plain->acceleration(cm.warm.data(), a.data());
    benchmark::DoNotOptimize(a.data());
  });
  set_rate(st, "springs/s", static_cast<double>(plain->springs()));
  st.counters["points"] = static_cast<double>(plain->points());
  st.counters["threads"] = threads;
}

// The first cloth ratio in interleaved rounds (paired_rounds): a fixed-step driver run of
// 20 symplectic_euler steps (after an untimed one-step run), then 4 calls of the plain gather
// (after an untimed one), on the 512² cloth; the round's ratio is (driver time / 20) / (plain
// time / 4), the rows' solve/symplectic_euler / rhs/plain_cloth taken side by side.
void paired_se_plain(benchmark::State& st, const std::string& name, int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model("cloth", {{"n", "512"}});
  const PlainClothRhs* plain = checked_plain_cloth(cm, 512);
  if (!plain) {
    st.SkipWithError("plain cloth RHS differs from the testbed's acceleration");
    return;
  }
  const OdeSystem& sys = *cm.sys;
  auto se = integrator_registry().create("symplectic_euler", Params{});
  Vec y = cm.warm, a(sys.as_mechanical()->dofs());
  double t = 0.0;
  bool failed = false;
  const double h = 1e-3;
  const auto run = [&](long steps) {
    failed = !driver_run(sys, *se, t, y, h, steps).empty() || failed;
  };
  const auto driver_side = [&] {
    run(1);
    const double t0 = now_seconds();
    run(20);
    return (now_seconds() - t0) / 20.0;
  };
  const auto plain_side = [&] {
    return timed_calls(
               [&] {
                 plain->acceleration(cm.warm.data(), a.data());
                 benchmark::DoNotOptimize(a.data());
               },
               4) /
           4.0;
  };
  try {
    paired_rounds(st, name, driver_side, plain_side);
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  if (failed) st.SkipWithError("a symplectic_euler run failed");
  st.counters["threads"] = threads;
}

// Building a cloth model through the registry (what `solve --model cloth` does) plus its first
// acceleration(), so that nothing deferred to first use escapes the measurement. Counters:
// construct (the registry's create() alone) and first_rhs (the first evaluation), seconds.
void cloth_build(benchmark::State& st, long side) {
  OmpThreads omp(1);
  Params p;
  p.set("n", std::to_string(side));
  double construct = 0.0, first = 0.0;
  for (auto _ : st) {
    const double t0 = now_seconds();
    auto sys = model_registry().create("cloth", p);
    const double t1 = now_seconds();
    const auto* mech = sys->as_mechanical();
    const Vec y = sys->initial_state();
    Vec a(mech->dofs());
    mech->acceleration(0.0, y.head(mech->dofs()), y.tail(mech->dofs()), a);
    benchmark::DoNotOptimize(a.data());
    construct += t1 - t0;
    first += now_seconds() - t1;
  }
  const double its = static_cast<double>(st.iterations());
  st.counters["construct_s"] = construct / its;
  st.counters["first_rhs_s"] = first / its;
  st.counters["threads"] = 1;
}

template <int D>
long count_pairs(const double* x, Index np, double radius) {
  sph::NeighbourGrid<D> grid;
  grid.build(x, np, radius);
  long pairs = 0;
  for (Index s = 0; s < np; ++s)
    grid.for_each_neighbour_slot(grid.positions() + D * s, radius,
                                 [&](std::size_t, double, const auto&) { ++pairs; });
  return pairs;
}

void sph_rhs(benchmark::State& st, const std::string& model, long n_param, int warm, int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model(model, {{"n", std::to_string(n_param)}}, warm);
  const auto* fluid = dynamic_cast<const SphFluid*>(cm.sys.get());
  const Index n = fluid->dofs();
  Vec a(n);
  const auto x = cm.warm.head(n), v = cm.warm.tail(n);
  // Verlet-list builds so far: on a fresh model (the first benchmark of each scene), those of
  // the warm-up's symplectic Euler steps (one acceleration each) plus this state's, if any.
  fluid->acceleration(0.0, x, v, a);
  st.counters["list_builds_before"] = static_cast<double>(fluid->neighbour_list_builds());
  st.counters["warm_steps"] = warm;
  time_on_fastest_cpu(st, threads, [&] {
    fluid->acceleration(0.0, x, v, a);
    benchmark::DoNotOptimize(a.data());
  });
  const double particles = static_cast<double>(fluid->fluid_particles());
  const double support = fluid->options().support;
  const long pairs = fluid->dim() == 2
                         ? count_pairs<2>(cm.warm.data(), fluid->fluid_particles(), support)
                         : count_pairs<3>(cm.warm.data(), fluid->fluid_particles(), support);
  st.counters["particles"] = particles;
  st.counters["boundary"] = static_cast<double>(fluid->boundary_particles());
  set_time_per(st, "s/particle", particles);
  set_rate(st, "pairs/s", static_cast<double>(pairs));
  st.counters["threads"] = threads;
}

// max |plain - testbed| / max |testbed| of the two accelerations at the cached warm state (a is
// left holding the plain gather's).
double plain_sph_difference(const CachedModel& cm, const SphFluid& fluid, const PlainSph3d& plain,
                            Vec& a) {
  const Index n = fluid.dofs();
  Vec ref(n);
  fluid.acceleration(0.0, cm.warm.head(n), cm.warm.tail(n), ref);
  plain.acceleration(cm.warm.data(), cm.warm.data() + n, a.data());
  return (a - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff();
}

// The plain 3D SPH gather (plain_sph.hpp) on the same model and warm state, checked once against
// the testbed's acceleration there (the two sum the same terms in different orders: agreement
// to round-off, 1e-8 of the largest acceleration; a failed check fails the benchmark).
void plain_sph_rhs(benchmark::State& st, const std::string& model, long n_param, int warm,
                   int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model(model, {{"n", std::to_string(n_param)}}, warm);
  const auto* fluid = dynamic_cast<const SphFluid*>(cm.sys.get());
  const Index n = fluid->dofs();
  const PlainSph3d plain(*fluid);
  Vec a(n);
  const double diff = plain_sph_difference(cm, *fluid, plain, a);
  if (!(diff <= 1e-8)) {
    st.SkipWithError("plain SPH RHS differs from the testbed's acceleration");
    return;
  }
  for (auto _ : st) {
    plain.acceleration(cm.warm.data(), cm.warm.data() + n, a.data());
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  const long pairs =
      count_pairs<3>(cm.warm.data(), fluid->fluid_particles(), fluid->options().support);
  set_rate(st, "pairs/s", static_cast<double>(pairs));
  set_time_per(st, "s/particle", static_cast<double>(fluid->fluid_particles()));
  st.counters["max_diff_vs_testbed"] = diff;
  st.counters["threads"] = threads;
}

// The SPH ratio in interleaved rounds (paired_rounds): 2 calls of the plain 3D gather,
// then 2 of the testbed's right-hand side (each after an untimed call), on the same warm state;
// the round's ratio is plain time / testbed time, which is the testbed's pairs/s over the
// peer's (the same pairs). The peer is checked against the testbed as in plain_sph_rhs.
void paired_sph_peer(benchmark::State& st, const std::string& name, const std::string& model,
                     long n_param, int warm, int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model(model, {{"n", std::to_string(n_param)}}, warm);
  const auto* fluid = dynamic_cast<const SphFluid*>(cm.sys.get());
  const Index n = fluid->dofs();
  const PlainSph3d plain(*fluid);
  Vec a(n);
  if (!(plain_sph_difference(cm, *fluid, plain, a) <= 1e-8)) {
    st.SkipWithError("plain SPH RHS differs from the testbed's acceleration");
    return;
  }
  const auto x = cm.warm.head(n), v = cm.warm.tail(n);
  paired_rounds(
      st, name,
      [&] {
        return timed_calls(
            [&] {
              plain.acceleration(cm.warm.data(), cm.warm.data() + n, a.data());
              benchmark::DoNotOptimize(a.data());
            },
            2);
      },
      [&] {
        return timed_calls(
            [&] {
              fluid->acceleration(0.0, x, v, a);
              benchmark::DoNotOptimize(a.data());
            },
            2);
      });
  st.counters["threads"] = threads;
}

// The SPH 2-thread speed-ups in interleaved rounds (paired_rounds): 2 calls of the
// testbed's right-hand side at 1 thread, pinned to the CPU the benchmark's probe found fastest
// (as the rhs/ rows' 1-thread loop), then 2 at 2 threads, each after an untimed call; the
// round's ratio t_1 / t_2 is the speed-up. The rhs/ rows at 1 and 2 threads are timed tens of
// seconds apart, and the machine's speed drifts on that scale.
void paired_sph_threads(benchmark::State& st, const std::string& name, const std::string& model,
                        long n_param, int warm) {
  const CachedModel& cm = cached_model(model, {{"n", std::to_string(n_param)}}, warm);
  const auto* fluid = dynamic_cast<const SphFluid*>(cm.sys.get());
  const Index n = fluid->dofs();
  Vec a(n);
  const auto x = cm.warm.head(n), v = cm.warm.tail(n);
  const auto call = [&] {
    fluid->acceleration(0.0, x, v, a);
    benchmark::DoNotOptimize(a.data());
  };
  {
    const OmpThreads two(2);
    call();  // the OpenMP threads start here, before the pinned side (they keep their mask)
  }
  const CpuSpeeds cpu = measure_cpu_speeds(0.03);
  paired_rounds(
      st, name,
      [&] {
        const OmpThreads one(1);
        const PinCurrentThread pin(cpu.fastest());
        return timed_calls(call, 2);
      },
      [&] {
        const OmpThreads two(2);
        return timed_calls(call, 2);
      });
  if (cpu.valid()) st.counters["cpu_attainable"] = cpu.attainable();
}

// The testbed's SPH right-hand side when every call rebuilds the Verlet list: calls alternate
// between the warm state and a copy with one particle moved by 0.6 skins (more than the half
// skin that triggers a build). rhs/ measures the calls that reuse the list; this, the calls
// that build it (the counter list_builds checks that each did).
void sph_rhs_rebuilding(benchmark::State& st, const std::string& model, long n_param, int warm,
                        int threads) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model(model, {{"n", std::to_string(n_param)}}, warm);
  const auto* fluid = dynamic_cast<const SphFluid*>(cm.sys.get());
  const Index n = fluid->dofs();
  Vec a(n);
  Vec moved = cm.warm;
  moved[0] += 0.6 * fluid->neighbour_skin();
  // Start from a list built at the warm state, so that the first timed call (at `moved`)
  // rebuilds it, and so does every call after it.
  fluid->acceleration(0.0, cm.warm.head(n), cm.warm.tail(n), a);
  const long before = fluid->neighbour_list_builds();
  bool flip = true;
  for (auto _ : st) {
    const Vec& y = flip ? moved : cm.warm;
    flip = !flip;
    fluid->acceleration(0.0, y.head(n), y.tail(n), a);
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  st.counters["list_builds_per_call"] =
      static_cast<double>(fluid->neighbour_list_builds() - before) /
      static_cast<double>(st.iterations());
  set_time_per(st, "s/particle", static_cast<double>(fluid->fluid_particles()));
  st.counters["threads"] = threads;
}

// Neighbour search alone on the fluid particles of an SPH scene: build the grid (build_only) or
// build it and visit every neighbour within the support radius, each particle in cell order, in
// parallel over particles as the testbed's passes do.
template <int D>
void sph_neighbours(benchmark::State& st, const std::string& model, long n_param, int warm,
                    int threads, bool build_only) {
  OmpThreads omp(threads);
  const CachedModel& cm = cached_model(model, {{"n", std::to_string(n_param)}}, warm);
  const auto* fluid = dynamic_cast<const SphFluid*>(cm.sys.get());
  const Index np = fluid->fluid_particles();
  const double radius = fluid->options().support;
  sph::NeighbourGrid<D> grid;
  grid.build(cm.warm.data(), np, radius);  // a first build outside the pinned loop
  time_on_fastest_cpu(st, threads, [&] {
    grid.build(cm.warm.data(), np, radius);
    if (build_only) return;
    // Sum r² over the pairs so that the visits cannot be optimised away.
    double total = 0.0;
    const double* pos = grid.positions();
#pragma omp parallel for schedule(static) reduction(+ : total)
    for (Index s = 0; s < np; ++s)
      grid.for_each_neighbour_slot(pos + D * s, radius,
                                   [&](std::size_t, double r2, const auto&) { total += r2; });
    benchmark::DoNotOptimize(total);
  });
  const long pairs = count_pairs<D>(cm.warm.data(), np, radius);
  st.counters["particles"] = static_cast<double>(np);
  if (!build_only) set_rate(st, "pairs/s", static_cast<double>(pairs));
  set_time_per(st, "s/particle", static_cast<double>(np));
  st.counters["threads"] = threads;
}

}  // namespace

void register_rhs_benchmarks(const Config& cfg) {
  const bool q = cfg.quick;
  using benchmark::kMicrosecond;
  using benchmark::kMillisecond;
  // spring_chain, 1e3 .. 1e6 free masses.
  const std::vector<std::pair<long, std::vector<int>>> chains =
      q ? std::vector<std::pair<long, std::vector<int>>>{{1000, {2}}, {1000000, {1, 2}}}
        : std::vector<std::pair<long, std::vector<int>>>{
              {1000, {1, 2}}, {10000, {1, 2}}, {100000, {1, 2}}, {1000000, {1, 2}}};
  for (const auto& [n, threads] : chains)
    for (const int t : threads)
      add(
          "rhs/spring_chain/n:" + std::to_string(n) + omp_suffix(t),
          [n = n, t](benchmark::State& st) {
            network_rhs(st, "spring_chain", {{"n", std::to_string(n)}}, t);
          },
          n < 100000 ? kMicrosecond : kMillisecond);
  // cloth 32² .. 512², then the plain gather on the same cloth right after (cached model).
  const std::vector<std::pair<long, std::vector<int>>> cloths =
      q ? std::vector<std::pair<long, std::vector<int>>>{{32, {2}}, {128, {2}}, {512, {1, 2}}}
        : std::vector<std::pair<long, std::vector<int>>>{
              {32, {1, 2}}, {64, {1, 2}}, {128, {1, 2}}, {256, {1, 2}}, {512, {1, 2}}};
  for (const auto& [n, threads] : cloths) {
    for (const int t : threads)
      add(
          "rhs/cloth/n:" + std::to_string(n) + omp_suffix(t),
          [n = n, t](benchmark::State& st) {
            network_rhs(st, "cloth", {{"n", std::to_string(n)}}, t);
          },
          n < 256 ? kMicrosecond : kMillisecond);
    if (n == 512 || (!q && n == 128))
      for (const int t : threads)
        add(
            "rhs/plain_cloth/n:" + std::to_string(n) + omp_suffix(t),
            [n = n, t](benchmark::State& st) { plain_cloth_rhs(st, n, t); },
            n < 256 ? kMicrosecond : kMillisecond);
  }
  // The cloth ratio side by side: 10 rounds a repetition (about 1.3 s).
  add("paired/symplectic_euler_vs_plain_gather/cloth:512/omp:2", [](benchmark::State& st) {
    paired_se_plain(st, "paired/symplectic_euler_vs_plain_gather/cloth:512/omp:2", 2);
  })->Iterations(10);
  // Construction of the largest cloth (target: a 512² cloth in well under 0.3 s).
  add(
      "build/cloth/n:512/omp:1", [](benchmark::State& st) { cloth_build(st, 512); }, kMillisecond);
  // SPH. sph_dam_break_2d: n across the column width a, 2n² fluid particles (n = 45: 4,050, the
  // size of PySPH's dam_break_2d example, 2,278 fluid + 1,660 boundary = 3,938 particles at its
  // default dx = 0.03; n = 224: 100,352). sph_dam_break_3d: a column n × 2n × n/2, n³ particles
  // (n = 46: 97,336). sph_drop_2d: a disc n across (n = 50: 1,976).
  struct SphCase {
    const char* model;  // (not std::string: g++ 12 warns falsely on the initializer lists)
    long n;
    int warm;
    std::vector<int> threads;
  };
  const std::vector<SphCase> sph =
      q ? std::vector<SphCase>{{"sph_dam_break_2d", 45, 50, {1, 2}},
                               {"sph_dam_break_2d", 224, 10, {1, 2}},
                               {"sph_dam_break_3d", 46, 5, {1, 2}}}
        : std::vector<SphCase>{
              {"sph_drop_2d", 50, 50, {1, 2}},       {"sph_dam_break_2d", 32, 50, {1, 2}},
              {"sph_dam_break_2d", 45, 50, {1, 2}},  {"sph_dam_break_2d", 100, 20, {1, 2}},
              {"sph_dam_break_2d", 224, 10, {1, 2}}, {"sph_dam_break_3d", 12, 20, {1, 2}},
              {"sph_dam_break_3d", 24, 10, {1, 2}},  {"sph_dam_break_3d", 46, 5, {1, 2}}};
  for (const auto& c : sph) {
    const std::string model = c.model;
    const std::string base = "/" + model + "/n:" + std::to_string(c.n);
    for (const int t : c.threads)
      add(
          "rhs" + base + omp_suffix(t),
          [c, t](benchmark::State& st) { sph_rhs(st, c.model, c.n, c.warm, t); },
          c.n >= 100 || model == "sph_dam_break_3d" ? kMillisecond : kMicrosecond);
    if (model == "sph_drop_2d" || (q && model == "sph_dam_break_2d" && c.n != 224)) continue;
    for (const int t : c.threads)
      for (const bool build_only : {false, true}) {
        const std::string name =
            std::string(build_only ? "neighbour_build" : "neighbour_search") + base + omp_suffix(t);
        if (model == "sph_dam_break_3d")
          add(name, [c, t, build_only](benchmark::State& st) {
            sph_neighbours<3>(st, c.model, c.n, c.warm, t, build_only);
          });
        else
          add(name, [c, t, build_only](benchmark::State& st) {
            sph_neighbours<2>(st, c.model, c.n, c.warm, t, build_only);
          });
      }
  }
  // The 3D dam break's plain peer and its RHS with a Verlet-list build at every call;
  // the peer and the testbed side by side, 6 rounds a repetition (about 2.5 s).
  add("paired/plain_sph_3d_vs_testbed/n:46/omp:2", [](benchmark::State& st) {
    paired_sph_peer(st, "paired/plain_sph_3d_vs_testbed/n:46/omp:2", "sph_dam_break_3d", 46, 5, 2);
  })->Iterations(6);
  // The 2D and 3D 2-thread speed-ups, 1 and 2 threads side by side (about 3 s each).
  const std::string threads_2d = "paired/sph_threads/sph_dam_break_2d/n:224/omp:1_vs_2";
  const std::string threads_3d = "paired/sph_threads/sph_dam_break_3d/n:46/omp:1_vs_2";
  add(threads_2d, [threads_2d](benchmark::State& st) {
    paired_sph_threads(st, threads_2d, "sph_dam_break_2d", 224, 10);
  })->Iterations(10);
  add(threads_3d, [threads_3d](benchmark::State& st) {
    paired_sph_threads(st, threads_3d, "sph_dam_break_3d", 46, 5);
  })->Iterations(6);
  for (const int t : {1, 2}) {
    add(
        "peer/plain_sph_3d/n:46" + omp_suffix(t),
        [t](benchmark::State& st) { plain_sph_rhs(st, "sph_dam_break_3d", 46, 5, t); },
        kMillisecond);
    add(
        "rhs_list_build/sph_dam_break_3d/n:46" + omp_suffix(t),
        [t](benchmark::State& st) { sph_rhs_rebuilding(st, "sph_dam_break_3d", 46, 5, t); },
        kMillisecond);
  }
}

}  // namespace stiffbench::bench
