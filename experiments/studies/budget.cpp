#include "experiments/studies/budget.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "core/ode_system.hpp"
#include "experiments/studies/budget_output.hpp"
#include "experiments/support/invariant_error.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using budget_internal::kIterationsKey;
using budget_internal::kSubstepsKey;

std::string join_longs(const std::vector<long>& v) {
  std::string s;
  for (long x : v) s += (s.empty() ? "" : ",") + std::to_string(x);
  return s;
}

// "1,2,4" → {1, 2, 4}: positive integers, no repeats; BadInput naming the flag otherwise.
std::vector<long> parse_count_list(const std::string& text, const std::string& flag) {
  std::vector<long> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    long v = 0;
    try {
      v = std::stol(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require_input(used > 0 && used == item.size() && v >= 1,
                  flag + ": '" + item + "' is not a positive integer (expected a list like 1,2,4)");
    require_input(std::find(out.begin(), out.end(), v) == out.end(),
                  flag + ": " + item + " is listed twice");
    out.push_back(v);
  }
  require_input(!out.empty(), flag + " must list at least one positive integer");
  return out;
}

// Whether the integrator `integrator` of `in` declares the parameter `key`.
bool declares(const StudyInputs& in, const std::string& integrator, const std::string& key) {
  for (const auto& p : in.integrator_entry(integrator).params)
    if (p.key == key) return true;
  return false;
}

}  // namespace

void BudgetSpec::validate() const {
  require_input(std::isfinite(frame) && frame > 0,
                "--frame must be > 0 (got " + format_full(frame) + ")");
  require_input(frame_count >= 1, "--frame-count must be >= 1");
  require_input(!substeps_list.empty() && !iterations_list.empty(),
                "--substeps and --iterations must each list at least one value");
  require_input(timing_repeats >= 1, "the number of timed runs must be >= 1");
  require_input(max_strain > 0, "--max-strain must be > 0");
  require_input(ref_substeps >= 0, "--ref-substeps must be >= 0");
  require_input(!integrators.empty(), "--integrators: give at least one integrator");
  for (const char* key : {kIterationsKey, kSubstepsKey})
    if (params.contains(key))
      throw BadInput(std::string("--param ") + key + "=" + params.values().at(key) +
                     ": budget sets each method's " + key + " from its grid (use " +
                     option_flag(key) + " LIST)");
}

nlohmann::json BudgetSpec::to_json() const {
  return {{"model", model},
          {"params", params.values()},
          {"integrators", integrators},
          {"frame", frame},
          {"frame_count", frame_count},
          {kSubstepsKey, substeps_list},
          {kIterationsKey, iterations_list},
          {"timing_repeats", timing_repeats},
          {"seed", seed},
          {"max_strain", max_strain},
          {"ref_integrator", ref_integrator},
          {"ref_substeps", ref_substeps}};
}

std::vector<double> spring_strains(const SpringNetworkView& net, CVecRef x) {
  std::vector<double> out;
  for (const SpringElement& e : net.springs) {
    if (!(e.k > 0) || !(e.rest > 0)) continue;
    double l2 = 0;
    for (int c = 0; c < net.dim; ++c) {
      const double d = x[net.dim * e.j + c] - x[net.dim * e.i + c];
      l2 += d * d;
    }
    out.push_back(std::abs(std::sqrt(l2) - e.rest) / e.rest);
  }
  return out;
}

StrainStats spring_strain(const SpringNetworkView& net, CVecRef x) {
  StrainStats s;
  double sum2 = 0;
  for (const double strain : spring_strains(net, x)) {
    s.max = std::isnan(strain) ? strain : std::max(s.max, strain);
    sum2 += strain * strain;
    ++s.springs;
  }
  s.rms = s.springs > 0 ? std::sqrt(sum2 / static_cast<double>(s.springs)) : 0.0;
  return s;
}

double BudgetRow::error() const {
  if (!std::isnan(strain_error_max)) return strain_error_max;
  if (!std::isnan(strain_max)) return strain_max;
  return constraint;
}

namespace {

// One configuration of the grid, its integrator object, its first run and its timed runs.
struct BudgetPoint {
  std::size_t method = 0;
  long substeps = 1;
  std::optional<long> iterations;
  std::unique_ptr<Integrator> integ;
  std::vector<double> ms;  // ms per frame, one per timed run
  RunResult first;
  BudgetRow measured;  // the errors of the first run (measure_errors)
  bool stopped = false;
  std::string mismatch;
};

// What the points share.
struct BudgetContext {
  const StudyInputs& in;
  const BudgetSpec& spec;
  const OdeSystem& sys;
  std::ostream* progress;
  const std::vector<double>* ref_strains = nullptr;  // empty or null: no reference
};

// The grid in the rows' order: per method, substeps ascending as given, then iterations.
std::vector<BudgetPoint> budget_points(const BudgetContext& c) {
  std::vector<BudgetPoint> points;
  for (std::size_t m = 0; m < c.spec.integrators.size(); ++m) {
    const std::string& name = c.spec.integrators[m];
    const bool iterative = declares(c.in, name, kIterationsKey);
    for (long s : c.spec.substeps_list) {
      const std::vector<long> its = iterative ? c.spec.iterations_list : std::vector<long>{0};
      for (long it : its) {
        Params prm = c.spec.params;
        if (iterative) prm.set(kIterationsKey, std::to_string(it));
        if (declares(c.in, name, kSubstepsKey)) prm.set(kSubstepsKey, "1");
        BudgetPoint p;
        p.method = m;
        p.substeps = s;
        if (iterative) p.iterations = it;
        p.integ = c.in.create_integrator(name, prm);
        check_compatible(p.integ->info(), c.sys);
        require_input(p.integ->supports_fixed_step(),
                      "integrator '" + name + "' is adaptive-only: budget runs fixed substeps");
        points.push_back(std::move(p));
      }
    }
  }
  return points;
}

// One run of a point over frame_count frames. The observer copies the state after every frame
// into `frames` (preallocated, so the copy is the only per-frame cost it adds) and the frame
// loop's wall time (from the first observer call, after reset(), to the last) is returned in ms
// per frame (NaN when the run ended before its last frame).
double run_point(const BudgetContext& c, BudgetPoint& p, std::vector<Vec>& frames, RunResult& r) {
  const std::size_t n = static_cast<std::size_t>(c.spec.frame_count) + 1;
  if (frames.size() != n) frames.assign(n, Vec::Zero(c.sys.dimension()));
  std::size_t k = 0;
  std::chrono::steady_clock::time_point start, last;
  const Observer observer = [&](double, CVecRef y) {
    last = std::chrono::steady_clock::now();
    if (k == 0) start = last;
    if (k < n) frames[k] = y;
    ++k;
  };
  FixedStepOptions opt;
  opt.t_end = c.sys.initial_time() + c.spec.frame * static_cast<double>(c.spec.frame_count);
  opt.h = c.spec.frame / static_cast<double>(p.substeps);
  opt.outputs = c.spec.frame_count;
  r = run_fixed_step(c.sys, *p.integ, opt, observer);
  if (k != n || r.stats.status != Status::ok) return kNaN;
  return 1e3 * std::chrono::duration<double>(last - start).count() /
         static_cast<double>(c.spec.frame_count);
}

std::string point_label(const BudgetContext& c, const BudgetPoint& p) {
  std::string s = c.spec.integrators[p.method] + " substeps=" + std::to_string(p.substeps);
  if (p.iterations) s += " iterations=" + std::to_string(*p.iterations);
  return s;
}

void measure_errors(const BudgetContext& c, const std::vector<Vec>& f, BudgetRow& row);

// The first run: its errors are measured from its frames (`frames`: a buffer every run of the
// study reuses, so one set of frames is held at a time); reported as run `done` of `total`.
void first_run(const BudgetContext& c, BudgetPoint& p, std::vector<Vec>& frames, std::size_t done,
               std::size_t total) {
  const double ms = run_point(c, p, frames, p.first);
  p.stopped = std::isnan(ms);  // a run that did not end ok is not repeated
  if (!p.stopped) {
    p.ms.push_back(ms);
    measure_errors(c, frames, p.measured);
  }
  if (!c.progress) return;
  *c.progress << "[" << done << "/" << total << "] " << point_label(c, p)
              << " h=" << format_short(c.spec.frame / static_cast<double>(p.substeps)) << ": "
              << (p.stopped ? to_string(p.first.stats.status) : format_short(ms, 3) + " ms/frame")
              << " (" << format_short(p.first.stats.wall_s, 2) << " s)\n"
              << std::flush;
}

// A repeat: its time, or a stop on a timeout or on a final state differing from run 1.
void repeat_run(const BudgetContext& c, BudgetPoint& p, std::vector<Vec>& frames) {
  RunResult r;
  const double ms = run_point(c, p, frames, r);
  if (r.stats.status == Status::timeout) {
    p.stopped = true;
    return;
  }
  if (r.stats.status != p.first.stats.status || r.y != p.first.y) {
    p.mismatch = "not deterministic: run " + std::to_string(p.ms.size() + 1) +
                 " differs from run 1 in its final state or status";
    p.stopped = true;
    return;
  }
  p.ms.push_back(ms);
}

// Work-precision's rule (kRepeatLongRun, kRepeatBudget): repeat while fewer than the repeats
// have run, the first run took under kRepeatLongRun s and all under kRepeatBudget s.
bool repeats_more(const BudgetContext& c, const BudgetPoint& p) {
  if (p.stopped || static_cast<int>(p.ms.size()) >= c.spec.timing_repeats) return false;
  const double run_s = 1e-3 * p.ms.front() * static_cast<double>(c.spec.frame_count);
  double total = 0;
  for (double m : p.ms) total += 1e-3 * m * static_cast<double>(c.spec.frame_count);
  return run_s < kRepeatLongRun && total < kRepeatBudget;
}

// Rounds in an order shuffled with the seed (run_order), as work-precision runs its points.
void run_rounds(const BudgetContext& c, std::vector<BudgetPoint>& points) {
  std::size_t done = 0;
  std::vector<Vec> frames;
  for (int round = 1; round <= c.spec.timing_repeats; ++round) {
    std::size_t ran = 0;
    for (const std::size_t idx : run_order(points.size(), c.spec.seed, round)) {
      BudgetPoint& p = points[idx];
      if (round > 1 && !repeats_more(c, p)) continue;
      ++ran;
      if (round == 1)
        first_run(c, p, frames, ++done, points.size());
      else
        repeat_run(c, p, frames);
    }
    if (c.progress && round > 1 && ran > 0)
      *c.progress << "repeat round " << round << "/" << c.spec.timing_repeats << ": " << ran
                  << " runs\n"
                  << std::flush;
    if (ran == 0) break;
  }
}

// ½ vᵀ M v of a mechanical state.
double kinetic_energy(const MechanicalSystem& mech, const Vec& masses, CVecRef y) {
  const Index n = mech.dofs();
  double e = 0;
  for (Index i = 0; i < n; ++i) e += 0.5 * masses[i] * y[n + i] * y[n + i];
  return e;
}

// The errors of a run from its states at t0 and after every frame.
void measure_errors(const BudgetContext& c, const std::vector<Vec>& f, BudgetRow& row) {
  const OdeSystem& sys = c.sys;
  const double t_end = sys.initial_time() + c.spec.frame * static_cast<double>(c.spec.frame_count);
  row.strain_max = row.strain_rms = row.strain_peak = kNaN;
  row.strain_error_max = row.strain_error_rms = kNaN;
  row.constraint = row.constraint_peak = kNaN;
  row.energy_rel = kNaN;
  const SpringNetworkView* net = sys.spring_network();
  if (net && spring_strain(*net, f.front()).springs > 0) {
    row.strain_peak = 0;
    for (const Vec& y : f) row.strain_peak = std::max(row.strain_peak, spring_strain(*net, y).max);
    const StrainStats last = spring_strain(*net, f.back());
    row.strain_max = last.max;
    row.strain_rms = last.rms;
    if (c.ref_strains && !c.ref_strains->empty()) {
      const std::vector<double> s = spring_strains(*net, f.back());
      double big = 0, sum2 = 0;
      for (std::size_t i = 0; i < s.size(); ++i) {
        const double d = std::abs(s[i] - (*c.ref_strains)[i]);
        big = std::isnan(d) ? d : std::max(big, d);
        sum2 += d * d;
      }
      row.strain_error_max = big;
      row.strain_error_rms = std::sqrt(sum2 / static_cast<double>(s.size()));
    }
  } else if (sys.has_constraints()) {
    row.constraint_peak = 0;
    for (const Vec& y : f)
      row.constraint_peak = std::max(row.constraint_peak, sys.constraint_residual(y));
    row.constraint = sys.constraint_residual(f.back());
  }
  const MechanicalSystem& mech = *sys.as_mechanical();
  const Vec masses = mech.masses();
  for (const Invariant& inv : sys.invariants()) {
    if (inv.name == "energy") {
      const double e0 = inv.value(sys.initial_time(), f.front());
      // An arbitrary zero (Invariant::arbitrary_zero) makes |E_0| no scale of the motion.
      double scale = inv.arbitrary_zero.empty() ? std::abs(e0) : 0.0;
      for (const Vec& y : f) scale = std::max(scale, kinetic_energy(mech, masses, y));
      row.energy_rel = (inv.value(t_end, f.back()) - e0) / scale;
    } else if (inv.name.rfind("angular_momentum", 0) == 0) {
      const double l0 = inv.value(sys.initial_time(), f.front());
      const double change = std::abs(inv.value(t_end, f.back()) - l0);
      const double drift = invariant_error_is_absolute(l0) ? change : change / std::abs(l0);
      row.angular_drift = std::max(row.angular_drift.value_or(0.0), drift);
    }
  }
}

// The row of point `idx`: timing spread over its runs, status, errors, whether it fits.
BudgetRow budget_row(const BudgetContext& c, const BudgetPoint& p, std::size_t idx) {
  BudgetRow row = p.measured;
  row.integrator = c.spec.integrators[p.method];
  row.substeps = p.substeps;
  row.iterations = p.iterations;
  row.h = p.first.h;
  row.stats = p.first.stats;
  if (!p.mismatch.empty()) {
    row.stats.status = Status::error;
    row.stats.message = p.mismatch;
  }
  if (!p.ms.empty()) {
    row.ms = timing_spread(p.ms, c.spec.seed, idx);
    row.ms_max = *std::max_element(p.ms.begin(), p.ms.end());
  } else {
    row.ms = {kNaN, kNaN, kNaN, kNaN, 0};
    row.ms_max = kNaN;
  }
  if (row.stats.status == Status::ok && row.strain_peak > c.spec.max_strain) {
    row.stats.status = Status::unstable;
    row.stats.message = "strain " + format_short(row.strain_peak) + " exceeds --max-strain " +
                        format_short(c.spec.max_strain);
  }
  if (row.stats.status != Status::ok) {
    row.strain_max = row.strain_rms = row.strain_peak = kNaN;
    row.strain_error_max = row.strain_error_rms = kNaN;
    row.constraint = row.constraint_peak = row.energy_rel = kNaN;
    row.angular_drift.reset();
  }
  row.fits = row.stats.status == Status::ok && row.ms.median <= 1e3 * c.spec.frame;
  return row;
}

// The reference strains at the last frame: the scene run with spec.ref_integrator at
// ref_substeps steps per frame, and at ref_substeps/2 as its check (BudgetResult::ref_check).
// No reference (error measure strain_max) when ref_substeps is 0 or either run fails.
void make_reference(const BudgetSpec& spec, const OdeSystem& sys, Integrator& integ,
                    BudgetResult& res, std::ostream* progress) {
  const SpringNetworkView& net = *sys.spring_network();
  const double t_end = sys.initial_time() + spec.frame * static_cast<double>(spec.frame_count);
  std::vector<double> strains[2];
  for (int k = 0; k < 2; ++k) {
    const long steps = std::max<long>(1, spec.ref_substeps / (k == 0 ? 1 : 2));
    FixedStepOptions opt;
    opt.t_end = t_end;
    opt.h = spec.frame / static_cast<double>(steps);
    const RunResult r = run_fixed_step(sys, integ, opt, {});
    if (r.stats.status != Status::ok) {
      res.ref_note = "no reference: " + spec.ref_integrator + " at " + std::to_string(steps) +
                     " steps per frame ended with " + to_string(r.stats.status) + " (" +
                     r.stats.message + "); the error is the strain itself";
      return;
    }
    strains[k] = spring_strains(net, r.y);
  }
  res.ref_check = 0;
  for (std::size_t i = 0; i < strains[0].size(); ++i)
    res.ref_check = std::max(res.ref_check, std::abs(strains[0][i] - strains[1][i]));
  res.ref_strains = std::move(strains[0]);
  res.error_measure = "strain_error_max";
  res.ref_note = "reference: " + spec.ref_integrator + " at " + std::to_string(spec.ref_substeps) +
                 " steps per frame; its largest strain difference from the run at half as many "
                 "steps is " +
                 format_short(res.ref_check) + " (a bound of its own strain error)";
  if (progress) *progress << "budget: " << res.ref_note << "\n" << std::flush;
}

}  // namespace

BudgetResult run_budget(const StudyInputs& in, const BudgetSpec& given, std::ostream* progress) {
  const BudgetSpec spec = with_inputs(given, in);
  spec.validate();
  std::vector<std::string> names = spec.integrators;
  names.push_back(spec.ref_integrator);  // checked with the others, before anything runs
  Setup setup = make_setup(in, names, spec.params);
  const std::unique_ptr<Integrator> ref = std::move(setup.integrators.back());
  setup.integrators.pop_back();
  const OdeSystem& sys = *setup.model;
  require_input(sys.as_mechanical() != nullptr,
                "--model " + spec.model +
                    ": budget needs a mechanical model (positions and velocities); this one is "
                    "not (see `stiffbench list models`)");
  BudgetResult res;
  res.model = spec.model;
  res.frame = spec.frame;
  res.frame_count = spec.frame_count;
  const Vec y0 = sys.initial_state();
  // A network whose springs all have k = 0 or L = 0 (the constrained pendulum chain's view has
  // none) is measured by its constraints.
  const SpringNetworkView* net = sys.spring_network();
  if (net && spring_strain(*net, y0).springs > 0) {
    res.error_measure = "strain_max";
    res.initial_strain_max = spring_strain(*net, y0).max;
  } else if (sys.has_constraints()) {
    res.error_measure = "constraint_residual";
    res.initial_strain_max = kNaN;
  } else {
    res.initial_strain_max = kNaN;
  }
  if (res.error_measure == "strain_max" && spec.ref_substeps > 0)
    make_reference(spec, sys, *ref, res, progress);
  const BudgetContext c{in, spec, sys, progress, &res.ref_strains};
  std::vector<BudgetPoint> points = budget_points(c);
  if (progress)
    *progress << "budget: " << points.size() << " configurations of " << spec.model << ", "
              << spec.frame_count << " frames of " << format_short(spec.frame) << " s each\n"
              << std::flush;
  run_rounds(c, points);
  for (std::size_t idx = 0; idx < points.size(); ++idx)
    res.rows.push_back(budget_row(c, points[idx], idx));
  return res;
}

namespace {

using budget_internal::best_markdown;
using budget_internal::budget_markdown_table;
using budget_internal::families_markdown;

const StudyFunctions<BudgetSpec, BudgetResult> kBudget{
    .run = [](const StudyInputs& in, const BudgetSpec& s,
              std::ostream* progress) { return run_budget(in, s, progress); },
    .unit_table = [](const BudgetSpec&, const BudgetResult& r) { return budget_table(r); },
    .write =
        [](const std::filesystem::path& dir, const BudgetSpec& s, const BudgetResult& r,
           const std::string& title, const PlotOptions& plot, std::ostream& err) {
          write_budget_outputs(dir, s, r);
          return plot_budget(dir / "budget.csv", title, plot, err);
        },
    .print_summary =
        [](const BudgetSpec& s, const BudgetResult& r, std::ostream& out) {
          out << budget_markdown_table(r).to_markdown() << "\n"
              << best_markdown(r, s.integrators) << families_markdown(r);
        },
    .report_markdown =
        [](const BudgetSpec& s, const BudgetResult& r, const std::string& note) {
          return note + "\n\n" + best_markdown(r, s.integrators) + families_markdown(r);
        },
    .default_title = [](const BudgetSpec& s) { return "Frame budget: " + s.model; },
    // The reference of the strain error consumes the integrator parameters too.
    .helpers = [](const BudgetSpec& s) { return std::vector<std::string>{s.ref_integrator}; }};

using BudgetJob = TypedStudyJob<BudgetSpec, BudgetResult>;

}  // namespace

StudyKind budget_study_kind() {
  using P = ParamType;
  const BudgetSpec d;
  StudyKind k;
  k.name = "budget";
  k.stem = "budget";
  k.summary =
      "cost and stretch per frame over a grid of substeps × iterations per method at a frame "
      "time: ms/frame, strain, energy, angular momentum, fits; writes budget.{csv,md,json,png}";
  k.options = {
      {"frame", P::real, "0.016666666666666666", "frame time in s (the budget)",
       Bounds::positive()},
      {"frame_count", P::integer, std::to_string(d.frame_count),
       "frames run from the initial state per configuration", Bounds::at_least(1)},
      {kSubstepsKey, P::text, join_longs(d.substeps_list),
       "substeps per frame (h = frame/substeps), a list like 1,2,4"},
      {kIterationsKey, P::text, join_longs(d.iterations_list),
       "iterations per substep of the methods with an iterations parameter, a list"},
      timing_repeats_option("3"),
      {"seed", P::integer, "1", "seed of the shuffled run order and of the bootstrap",
       Bounds::non_negative()},
      {"max_strain", P::real, format_full(d.max_strain),
       "a strain above this at any frame makes the configuration unstable", Bounds::positive()},
      {"ref_integrator", P::text, d.ref_integrator,
       "reference of the strain error (spring networks): this integrator at --ref-substeps"},
      {"ref_substeps", P::integer, std::to_string(d.ref_substeps),
       "steps per frame of the reference (checked against half as many); 0: no reference, the "
       "error is the strain itself",
       Bounds::non_negative()}};
  k.unit_columns = budget_table(BudgetResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    BudgetSpec spec = with_inputs(BudgetSpec{}, t);
    spec.frame = o.real("frame");
    spec.frame_count = o.integer("frame_count");
    spec.substeps_list = parse_count_list(o.text(kSubstepsKey), option_flag(kSubstepsKey));
    spec.iterations_list = parse_count_list(o.text(kIterationsKey), option_flag(kIterationsKey));
    spec.timing_repeats = static_cast<int>(o.integer(timing_repeats_option("").key));
    spec.seed = static_cast<unsigned long>(o.integer("seed"));
    spec.max_strain = o.real("max_strain");
    // A method-file path or a variant is resolved here, once, like the studied integrators.
    spec.ref_integrator = resolve_integrator_tokens({o.text("ref_integrator")}).front();
    spec.ref_substeps = o.integer("ref_substeps");
    return std::make_unique<BudgetJob>(kBudget, t, std::move(spec));
  };
  return k;
}

const BudgetResult& budget_result(const StudyJob& job) {
  return typed_result<BudgetSpec, BudgetResult>(job);
}

BudgetResult run_budget(const BudgetSpec& spec, std::ostream* progress) {
  return run_budget(inputs_of(spec), spec, progress);
}

BudgetResult budget_study(const StudyInputs& in, BudgetSpec spec, const std::filesystem::path& dir,
                          const StudyContext& ctx) {
  BudgetJob job(kBudget, in, with_inputs(std::move(spec), in));
  run_study_job(study_kind("budget"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
