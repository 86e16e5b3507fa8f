#include "experiments/studies/energy.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <ostream>
#include <sstream>

#include "experiments/framework/catalog.hpp"
#include "experiments/framework/option_table.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/progress.hpp"

namespace stiffbench {

namespace fs = std::filesystem;

namespace {

// The options of `stiffbench energy`, bound to EnergySpec's fields (defaults: its initialisers).
const OptionTable<EnergySpec>& energy_options() {
  static const OptionTable<EnergySpec> table =
      OptionTable<EnergySpec>()
          .add("h", &EnergySpec::h,
               "step size (the run takes N = round(T/h) steps of T/N; default: the model's "
               "suggested step, where it has one)",
               Bounds::positive())
          .add("t_end", &EnergySpec::t_end,
               "final time (default: the model's literature end time, where it has one)",
               Bounds::positive())
          .add("samples", &EnergySpec::samples,
               "rows per integrator in energy.csv (every ceil(N/samples) steps, each with the "
               "maximum error since the previous row)",
               Bounds::at_least(1))
          .add("invariant", &EnergySpec::invariant,
               "which invariant of the model is measured (see `stiffbench describe MODEL`)");
  return table;
}

}  // namespace

void EnergySpec::validate() const {
  energy_options().check(*this);
  require_input(!invariant.empty(), "--invariant: empty name");
  require_input(!integrators.empty(), "--integrators: no integrator given");
}

nlohmann::json EnergySpec::to_json() const {
  nlohmann::json j = {{"model", model}, {"params", params.values()}, {"integrators", integrators}};
  energy_options().to_json(*this, j);
  return j;
}

namespace {

// |v - v0| / |v0|, or |v - v0| when v0 is (round-off) zero; NaN counts as +inf so a maximum
// cannot skip it.
double relative_error(double v, double v0, bool absolute) {
  const double d = std::abs(v - v0);
  const double e = absolute ? d : d / std::abs(v0);
  return std::isnan(e) ? std::numeric_limits<double>::infinity() : e;
}

// Online least-squares slope of e against t (Welford's centred updates: no cancellation between
// large sums when e is nearly constant), so no per-step storage is needed.
class SlopeAccumulator {
 public:
  void add(double t, double e) {
    ++n_;
    const double dt = t - mean_t_;
    mean_t_ += dt / static_cast<double>(n_);
    mean_e_ += (e - mean_e_) / static_cast<double>(n_);
    c_te_ += dt * (e - mean_e_);
    m2_t_ += dt * (t - mean_t_);
  }
  double slope() const { return m2_t_ > 0 ? c_te_ / m2_t_ : 0.0; }

 private:
  long n_ = 0;
  double mean_t_ = 0, mean_e_ = 0, c_te_ = 0, m2_t_ = 0;
};

std::string names_of(const std::vector<Invariant>& invs) {
  std::string s;
  for (const auto& inv : invs) s += (s.empty() ? "" : ", ") + inv.name;
  return s.empty() ? "none" : s;
}

// The index of opt.invariant among the model's invariants `invs`; BadInput when the model has
// no such invariant or the integrator cannot run fixed steps on it.
std::size_t checked_main_invariant(const OdeSystem& sys, const Integrator& integ,
                                   const std::vector<Invariant>& invs,
                                   const EnergyRunOptions& opt) {
  require_input(opt.samples >= 1, "--samples must be >= 1");
  std::size_t main_index = invs.size();
  for (std::size_t i = 0; i < invs.size(); ++i)
    if (invs[i].name == opt.invariant) main_index = i;
  require_input(main_index < invs.size(), "model '" + sys.name() + "' has no invariant '" +
                                              opt.invariant +
                                              "' (its invariants: " + names_of(invs) + ")");
  require_input(integ.supports_fixed_step(),
                "integrator '" + integ.info().name +
                    "' is adaptive only: the energy-drift study runs fixed steps (--h)");
  check_compatible(integ.info(), sys);
  return main_index;
}

// The invariants other than the main one: their initial values and largest relative errors.
struct OtherInvariants {
  std::vector<const Invariant*> invs;
  std::vector<double> v0, max;
  std::vector<char> absolute;

  OtherInvariants(const std::vector<Invariant>& all, std::size_t main_index, double t0,
                  const Vec& y0) {
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (i == main_index) continue;
      invs.push_back(&all[i]);
      v0.push_back(all[i].value(t0, y0));
      max.push_back(0.0);
      absolute.push_back(invariant_error_is_absolute(v0.back(), all[i].arbitrary_zero));
    }
  }
  void add(double t, CVecRef y) {
    for (std::size_t i = 0; i < invs.size(); ++i)
      max[i] = std::max(max[i], relative_error(invs[i]->value(t, y), v0[i], absolute[i] != 0));
  }
};

// The largest error over the run divided by the largest over its first tenth (infinite when the
// first tenth had none and the run some, 1 when neither had any).
double growth_ratio(double max_all, double max_tenth) {
  if (max_tenth > 0) return max_all / max_tenth;
  return max_all > 0 ? std::numeric_limits<double>::infinity() : 1.0;
}

}  // namespace

EnergyRun measure_energy_drift(const OdeSystem& sys, Integrator& integ,
                               const EnergyRunOptions& opt) {
  const std::vector<Invariant> invs = sys.invariants();
  const std::size_t main_index = checked_main_invariant(sys, integ, invs, opt);

  const double t0 = sys.initial_time();
  FixedStepOptions fopt;
  fopt.t_end = opt.t_end;
  fopt.h = opt.h;
  const long n = fixed_step_count(t0, opt.t_end, opt.h, fopt.max_steps);
  fopt.outputs = n;  // the observer sees every step
  const long stride = (n + opt.samples - 1) / opt.samples;
  // A step belongs to the first tenth when t <= t_tenth (with a little slack for the rounding of
  // t0 + k·h).
  const double span = opt.t_end - t0;
  const double t_tenth = t0 + 0.1 * span + 1e-12 * std::abs(span);

  const Invariant& main_inv = invs[main_index];
  const Vec y0 = sys.initial_state();
  const double v0 = main_inv.value(t0, y0);
  const bool absolute = invariant_error_is_absolute(v0, main_inv.arbitrary_zero);
  OtherInvariants others(invs, main_index, t0, y0);

  EnergyRun run;
  run.integrator = integ.info().name;
  run.steps = n;
  run.t_end = opt.t_end;
  run.samples.reserve(static_cast<std::size_t>(n / stride + 3));

  SlopeAccumulator slope;
  double max_all = 0, max_tenth = 0, since_last = 0;
  bool reached_tenth = false;
  long k = 0;  // step index of the observer call (0: the initial state)
  long last_sampled = -1;
  EnergySample last{};
  int tenths_reported = 0;
  const Observer observer = [&](double t, CVecRef y) {
    const double v = main_inv.value(t, y);
    const double e = relative_error(v, v0, absolute);
    since_last = std::max(since_last, e);
    max_all = std::max(max_all, e);
    if (t <= t_tenth) {
      max_tenth = std::max(max_tenth, e);
    } else {
      reached_tenth = true;
    }
    slope.add(t, e);
    others.add(t, y);
    last = {t, v, e, since_last};
    if (k % stride == 0 || k == n) {
      run.samples.push_back(last);
      last_sampled = k;
      since_last = 0;
    }
    if (opt.on_tenth && k > 0 && k * 10 >= (tenths_reported + 1) * n) {
      while (k * 10 >= (tenths_reported + 1) * n) ++tenths_reported;
      opt.on_tenth(tenths_reported, t);
    }
    ++k;
  };

  const RunResult r = run_fixed_step_from(sys, integ, t0, y0, fopt, observer);
  // A run that stopped early ends its series at its last good step.
  if (k > 0 && last_sampled != k - 1) run.samples.push_back(last);
  run.h = r.h;
  run.stats = r.stats;
  run.t_reached = last.t;
  run.max_rel_error = max_all;
  run.final_rel_error = last.rel_error;
  run.final_change = absolute ? last.value - v0 : (last.value - v0) / std::abs(v0);
  run.drift_rate = slope.slope();
  if (reached_tenth || r.stats.status == Status::ok)
    run.growth_ratio = growth_ratio(max_all, max_tenth);
  for (std::size_t i = 0; i < others.invs.size(); ++i)
    run.other_max_rel_error.emplace_back(others.invs[i]->name, others.max[i]);
  return run;
}

EnergyResult run_energy(const StudyInputs& in, const EnergySpec& spec, std::ostream* progress) {
  const EnergySpec given = with_inputs(spec, in);
  given.validate();
  Setup setup = make_setup(in);
  const OdeSystem& sys = *setup.model;

  EnergyResult res;
  res.model = given.model;
  res.invariant = given.invariant;
  const std::vector<Invariant> invs = sys.invariants();
  bool found = false;
  for (const auto& inv : invs) {
    if (inv.name == given.invariant) {
      found = true;
      res.initial_value = inv.value(sys.initial_time(), sys.initial_state());
      res.arbitrary_zero = inv.arbitrary_zero;
    } else {
      res.other_invariants.push_back(inv.name);
      res.other_initial_values.push_back(inv.value(sys.initial_time(), sys.initial_state()));
      res.other_arbitrary_zero.push_back(inv.arbitrary_zero);
    }
  }
  require_input(found, "--invariant: model '" + given.model + "' has no invariant '" +
                           given.invariant + "' (its invariants: " + names_of(invs) + ")");
  for (const auto& integ : setup.integrators)
    require_input(integ->supports_fixed_step(),
                  "integrator '" + integ->info().name +
                      "' is adaptive only: the energy-drift study runs fixed steps (--h)");

  const Resolved h = resolve_step(sys, given.h, given.model);
  res.h = h.value;
  res.h_source = h.source;
  if (progress && h.source != "--h")
    *progress << "no --h given: the model's suggested step h = " << format_full(res.h) << " ("
              << h.source.substr(16) << ")\n";
  const Resolved t_end = resolve_end_time(sys, given.t_end, given.model);
  res.t_end = t_end.value;
  res.t_end_source = t_end.source;
  // Checks h and t_end (and the step budget) before the first run.
  fixed_step_count(sys.initial_time(), res.t_end, res.h, FixedStepOptions{}.max_steps);

  const long total = 10 * static_cast<long>(setup.integrators.size());
  Progress prog(progress, "energy", total);
  for (auto& integ : setup.integrators) {
    EnergyRunOptions opt;
    opt.h = res.h;
    opt.t_end = res.t_end;
    opt.samples = given.samples;
    opt.invariant = given.invariant;
    const std::string name = integ->info().name;
    int ticked = 0;
    opt.on_tenth = [&](int tenth, double t) {
      // The tenth tick comes after the run, with its result.
      for (; ticked < std::min(tenth, 9); ++ticked) prog.tick(name + ", t = " + format_short(t, 3));
    };
    res.runs.push_back(measure_energy_drift(sys, *integ, opt));
    const EnergyRun& run = res.runs.back();
    // A run that stopped early still counts as done.
    for (; ticked < 10; ++ticked)
      prog.tick(
          name + " " + to_string(run.stats.status) + ", max " +
          (invariant_error_is_absolute(res.initial_value, res.arbitrary_zero) ? "abs." : "rel.") +
          " error = " + format_short(run.max_rel_error, 3));
  }
  return res;
}

namespace {

std::string optional_full(const std::optional<double>& x) { return x ? format_full(*x) : ""; }

}  // namespace

Table energy_table(const EnergyResult& r) {
  Table t{{"model", "integrator", "h", "t", "energy", "rel_error", "max_rel_error_since_last"}, {}};
  for (const auto& run : r.runs)
    for (const auto& s : run.samples)
      t.rows.push_back({r.model, run.integrator, format_full(run.h), format_full(s.t),
                        format_full(s.value), format_full(s.rel_error),
                        format_full(s.max_rel_error_since_last)});
  return t;
}

// The original contract columns first, then the run's counters (docs/formats.md).
Table energy_summary_table(const EnergyResult& r) {
  Table t{{"model", "integrator", "h", "t_end", "max_rel_error", "final_rel_error", "drift_rate",
           "growth", "status", "steps", "f_evals", "jac_evals", "lin_solves"},
          {}};
  for (const auto& c : SolveStats::counter_names()) t.columns.push_back(c);
  for (const auto& run : r.runs) {
    std::vector<std::string> row = {r.model,
                                    run.integrator,
                                    format_full(run.h),
                                    format_full(run.t_end),
                                    format_full(run.max_rel_error),
                                    format_full(run.final_rel_error),
                                    format_full(run.drift_rate),
                                    optional_full(run.growth_ratio),
                                    to_string(run.stats.status),
                                    std::to_string(run.stats.steps),
                                    std::to_string(run.stats.f_evals),
                                    std::to_string(run.stats.jac_evals),
                                    SolveStats::count_text(run.stats.lin_solves)};
    for (auto& v : run.stats.counter_values()) row.push_back(std::move(v));
    t.rows.push_back(std::move(row));
  }
  return t;
}

namespace {

// "+1.2e-03 (gain)", "-3.4e-05 (loss)", "0", or "-" when not finite.
std::string signed_change(double c) {
  if (!std::isfinite(c)) return "-";
  if (c == 0.0) return "0";
  return (c > 0 ? "+" : "") + format_short(c, 2) + (c > 0 ? " (gain)" : " (loss)");
}

}  // namespace

Table energy_markdown_table(const EnergyResult& r) {
  const std::string kind =
      invariant_error_is_absolute(r.initial_value, r.arbitrary_zero) ? "abs." : "rel.";
  Table t{{"integrator", "h", "steps", "max " + kind + " error", "final " + kind + " error",
           "final change", "drift rate (1/t)", "growth", "status"},
          {}};
  for (std::size_t i = 0; i < r.other_invariants.size(); ++i)
    t.columns.push_back(
        (invariant_error_is_absolute(r.other_initial_values.at(i), r.other_arbitrary_zero.at(i))
             ? "max abs. error "
             : "max rel. error ") +
        r.other_invariants[i]);
  // f evaluations, and of the solver counters those some run reports (implicit methods).
  t.columns.push_back("f_evals");
  std::vector<std::size_t> counters;
  const auto names = SolveStats::counter_names();
  for (std::size_t c = 0; c < names.size(); ++c)
    for (const auto& run : r.runs)
      if (run.stats.counter_values()[c] != "0") {
        counters.push_back(c);
        t.columns.push_back(names[c]);
        break;
      }
  t.columns.push_back("wall s");
  for (const auto& run : r.runs) {
    std::vector<std::string> row = {run.integrator,
                                    format_short(run.h, 3),
                                    std::to_string(run.steps),
                                    format_short(run.max_rel_error, 2),
                                    format_short(run.final_rel_error, 2),
                                    signed_change(run.final_change),
                                    format_short(run.drift_rate, 2),
                                    run.growth_ratio ? format_short(*run.growth_ratio, 2) : "-",
                                    to_string(run.stats.status)};
    for (const auto& [name, value] : run.other_max_rel_error) row.push_back(format_short(value, 2));
    row.push_back(std::to_string(run.stats.f_evals));
    const auto values = run.stats.counter_values();
    for (std::size_t c : counters) row.push_back(SolveStats::count_shown(values[c]));
    row.push_back(format_short(run.stats.wall_s, 2));
    t.rows.push_back(std::move(row));
  }
  return t;
}

namespace {

std::string markdown_report(const EnergySpec& spec, const EnergyResult& r) {
  std::ostringstream os;
  os << "# Energy drift: " << r.model << "\n\n";
  os << "Invariant: " << r.invariant << ", initial value " << format_full(r.initial_value)
     << "; relative error |I(t) - I0|/|I0|"
     << (!r.arbitrary_zero.empty()
             ? " (here the absolute error |I(t) - I0|: its zero is arbitrary, " + r.arbitrary_zero +
                   ")"
         : invariant_error_is_absolute(r.initial_value)
             ? " (here the absolute error |I(t) - I0|, since |I0| <= " +
                   format_short(kZeroInvariant, 0) + ")"
             : "")
     << " evaluated after every step. h = " << format_full(r.h) << " (" << r.h_source
     << "), t_end = " << format_full(r.t_end) << " (" << r.t_end_source << ").";
  if (!spec.params.empty()) {
    os << " Parameters:";
    for (const auto& [k, v] : spec.params.values()) os << " " << k << "=" << v;
    os << ".";
  }
  if (!r.other_invariants.empty()) {
    os << " Other invariants:";
    for (std::size_t i = 0; i < r.other_invariants.size(); ++i)
      os << (i ? "," : "") << " " << r.other_invariants[i] << " (initial value "
         << format_short(r.other_initial_values[i], 3) << ", "
         << (invariant_error_is_absolute(r.other_initial_values[i], r.other_arbitrary_zero[i])
                 ? "absolute"
                 : "relative")
         << " error" << (r.other_arbitrary_zero[i].empty() ? "" : ": " + r.other_arbitrary_zero[i])
         << ")";
    os << ".";
  }
  os << "\n\n";
  os << "growth = max error over the run / max over its first tenth: about 1 means the error "
        "oscillates within a bounded band (symplectic methods), about 10 means it grows "
        "linearly in time (secular drift, e.g. rk4); drift rate is the least-squares slope of "
        "the error against t; final change is the invariant's change at the end with its sign "
        "(same scale as the error): a gain or a loss.\n\n";
  os << energy_markdown_table(r).to_markdown() << "\n";
  for (const auto& run : r.runs)
    if (run.stats.status != Status::ok)
      os << "- " << run.integrator << ": " << run.stats.message
         << "; rows end at t = " << format_full(run.t_reached) << ".\n";
  os << "\nTime series (sampled, each row with the maximum since the previous one): "
        "`energy.csv`; summary at full precision: `energy_summary.csv`; metadata: "
        "`energy.json`; plot: `energy.png`.\n";
  return os.str();
}

}  // namespace

bool write_energy_outputs(const fs::path& dir, const EnergySpec& spec, const EnergyResult& r,
                          const PlotOptions& opt, std::ostream& err, const std::string& title) {
  write_file_atomic(dir / "energy.csv", energy_table(r).to_csv());
  write_file_atomic(dir / "energy_summary.csv", energy_summary_table(r).to_csv());
  write_file_atomic(dir / "energy.md", markdown_report(spec, r));
  // "spec" is the spec as given (what check_study_output compares before a run); the step and
  // end time it resolved to are recorded beside it.
  nlohmann::json meta = run_metadata("energy", spec.to_json());
  meta["h_used"] = r.h;
  meta["h_source"] = r.h_source;
  meta["t_end_used"] = r.t_end;
  meta["t_end_source"] = r.t_end_source;
  meta["invariant"] = r.invariant;
  meta["initial_value"] = r.initial_value;
  meta["other_invariants"] = r.other_invariants;
  meta["other_initial_values"] = r.other_initial_values;
  meta["arbitrary_zero"] = r.arbitrary_zero;
  meta["other_arbitrary_zero"] = r.other_arbitrary_zero;
  meta["relative_error"] =
      "|I(t) - I0| / |I0| after every step (absolute |I(t) - I0| when |I0| <= " +
      format_short(kZeroInvariant, 0) +
      " or when the invariant's zero is arbitrary: arbitrary_zero says why); energy.csv rows "
      "every ceil(N/samples) steps plus the first and last, each with the maximum since the "
      "previous row";
  meta["growth"] = "max over the run / max over t <= t0 + (t_end - t0)/10";
  nlohmann::json runs = nlohmann::json::array();
  for (const auto& run : r.runs) {
    nlohmann::json j = {
        {"integrator", run.integrator},
        {"h", run.h},
        {"steps", run.steps},
        {"t_reached", run.t_reached},
        {"status", to_string(run.stats.status)},
        {"final_change", std::isfinite(run.final_change) ? nlohmann::json(run.final_change)
                                                         : nlohmann::json(nullptr)},
        {"message", run.stats.message},
        {"f_evals", run.stats.f_evals},
        {"wall_s", run.stats.wall_s}};
    for (const auto& [name, value] : run.other_max_rel_error) j["max_error_" + name] = value;
    runs.push_back(std::move(j));
  }
  meta["runs"] = std::move(runs);
  write_file_atomic(dir / "energy.json", meta.dump(2) + "\n");
  return plot_energy(dir / "energy.csv", title.empty() ? "Energy drift: " + r.model : title, opt,
                     err);
}

bool plot_energy(const fs::path& csv, const std::string& title, const PlotOptions& opt,
                 std::ostream& err) {
  fs::path stem = csv;
  stem.replace_extension();
  // The invariant's name for the axis, from energy.json beside the CSV when there is one.
  std::string invariant = "energy";
  fs::path json = csv;
  json.replace_extension(".json");
  if (std::ifstream in(json); in) {
    try {
      const auto meta = nlohmann::json::parse(in);
      if (meta.contains("invariant") && meta["invariant"].is_string())
        invariant = meta["invariant"].get<std::string>();
    } catch (const std::exception&) {
    }
  }
  return run_plot("energy.gp", stem,
                  {{"csvfile", csv.string()},
                   {"ttl", title},
                   {"ylab", "relative " + invariant + " error (max since previous sample)"}},
                  family_panels(csv_column_values(csv, "integrator"), opt.family), opt, err);
}

namespace {

const StudyFunctions<EnergySpec, EnergyResult> kEnergy{
    .run = [](const StudyInputs& in, const EnergySpec& s,
              std::ostream* progress) { return run_energy(in, s, progress); },
    .unit_table = [](const EnergySpec&, const EnergyResult& r) { return energy_summary_table(r); },
    .write = [](const std::filesystem::path& dir, const EnergySpec& s, const EnergyResult& r,
                const std::string& title, const PlotOptions& plot,
                std::ostream& err) { return write_energy_outputs(dir, s, r, plot, err, title); },
    .print_summary =
        [](const EnergySpec&, const EnergyResult& r, std::ostream& out) {
          out << energy_markdown_table(r).to_markdown();
          for (const auto& run : r.runs)
            if (run.stats.status != Status::ok)
              out << run.integrator << ": " << run.stats.message << "\n";
        },
    .report_markdown =
        [](const EnergySpec&, const EnergyResult& r, const std::string& note) {
          return note + "\n\n" + energy_markdown_table(r).to_markdown() + "\n";
        },
    .default_title = [](const EnergySpec& s) { return "Energy drift: " + s.model; },
    .helpers = {}};

using EnergyJob = TypedStudyJob<EnergySpec, EnergyResult>;

}  // namespace

StudyKind energy_study_kind() {
  StudyKind k;
  k.name = "energy";
  k.stem = "energy";
  k.summary =
      "energy drift of long fixed-step runs: the relative error of an invariant after every step, "
      "sampled with the maximum between samples, its maximum, final value, drift rate and growth "
      "ratio; writes energy.{csv,md,json,png} and energy_summary.csv";
  k.options = energy_options().declarations();
  k.extra_files = {"energy_summary.csv"};
  k.unit_columns = energy_summary_table(EnergyResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    EnergySpec s = with_inputs(EnergySpec{}, t);
    energy_options().read(o, s);
    s.validate();
    return std::make_unique<EnergyJob>(kEnergy, t, std::move(s));
  };
  return k;
}

const EnergyResult& energy_result(const StudyJob& job) {
  return typed_result<EnergySpec, EnergyResult>(job);
}

EnergyResult run_energy(const EnergySpec& spec, std::ostream* progress) {
  return run_energy(inputs_of(spec), spec, progress);
}

EnergyResult energy_study(const StudyInputs& in, EnergySpec spec, const std::filesystem::path& dir,
                          const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  spec.validate();
  EnergyJob job(kEnergy, in, std::move(spec));
  run_study_job(study_kind("energy"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
