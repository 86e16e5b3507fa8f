// The summary printed after the benchmark table: the target table as ratios of two
// measurements from this run, then the per-integrator overheads and allocation counts, the
// thread scaling of every right-hand side and the side-by-side RK4 figures. A figure whose
// benchmarks were filtered out or failed prints "n/a" with the reason.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bench/bench_common.hpp"
#include "experiments/support/timing.hpp"
#include "models/mass_spring/network.hpp"

namespace stiffbench::bench {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Lookup {
  const Results& r;

  const Result* get(const std::string& name) const {
    const auto it = r.find(name);
    return it == r.end() || it->second.error ? nullptr : &it->second;
  }
  double sec(const std::string& name) const {
    const Result* x = get(name);
    return x ? x->seconds : kNaN;
  }
  double counter(const std::string& name, const std::string& key) const {
    const Result* x = get(name);
    if (!x) return kNaN;
    const auto it = x->counters.find(key);
    return it == x->counters.end() ? kNaN : it->second;
  }
  // Why a figure is missing: the benchmark's error, or "not run".
  std::string why(const std::string& name) const {
    const auto it = r.find(name);
    if (it == r.end()) return name + " not run";
    return name + ": " + it->second.message;
  }
};

std::string fmt(const char* f, double v) {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// A paired figure (paired_rounds in bench_common.hpp): the median of every round's ratio and
// the bootstrap 95% interval of that median (timing_spread, as for the times).
struct PairedFigure {
  double median = kNaN, ci_low = kNaN, ci_high = kNaN;
  std::size_t rounds = 0;
  std::string name;
  std::string describe() const {
    if (!std::isfinite(median)) return "n/a (" + name + " not run)";
    return fmt("%.3f", median) + " [" + fmt("%.3f", ci_low) + ", " + fmt("%.3f", ci_high) +
           "] over " + std::to_string(rounds) + " rounds";
  }
};

PairedFigure paired(const std::string& name) {
  PairedFigure f;
  f.name = name;
  const auto it = paired_ratios().find(name);
  if (it == paired_ratios().end() || it->second.empty()) return f;
  const TimingSpread t = timing_spread(it->second, 1, 2);
  f.median = t.median;
  f.ci_low = t.ci_low;
  f.ci_high = t.ci_high;
  f.rounds = it->second.size();
  return f;
}

// One row of the target table: figure, measured value, target, met / NOT met / n/a.
void row(const std::string& figure, double value, const char* format, const std::string& target,
         bool met, const std::string& note = "") {
  const std::string status = !std::isfinite(value) ? "n/a" : met ? "met" : "NOT met";
  std::printf("| %s | %s | %s | %s |%s\n", figure.c_str(), fmt(format, value).c_str(),
              target.c_str(), status.c_str(), note.empty() ? "" : (" " + note).c_str());
}

// "; these CPUs reach at most 1.69 (before) and 1.98 (after)": the speed-up that work divided
// perfectly between the CPUs would reach (cpu_speed.hpp), or "" when the probe did not run.
std::string attainable_note(const Config& cfg) {
  if (!cfg.cpu_before.valid() || !cfg.cpu_after.valid()) return "";
  return "; these CPUs reach at most " + fmt("%.2f", cfg.cpu_before.attainable()) +
         " (before the benchmarks) and " + fmt("%.2f", cfg.cpu_after.attainable()) + " (after)";
}

}  // namespace

void print_summary(const Results& results, const Config& cfg, double wall_seconds) {
  const Lookup L{results};
  std::printf(
      "\n== stiffbench_bench summary (%s run; %ld cores online; load average %s; "
      "benchmarks took %.1f s)\n",
      cfg.quick ? "--quick" : "full", sysconf(_SC_NPROCESSORS_ONLN), load_average().c_str(),
      wall_seconds);
  std::printf(
      "Each ratio divides two measurements of this run. Times are real (wall) time per "
      "iteration, the median over the repetitions (spread: see the end). A row marked 'paired "
      "rounds' takes the median of per-round ratios of its two sides timed in alternation "
      "(paired/... benchmarks), with a bootstrap 95%% interval of that median.\n");
  if (cfg.cpu_before.valid() && cfg.cpu_after.valid())
    std::printf(
        "CPU speeds (a fixed multiply-add loop, one pinned thread per CPU, relative to the fastest "
        "CPU alone): before the benchmarks %s; after %s. Work divided perfectly among these "
        "CPUs runs at most %s (before) and %s (after) times as fast as on the fastest CPU alone: "
        "a 2-thread speed-up cannot exceed that, and a 1-thread time taken on a slower CPU "
        "inflates it. The loop touches no memory: contention for memory from other guests "
        "does not show in it.\n",
        cfg.cpu_before.describe().c_str(), cfg.cpu_after.describe().c_str(),
        fmt("%.2f", cfg.cpu_before.attainable()).c_str(),
        fmt("%.2f", cfg.cpu_after.attainable()).c_str());
  std::printf("Mass-spring kernel build in use: %s (MassSpringNetwork::kernel_isa).\n",
              to_string(MassSpringNetwork::kernel_isa()));
  std::printf("\n");

  // ---- Target table (2 threads).
  const std::string plain2 = "implicit/plain_bw/cloth:64/omp:2";
  const std::string plain1 = "implicit/plain_bw/cloth:64/omp:1";
  const double plain_step = L.sec(plain2) / 50.0;  // one iteration = 50 steps
  std::printf(
      "Targets (cloth 64² h = 0.01 rows: plain Baraff-Witkin step = %s ms on 2 threads, "
      "%s ms on 1; assembly %s ms + CG %s ms, %s CG iterations per step):\n\n",
      fmt("%.3g", plain_step * 1e3).c_str(), fmt("%.3g", L.sec(plain1) / 50.0 * 1e3).c_str(),
      fmt("%.3g", L.counter(plain2, "assembly_s/step") * 1e3).c_str(),
      fmt("%.3g", L.counter(plain2, "cg_s/step") * 1e3).c_str(),
      fmt("%.3g", L.counter(plain2, "cg_iters/step")).c_str());
  std::printf("| figure | measured | target | status | note\n|---|---|---|---|\n");

  // Each figure at 2 threads (the target's setting) and, in the note, the same ratio at 1
  // thread: on a loaded machine the second thread rarely has a core, and the 1-thread ratio is
  // the less distorted one.
  const auto omp = [](const std::string& name, int t) {
    return name + "/omp:" + std::to_string(t);
  };
  const auto one_thread = [](double v, const char* f) { return "; 1 thread: " + fmt(f, v); };

  const std::string bw = "implicit/baraff_witkin/cloth:64";
  const auto bw_ratio = [&](int t) {
    return L.sec(omp(bw, t)) / L.sec(omp("implicit/plain_bw/cloth:64", t));
  };
  row("baraff_witkin step / plain BW step", bw_ratio(2), "%.3g", "<= 2", bw_ratio(2) <= 2.0,
      std::isfinite(bw_ratio(2)) ? "(" + fmt("%.4g", L.sec(omp(bw, 2)) / 50.0 * 1e3) + " ms/step" +
                                       one_thread(bw_ratio(1), "%.3g") + ")"
                                 : L.why(omp(bw, 2)));
  const std::string be = "implicit/backward_euler/cloth:64";
  const auto be_ratio = [&](int t) {
    return L.sec(omp(be, t)) / (L.sec(omp("implicit/plain_bw/cloth:64", t)) / 50.0);
  };
  row("backward_euler step / plain BW step", be_ratio(2), "%.3g", "<= 8", be_ratio(2) <= 8.0,
      std::isfinite(be_ratio(2)) ? "(" + fmt("%.4g", L.sec(omp(be, 2)) * 1e3) + " ms/step" +
                                       one_thread(be_ratio(1), "%.3g") + ")"
                                 : L.why(omp(be, 2)));
  const std::string cv = "implicit/cvode_bdf/cloth:64/omp:2";
  const double cv_ratio = L.sec(cv) / (100.0 * plain_step);
  row("cvode_bdf (defaults) to t = 0.5 / 100 plain BW steps", cv_ratio, "%.3g", "<= 40",
      cv_ratio <= 40.0,
      std::isfinite(cv_ratio)
          ? "(" + fmt("%.4g", L.sec(cv)) + " s, " + fmt("%.0f", L.counter(cv, "steps")) +
                " steps, " + fmt("%.3g", L.counter(cv, "s/step") * 1e3) + " ms/step = " +
                fmt("%.3g", L.counter(cv, "s/step") / plain_step) + "x the plain BW step)"
          : L.why(cv));

  const auto se_step = [&](int t) {
    return L.sec(omp("solve/symplectic_euler/cloth:512", t)) / 20.0;
  };
  const auto rk_step = [&](int t) { return L.sec(omp("solve/rk4/cloth:512", t)) / 20.0; };
  const auto rhs_ratio = [&](int t) { return se_step(t) / L.sec(omp("rhs/plain_cloth/n:512", t)); };
  // Cloth step against the plain gather, from paired rounds (paired_se_plain in bench_rhs.cpp);
  // the rows' ratio, whose two times are taken seconds apart, stays in the note.
  const PairedFigure sp_plain = paired("paired/symplectic_euler_vs_plain_gather/cloth:512/omp:2");
  row("cloth 512² symplectic_euler step (driver) / plain gather RHS, paired rounds",
      sp_plain.median, "%.3g", "<= 0.65", sp_plain.median <= 0.65,
      "(paired: " + sp_plain.describe() + "; from the separate rows: " + fmt("%.3g", rhs_ratio(2)) +
          "; testbed acceleration() alone / plain: " +
          fmt("%.3g", L.sec("rhs/cloth/n:512/omp:2") / L.sec("rhs/plain_cloth/n:512/omp:2")) +
          "; plain RHS " + fmt("%.3g", L.sec("rhs/plain_cloth/n:512/omp:2") * 1e3) + " ms" +
          one_thread(rhs_ratio(1), "%.3g") + ")");
  const double springs = L.counter("rhs/cloth/n:512/omp:2", "springs");
  // Target >= 4e8 springs/s in a symplectic_euler step.
  row("cloth 512² springs/s in a symplectic_euler step", springs / se_step(2), "%.3g", ">= 4e8",
      springs / se_step(2) >= 4e8, "(" + one_thread(springs / se_step(1), "%.3g").substr(2) + ")");
  const auto rk_ratio = [&](int t) { return rk_step(t) / (4.0 * se_step(t)); };
  // The rows' ratios (driver and direct step()) divide times measured seconds apart, so a drift
  // of the vCPUs' speed between the rows enters them whole; the paired rows time rk4 and
  // symplectic_euler in alternating rounds (paired_rk4_se in bench_steps.cpp), and the figure is
  // the worse of their two medians over all rounds. The driver's per-run costs (the result's
  // copy of y0, ‖y0‖∞) are in both sides of a paired driver round alike.
  const double rk_direct =
      L.sec("step/rk4/cloth:512/omp:2") / (4.0 * L.sec("step/symplectic_euler/cloth:512/omp:2"));
  const PairedFigure pd = paired("paired/rk4_vs_4_symplectic_euler/step/cloth:512/omp:2");
  const PairedFigure pv = paired("paired/rk4_vs_4_symplectic_euler/driver/cloth:512/omp:2");
  const double rk_worse =
      std::isfinite(pd.median) && std::isfinite(pv.median) ? std::max(pd.median, pv.median) : kNaN;
  row("cloth 512² rk4 step / (4 x symplectic_euler step), paired rounds, the worse of step() and "
      "driver",
      rk_worse, "%.3g", "<= 1.06", rk_worse <= 1.06,
      "(paired step(): " + pd.describe() + "; paired driver: " + pv.describe() +
          "; from the separate rows: driver " + fmt("%.3g", rk_ratio(2)) + ", step() " +
          fmt("%.3g", rk_direct) + "; Odeint rk4 / (4 x symplectic_euler step()): " +
          fmt("%.3g", L.sec("peer/odeint_rk4/cloth:512/omp:2") /
                          (4.0 * L.sec("step/symplectic_euler/cloth:512/omp:2"))) +
          one_thread(rk_ratio(1), "%.3g") + ")");

  const std::string sph2 = "rhs/sph_dam_break_2d/n:45";
  const auto sph2_us = [&](int t) { return L.counter(omp(sph2, t), "s/particle") * 1e6; };
  row("SPH 2D dam break (4,050 particles), us per particle per RHS", sph2_us(2), "%.3g",
      "<= 0.3 (PySPH: scripts/bench_pysph.sh)", sph2_us(2) <= 0.3,
      "(" + one_thread(sph2_us(1), "%.3g").substr(2) + ")");
  const std::string sph3 = "rhs/sph_dam_break_3d/n:46/omp:2";
  const double sph3_ms = L.sec(sph3) * 1e3;
  // Target 35 ms (the Verlet list reused; a call that rebuilds
  // it is rhs_list_build/, shown in the note).
  row("SPH 3D dam break (97,336 particles), one RHS, ms", sph3_ms, "%.3g", "<= 35", sph3_ms <= 35.0,
      "(" + one_thread(L.sec("rhs/sph_dam_break_3d/n:46/omp:1") * 1e3, "%.3g").substr(2) +
          "; with a list build: " +
          fmt("%.3g", L.sec("rhs_list_build/sph_dam_break_3d/n:46/omp:2") * 1e3) + " ms" +
          one_thread(L.sec("rhs_list_build/sph_dam_break_3d/n:46/omp:1") * 1e3, "%.3g") + ")");
  // The testbed's pairs/s over the plain 3D gather's (bench/plain_sph.hpp),
  // the same pairs (fluid pairs within h) and state, so the ratio of their times.
  const auto sph3_vs_peer = [&](int t) {
    return L.sec(omp("peer/plain_sph_3d/n:46", t)) / L.sec(omp("rhs/sph_dam_break_3d/n:46", t));
  };
  // From paired rounds (paired_sph_peer in bench_rhs.cpp); the rows' ratio stays in the note.
  const PairedFigure sph_peer = paired("paired/plain_sph_3d_vs_testbed/n:46/omp:2");
  row("SPH 3D dam break pairs/s / plain SPH gather's pairs/s, paired rounds", sph_peer.median,
      "%.3g", ">= 3", sph_peer.median >= 3.0,
      "(paired: " + sph_peer.describe() +
          "; from the separate rows: " + fmt("%.3g", sph3_vs_peer(2)) +
          "; plain: " + fmt("%.3g", L.sec("peer/plain_sph_3d/n:46/omp:2") * 1e3) + " ms, " +
          fmt("%.3g", L.counter("peer/plain_sph_3d/n:46/omp:2", "pairs/s")) + " pairs/s" +
          one_thread(sph3_vs_peer(1), "%.3g") + ")");
  // The SPH right-hand sides' 2-thread speed-ups, largest size of each.
  // From paired rounds (paired_sph_threads in bench_rhs.cpp) when they ran, else from the rows;
  // the rows' speed-up stays in the note.
  for (const char* sph_rhs : {"rhs/sph_dam_break_2d/n:224", "rhs/sph_dam_break_3d/n:46"}) {
    const std::string b = sph_rhs;
    const double rows_sp = L.sec(b + "/omp:1") / L.sec(b + "/omp:2");
    const std::string paired_name = "paired/sph_threads/" + b.substr(4) + "/omp:1_vs_2";
    const PairedFigure pt = paired(paired_name);
    const bool use_paired = std::isfinite(pt.median);
    const double sp = use_paired ? pt.median : rows_sp;
    // cpu_attainable: the CPUs' probe just before the 2-thread loop (time_on_fastest_cpu in
    // bench_rhs.cpp; the 1-thread loop ran pinned to the CPU its own probe found fastest).
    const double reach = L.counter(b + "/omp:2", "cpu_attainable");
    const double paired_reach = L.counter(paired_name, "cpu_attainable");
    const std::string pinned =
        L.counter(b + "/omp:1", "cpu_pinned") >= 0 ? " (pinned to the fastest CPU)" : "";
    row(b.substr(4) + " 2-thread speed-up" + (use_paired ? ", paired rounds" : ""), sp, "%.2f",
        ">= 1.8", sp >= 1.8,
        "(paired: " + pt.describe() +
            (std::isfinite(paired_reach)
                 ? "; the CPUs' probe before it: at most " + fmt("%.2f", paired_reach)
                 : "") +
            "; from the separate rows: " + fmt("%.2f", rows_sp) + ", " +
            fmt("%.3g", L.sec(b + "/omp:1") * 1e3) + " ms on 1 thread" + pinned + ", " +
            fmt("%.3g", L.sec(b + "/omp:2") * 1e3) + " ms on 2; the CPUs' probe before the " +
            "2-thread run: at most " + fmt("%.2f", reach) + ", so " +
            fmt("%.0f%%", rows_sp / reach * 100.0) + " of what these CPUs allowed)");
  }
  const std::string nb3 = "neighbour_search/sph_dam_break_3d/n:46/omp:2";
  const double share = L.sec(nb3) / L.sec(sph3);
  row("SPH 3D neighbour search (grid build + one visit of all pairs) / RHS", share * 100.0,
      "%.3g%%", "<= 30%", share <= 0.3,
      "(grid build alone: " +
          fmt("%.3g%%",
              L.sec("neighbour_build/sph_dam_break_3d/n:46/omp:2") / L.sec(sph3) * 100.0) +
          one_thread(L.sec("neighbour_search/sph_dam_break_3d/n:46/omp:1") /
                         L.sec("rhs/sph_dam_break_3d/n:46/omp:1") * 100.0,
                     "%.3g%%") +
          ")");

  // 2-thread speed-up of each right-hand side measured at 1 and 2 threads. The target applies
  // to the largest size of each model (small sizes run serially below the models'
  // parallel_threshold by design); every pair is listed further down.
  std::map<std::string, std::pair<long, double>> largest;  // "rhs/cloth" -> (n, speed-up)
  std::string speedups;
  for (const auto& [name, res] : results) {
    const std::string suffix = "/omp:1";
    if ((name.rfind("rhs/", 0) != 0 && name.rfind("neighbour_search/", 0) != 0) ||
        name.size() < suffix.size() ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string base = name.substr(0, name.size() - suffix.size());
    const double s = L.sec(name) / L.sec(base + "/omp:2");
    if (!std::isfinite(s)) continue;
    const double reach = L.counter(base + "/omp:2", "cpu_attainable");
    speedups += "    " + base + ": " + fmt("%.2f", s) +
                (std::isfinite(reach) ? " (the CPUs' probe allowed " + fmt("%.2f", reach) + ": " +
                                            fmt("%.0f%%", s / reach * 100.0) + ")"
                                      : "") +
                "\n";
    const std::size_t at = base.rfind("/n:");
    if (at == std::string::npos) continue;
    const std::string family = base.substr(0, at);
    const long n = std::stol(base.substr(at + 3));
    auto it = largest.find(family);
    if (it == largest.end() || n > it->second.first) largest[family] = {n, s};
  }
  double worst_speedup = kNaN;
  std::string worst_name;
  for (const auto& [family, ns] : largest)
    if (!(ns.second >= worst_speedup)) {
      worst_speedup = ns.second;
      worst_name = family + "/n:" + std::to_string(ns.first);
    }
  row("2-thread speed-up of each RHS, largest size of each (worst)", worst_speedup, "%.2f",
      ">= 1.8", worst_speedup >= 1.8,
      worst_name.empty() ? "" : "(" + worst_name + attainable_note(cfg) + ")");

  // Building the 512² cloth through the registry plus its first acceleration() (1 thread).
  const std::string build = "build/cloth/n:512/omp:1";
  row("cloth 512² model construction + first RHS, s", L.sec(build), "%.3g", "< 0.3",
      L.sec(build) < 0.3,
      "(construction alone " + fmt("%.3g", L.counter(build, "construct_s")) + " s, first RHS " +
          fmt("%.3g", L.counter(build, "first_rhs_s")) + " s)");

  // Heap allocations per step of every hand-written integrator (after its first step), at 2
  // threads. At 1 thread GCC 12's libgomp allocates a team for every parallel region it enters
  // (it caches teams of 2 or more threads only), so 1-thread rows count one allocation per
  // parallel region of the step; they are listed in the note.
  double worst_allocs = kNaN;
  std::string alloc_list, one_thread_allocs;
  for (const auto& [name, res] : results) {
    if (res.error) continue;
    const auto it = res.counters.find("allocs/step");
    if (it == res.counters.end()) continue;
    const bool t1 = name.size() >= 6 && name.compare(name.size() - 6, 6, "/omp:1") == 0;
    if (t1) {
      one_thread_allocs += " " + name + "=" + fmt("%.3g", it->second);
      continue;
    }
    if (!(it->second <= worst_allocs)) worst_allocs = it->second;
    if (it->second > 0) alloc_list += " " + name + "=" + fmt("%.3g", it->second);
  }
  row("heap allocations per step, hand-written integrators (max)", worst_allocs, "%.3g", "0",
      worst_allocs == 0.0,
      (alloc_list.empty() ? "" : "(non-zero:" + alloc_list + ")") +
          (one_thread_allocs.empty()
               ? ""
               : " (1 thread, libgomp's per-region teams included:" + one_thread_allocs + ")"));
  std::printf("(allocation counter self-check: %ld of 2 test allocations seen)\n",
              cfg.alloc_self_check);

  // ---- Baraff-Witkin trajectory check.
  const std::string chk = "check/bw_trajectory/cloth:64";
  std::printf("\nBaraff-Witkin trajectory, cloth 64², h = 0.01, max |x difference| at t = 0.5:\n");
  std::printf("  plain BW (CG 1e-6) vs testbed baraff_witkin (defaults):        %s\n",
              fmt("%.3g", L.counter(chk, "plain_vs_bw")).c_str());
  std::printf(
      "  plain BW (CG 1e-6) vs testbed baraff_witkin (cg, 1e-6):        %s%s\n",
      fmt("%.3g", L.counter(chk, "plain_vs_bw_cg")).c_str(),
      L.counter(chk, "plain_vs_bw_cg") < 0
          ? ("  (no run: " + L.why("implicit/baraff_witkin_cg/cloth:64/omp:2") + ")").c_str()
          : "");
  std::printf("  plain BW (CG 1e-12) vs testbed baraff_witkin (defaults):       %s\n",
              fmt("%.3g", L.counter(chk, "plain_tight_vs_bw")).c_str());
  std::printf("  plain BW (CG 1e-6) vs plain BW (CG 1e-12): the solve error      %s\n",
              fmt("%.3g", L.counter(chk, "plain_vs_plain_tight")).c_str());
  std::printf("  (-1: a run it compares was filtered out or failed; the issue's target is 2e-8)\n");

  // ---- Per-step overhead of every hand-written integrator.
  std::printf(
      "\nPer-step cost of the hand-written integrators (overhead = step time / (f evals "
      "per step x one acceleration() time)):\n\n");
  std::printf("| benchmark | step | f/step | overhead | allocs/step |\n|---|---|---|---|---|\n");
  for (const auto& [name, res] : results) {
    if (name.rfind("step/", 0) != 0 && name.rfind(be, 0) != 0) continue;
    if (res.error) {
      std::printf("| %s | failed: %s | | | |\n", name.c_str(), res.message.c_str());
      continue;
    }
    std::printf("| %s | %s us | %s | %s | %s |\n", name.c_str(),
                fmt("%.4g", res.seconds * 1e6).c_str(),
                fmt("%.3g", L.counter(name, "f/step")).c_str(),
                fmt("%.3g", L.counter(name, "overhead")).c_str(),
                fmt("%.3g", L.counter(name, "allocs/step")).c_str());
  }

  // ---- Side by side: classic RK4 on the same RHS and state layout.
  std::printf("\nClassic RK4 side by side, cloth 512², same rhs(), one step:\n");
  for (const std::string t : {"1", "2"}) {
    const std::string tb = "step/rk4/cloth:512/omp:" + t;
    if (!L.get(tb)) continue;
    const double ours = L.sec(tb);
    const double ours_f = ours / L.counter(tb, "f/step");
    std::printf("  %s threads: testbed rk4 %s ms/step (%s f/step)\n", t.c_str(),
                fmt("%.4g", ours * 1e3).c_str(), fmt("%.3g", L.counter(tb, "f/step")).c_str());
    for (const std::string peer : {"odeint_rk4", "gsl_rk4", "arkode_rk4"}) {
      const std::string p = "peer/" + peer + "/cloth:512/omp:" + t;
      const double ps = L.sec(p), pf = L.counter(p, "f/step");
      std::printf(
          "    %-11s %s ms/step, %s f/step: step time / testbed's = %s, per f evaluation "
          "= %s%s\n",
          peer.c_str(), fmt("%.4g", ps * 1e3).c_str(), fmt("%.3g", pf).c_str(),
          fmt("%.3g", ps / ours).c_str(), fmt("%.3g", (ps / pf) / ours_f).c_str(),
          std::isfinite(ps) ? "" : ("  (" + L.why(p) + ")").c_str());
    }
  }

  std::printf("\n2-thread speed-ups (time at 1 thread / time at 2)%s:\n%s",
              attainable_note(cfg).empty() ? "" : (" -- " + attainable_note(cfg).substr(2)).c_str(),
              speedups.empty() ? "    (none measured at both thread counts)\n" : speedups.c_str());
  // Spread over repetitions: median, fastest, and the bootstrap 95% interval of the median.
  int most = 0;
  for (const auto& [name, res] : results) most = std::max(most, res.repetitions);
  std::printf(
      "\nSpread over repetitions (real time per iteration: median, minimum, bootstrap 95%% "
      "interval of the median, 2000 resamples; its half-width relative to the median)%s:\n\n",
      most <= 1 ? " -- one repetition each: pass --benchmark_repetitions=N for a spread" : "");
  std::printf(
      "| benchmark | repetitions | median | min | 95%% interval | +/- "
      "|\n|---|---|---|---|---|---|\n");
  for (const auto& [name, res] : results) {
    if (res.error) continue;
    const double half = 0.5 * (res.ci_high - res.ci_low) / res.seconds;
    std::printf("| %s | %d | %s s | %s s | [%s, %s] s | %s |\n", name.c_str(), res.repetitions,
                fmt("%.4g", res.seconds).c_str(), fmt("%.4g", res.min_seconds).c_str(),
                fmt("%.4g", res.ci_low).c_str(), fmt("%.4g", res.ci_high).c_str(),
                fmt("%.1f%%", 100.0 * half).c_str());
  }

  std::vector<std::pair<double, std::string>> spent;
  for (const auto& [name, t] : time_spent()) spent.emplace_back(t, name);
  std::sort(spent.rbegin(), spent.rend());
  std::printf("\nWall time spent per benchmark (set-up and trial runs included), largest:\n");
  for (std::size_t i = 0; i < spent.size() && i < 8; ++i)
    std::printf("    %6.1f s  %s\n", spent[i].first, spent[i].second.c_str());
  std::printf("\nstiffbench_bench: %s run finished in %.1f s\n", cfg.quick ? "--quick" : "full",
              wall_seconds);
}

}  // namespace stiffbench::bench
