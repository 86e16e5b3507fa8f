#include "experiments/studies/stability.hpp"

#include <cmath>
#include <ostream>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/output/progress.hpp"
#include "experiments/studies/stability_output.hpp"
#include "experiments/studies/stability_search.hpp"

namespace stiffbench {

namespace {

using stability_internal::energy_criterion;
using stability_internal::EnergyCriterion;
using stability_internal::explicit_spectrum_of;
using stability_internal::measure;
using stability_internal::num;
using stability_internal::perturbed_state;
using stability_internal::Spectrum;
using stability_internal::spectrum_of;

double parse_number(const std::string& s, const std::string& what) {
  return parse_real(s, "--sweep " + what);
}

}  // namespace

void StabilitySpec::validate() const {
  require_input(!model.empty(), "stability: --model is required");
  require_input(!integrators.empty(), "stability: --integrators is empty");
  require_input(rel_tol > 0 && rel_tol < 0.5, "--rel-tol must be in (0, 0.5), got " + num(rel_tol));
  require_input(periods > 0 && std::isfinite(periods), "--periods must be > 0");
  require_input(min_steps >= 1, "--min-steps must be >= 1");
  require_input(energy_growth > 1 && std::isfinite(energy_growth),
                "--growth must be a finite factor > 1");
  require_input(norm_growth > 1 && std::isfinite(norm_growth),
                "--norm-growth must be a finite factor > 1");
  require_input(perturbation >= 0 && perturbation < 1, "--perturbation must be in [0, 1)");
  require_input(h_cap_factor > 1, "--h-cap-factor must be > 1");
  require_input(max_steps >= 10, "--max-steps must be >= 10");
  require_input(criterion == "auto" || criterion == "energy" || criterion == "norm",
                "--criterion must be auto, energy or norm, got '" + criterion + "'");
  require_input(ray == "auto" || ray == "imag" || ray == "real",
                "--ray must be auto, imag or real, got '" + ray + "'");
  require_input(!horizon || (*horizon > 0 && std::isfinite(*horizon)),
                "--horizon must be a positive time");
  if (!sweep_param.empty())
    require_input(!sweep_values.empty(), "--sweep " + sweep_param + " has no values");
}

nlohmann::json StabilitySpec::to_json() const {
  nlohmann::json j;
  j["model"] = model;
  j["params"] = params.values();
  j["integrators"] = integrators;
  if (!sweep_param.empty()) {
    j["sweep"]["param"] = sweep_param;
    j["sweep"]["values"] = sweep_values;
  }
  j["rel_tol"] = rel_tol;
  j["periods"] = periods;
  j["min_steps"] = min_steps;
  j["growth"] = energy_growth;
  j["norm_growth"] = norm_growth;
  j["perturbation"] = {{"epsilon", perturbation},
                       {"seed", seed},
                       {"generator", "std::mt19937_64, standard normal"},
                       {"rule",
                        "mechanical: x_i += eps*s*xi_i, s = RMS deviation of x0 from its mean; "
                        "first-order: y_i += eps*max(|y0_i|, 1e-3*max|y0|)*xi_i"}};
  j["h_cap_factor"] = h_cap_factor;
  j["max_steps"] = max_steps;
  j["ray"] = ray;
  j["criterion"] = criterion;
  j["dense_limit"] = dense_limit;
  if (horizon) j["horizon"] = *horizon;
  j["probe_unbounded"] = probe_unbounded;
  return j;
}

void parse_sweep(const std::string& arg, std::string& name, std::vector<double>& values) {
  const auto eq = arg.find('=');
  require_input(eq != std::string::npos && eq > 0 && eq + 1 < arg.size(),
                "--sweep expects NAME=v1,v2,... or NAME=lo:hi:n, got '" + arg + "'");
  name = arg.substr(0, eq);
  const std::string rest = arg.substr(eq + 1);
  values.clear();
  if (rest.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream ss(rest);
    for (std::string p; std::getline(ss, p, ':');) parts.push_back(p);
    require_input(parts.size() == 3,
                  "--sweep " + name + "=lo:hi:n needs three fields, got '" + rest + "'");
    const double lo = parse_number(parts[0], arg), hi = parse_number(parts[1], arg);
    const double n = parse_number(parts[2], arg);
    require_input(n >= 2 && n <= 1000 && n == std::floor(n),
                  "--sweep " + name + ": n must be an integer in 2..1000, got '" + parts[2] + "'");
    require_input(lo != 0 && hi != 0 && (lo > 0) == (hi > 0),
                  "--sweep " + name +
                      ": lo and hi of a log-spaced range must be non-zero and of "
                      "one sign, got " +
                      parts[0] + " and " + parts[1]);
    const double sign = lo > 0 ? 1.0 : -1.0;
    const double a = std::log(std::abs(lo)), b = std::log(std::abs(hi));
    for (int k = 0; k < static_cast<int>(n); ++k)
      values.push_back(sign * std::exp(a + (b - a) * k / (n - 1)));
  } else {
    const auto items = split_list(rest, "--sweep");
    for (const auto& it : items) values.push_back(parse_number(it, arg));
  }
}

std::optional<double> loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> lx, ly;
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k)
    if (x[k] != 0 && y[k] > 0 && std::isfinite(x[k]) && std::isfinite(y[k])) {
      lx.push_back(std::log(std::abs(x[k])));
      ly.push_back(std::log(y[k]));
    }
  return least_squares_slope(lx, ly);
}

namespace {

// The set-up of every value of the swept parameter (one without a sweep), each created and
// checked before the first run, so a bad value or an incompatible pair is reported at once.
std::vector<Setup> stability_setups(const StudyInputs& in, const StabilitySpec& spec,
                                    const std::vector<double>& values) {
  const bool sweep = !spec.sweep_param.empty();
  std::vector<Setup> setups;
  for (const double v : values) {
    Params p = spec.params;
    if (sweep) p.set(spec.sweep_param, format_full(v));
    setups.push_back(make_setup(in, in.integrators, p));
  }
  for (const auto& integ : setups.front().integrators)
    require_input(integ->supports_fixed_step(),
                  "--integrators: '" + integ->info().name +
                      "' is adaptive only: the stability study runs fixed steps");
  return setups;
}

// The log-log slopes of the measured and predicted h_max against the swept value, per integrator.
std::vector<StabilityResult::Fit> sweep_fits(const StabilitySpec& spec,
                                             const std::vector<StabilityRow>& rows) {
  std::vector<StabilityResult::Fit> fits;
  for (const auto& name : spec.integrators) {
    StabilityResult::Fit f;
    f.integrator = name;
    std::vector<double> xm, ym, xp, yp;
    for (const auto& r : rows) {
      if (r.integrator != name) continue;
      if (r.status == "ok" && r.h_measured) {
        xm.push_back(r.value);
        ym.push_back(*r.h_measured);
      }
      if (r.h_predicted && *r.h_predicted > 0) {
        xp.push_back(r.value);
        yp.push_back(*r.h_predicted);
      }
    }
    f.points = static_cast<int>(xm.size());
    f.measured_slope = loglog_slope(xm, ym);
    f.predicted_slope = loglog_slope(xp, yp);
    fits.push_back(f);
  }
  return fits;
}

}  // namespace

StabilityResult run_stability(const StudyInputs& in, const StabilitySpec& given,
                              std::ostream* progress) {
  const StabilitySpec spec = with_inputs(given, in);
  spec.validate();
  StabilityResult res;
  const bool sweep = !spec.sweep_param.empty();
  const std::vector<double> values = sweep ? spec.sweep_values : std::vector<double>{0.0};
  std::vector<Setup> setups = stability_setups(in, spec, values);
  // The criterion of every value too: --criterion energy with a value whose energy has an
  // arbitrary zero (--sweep gravity=0,1) is BadInput before the first value runs.
  std::vector<EnergyCriterion> criteria;
  for (const Setup& s : setups) criteria.push_back(energy_criterion(*s.model, spec));
  Progress prog(progress, "stability", static_cast<long>(values.size() * spec.integrators.size()));
  for (std::size_t iv = 0; iv < values.size(); ++iv) {
    Setup& s = setups[iv];
    const EnergyCriterion& criterion = criteria[iv];
    res.criterion = criterion.energy ? "energy" : "norm";
    res.criterion_note = criterion.not_used;
    const Vec y0 = perturbed_state(*s.model, spec);
    const Spectrum sp = spectrum_of(*s.model, s.model->initial_time(), y0, spec);
    res.spectrum_source = sp.source;
    require_input(sp.omega > 0 || spec.horizon,
                  "stability: model " + spec.model + " gives no spectrum (" + sp.source +
                      "), so the horizon cannot be set in periods of its fastest mode: give "
                      "--horizon T");
    std::optional<Spectrum> spe;
    if (s.model->has_imex_split()) {
      bool wanted = false;
      for (const auto& integ : s.integrators)
        wanted |= integ->explicit_part_stability().has_value();
      if (wanted) {
        spe = explicit_spectrum_of(*s.model, s.model->initial_time(), y0, spec);
        res.explicit_spectrum_source = spe->source;
      }
    }
    for (auto& integ : s.integrators) {
      const RowClock clock;  // --max-wall covers the row's whole bisection
      StabilityRow row =
          measure(*s.model, *integ, sp, spe ? &*spe : nullptr, y0, spec, criterion.energy);
      if (sweep) {
        row.param = spec.sweep_param;
        row.value = values[iv];
      }
      std::string what = row.integrator;
      if (sweep) what += ", " + row.param + " = " + num(row.value);
      what += ": " + row.status;
      if (row.h_measured) what += ", h_max = " + num(*row.h_measured);
      prog.tick(what);
      res.rows.push_back(std::move(row));
    }
  }
  if (sweep) res.fits = sweep_fits(spec, res.rows);
  return res;
}

namespace {

const StudyFunctions<StabilitySpec, StabilityResult> kStability{
    .run = [](const StudyInputs& in, const StabilitySpec& s,
              std::ostream* progress) { return run_stability(in, s, progress); },
    .unit_table = [](const StabilitySpec&, const StabilityResult& r) { return stability_table(r); },
    .write =
        [](const std::filesystem::path& dir, const StabilitySpec& s, const StabilityResult& r,
           const std::string& title, const PlotOptions& plot, std::ostream& err) {
          write_stability_outputs(dir, s, r);
          return plot_stability(dir / "stability.csv", title, plot, err);
        },
    .print_summary = print_stability_summary,
    .report_markdown = stability_report_markdown,
    .default_title = [](const StabilitySpec& s) { return "Stability limit: " + s.model; },
    .helpers = {}};

using StabilityJob = TypedStudyJob<StabilitySpec, StabilityResult>;

// The options of `stiffbench stability` (the flags, the spec-file keys and their defaults).
std::vector<ParamSpec> stability_options() {
  using P = ParamType;
  return {
      {"sweep", P::text, "",
       "repeat over a model parameter: NAME=v1,v2,... or NAME=lo:hi:n (n log-spaced values) and "
       "fit the log-log slope of h_max against it"},
      {"rel_tol", P::real, "0.001", "relative bisection tolerance on h_max", Bounds::in(0, 0.5)},
      {"periods", P::real, "500", "horizon of each run in periods 2*pi/omega of the fastest mode",
       Bounds::positive()},
      {"min_steps", P::integer, "200", "each run takes at least this many steps",
       Bounds::at_least(1)},
      {"horizon", P::real, "",
       "horizon of each run as a time (instead of --periods; needed when the model gives no "
       "spectrum)",
       Bounds::positive()},
      {"growth", P::real, "2",
       "mechanical systems: a run is unstable when its energy exceeds E0 + (growth - 1)|E0| at "
       "any step",
       Bounds::above(1)},
      {"criterion",
       P::text,
       "auto",
       "auto (energy for mechanical systems with an energy invariant whose zero is not "
       "arbitrary, else the norm: a cloth under gravity gets the norm), energy, or norm",
       {"auto", "energy", "norm"}},
      {"norm_growth", P::real, "10",
       "a run is unstable when its max-norm exceeds this factor times max(1, |y0|)",
       Bounds::above(1)},
      {"perturbation", P::real, "0.001",
       "relative random perturbation of the initial state that excites every mode",
       Bounds::in_closed_open(0, 1)},
      {"seed", P::integer, "1", "seed of the perturbation", Bounds::non_negative()},
      {"h_cap_factor", P::real, "1000",
       "largest step tried, in units of 2/omega (A-stable methods are reported stable_up_to it)",
       Bounds::above(1)},
      {"probe_unbounded", P::boolean, "false",
       "search the limit of methods predicted stable for every step too (doubling from 2/omega "
       "up to the largest step, bisection where one fails); by default they get one run at the "
       "largest step"},
      {"max_steps", P::integer, "20000000", "step budget of one run", Bounds::at_least(10)},
      {"ray",
       P::text,
       "auto",
       "where the stiffness() estimate is placed when the spectrum is not computed: auto "
       "(imaginary axis for mechanical systems, real axis otherwise), imag, real",
       {"auto", "imag", "real"}},
      {"dense_limit", P::integer, "600",
       "compute the exact spectrum (dense eigensolver) up to this dimension",
       Bounds::non_negative()}};
}

}  // namespace

StudyKind stability_study_kind() {
  StudyKind k;
  k.name = "stability";
  k.stem = "stability";
  k.summary =
      "largest stable fixed step h_max per integrator (bisection) against the linear-theory "
      "prediction from the system's spectrum; writes stability.{csv,md,json,png}";
  k.options = stability_options();
  k.unit_columns = stability_table(StabilityResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    StabilitySpec s = with_inputs(StabilitySpec{}, t);
    if (o.contains("sweep")) parse_sweep(o.text("sweep"), s.sweep_param, s.sweep_values);
    s.rel_tol = o.real("rel_tol");
    s.periods = o.real("periods");
    s.min_steps = o.integer("min_steps");
    if (o.contains("horizon")) s.horizon = o.real("horizon");
    s.energy_growth = o.real("growth");
    s.criterion = o.text("criterion");
    s.norm_growth = o.real("norm_growth");
    s.perturbation = o.real("perturbation");
    s.seed = static_cast<unsigned long>(o.integer("seed"));
    s.h_cap_factor = o.real("h_cap_factor");
    s.probe_unbounded = o.boolean("probe_unbounded");
    s.max_steps = o.integer("max_steps");
    s.ray = o.text("ray");
    s.dense_limit = static_cast<Index>(o.integer("dense_limit"));
    s.validate();
    return std::make_unique<StabilityJob>(kStability, t, std::move(s));
  };
  return k;
}

const StabilityResult& stability_result(const StudyJob& job) {
  return typed_result<StabilitySpec, StabilityResult>(job);
}

StabilityResult run_stability(const StabilitySpec& spec, std::ostream* progress) {
  return run_stability(inputs_of(spec), spec, progress);
}

StabilityResult stability_study(const StudyInputs& in, StabilitySpec spec,
                                const std::filesystem::path& dir, const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  spec.validate();
  StabilityJob job(kStability, in, std::move(spec));
  run_study_job(study_kind("stability"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
