#include "experiments/studies/fidelity.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <ostream>
#include <set>
#include <sstream>

#include "core/driver.hpp"
#include "core/ode_system.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/option_table.hpp"
#include "experiments/output/progress.hpp"
#include "experiments/studies/fidelity_modes.hpp"
#include "experiments/studies/fidelity_output.hpp"

namespace stiffbench {

using cd = std::complex<double>;

namespace {
constexpr double kRowFloor = 1e-280;  // equations whose terms underflowed carry no information
// Noisy (per-mode) fits use the steps while the mode is above 1e-4 of its largest value: below,
// the other modes' nonlinear coupling and the Newton tolerance are no longer small against it.
constexpr double kNoiseFloor = 1e-4;

// One least-squares fit of order p. normalize: every equation scaled to its largest term (exact
// data: geometric decay or growth over hundreds of orders of magnitude weighs every step alike),
// residual the largest scaled one; else the equations as they are (noisy data: early steps,
// where the signal is large, weigh most), residual relative to the largest term. Equations whose
// largest term is below floor × the series' largest are dropped (underflow, or noise).
std::optional<std::pair<Vec, double>> fit_order(const std::vector<std::vector<double>>& series,
                                                int skip, int p, bool normalize, double floor) {
  std::vector<std::pair<Vec, double>> rows;
  double top = 0.0;
  for (const auto& s : series) {
    double series_max = 0.0;
    for (double x : s)
      if (std::isfinite(x)) series_max = std::max(series_max, std::abs(x));
    const long n = static_cast<long>(s.size());
    for (long i = skip; i + p < n; ++i) {
      Vec row(p);
      double scale = std::abs(s[static_cast<std::size_t>(i + p)]);
      for (int j = 0; j < p; ++j) {
        row(j) = s[static_cast<std::size_t>(i + j)];
        scale = std::max(scale, std::abs(row(j)));
      }
      if (!std::isfinite(scale) || scale < kRowFloor || scale < floor * series_max) continue;
      const double w = normalize ? 1.0 / scale : 1.0;
      rows.emplace_back(row * w, s[static_cast<std::size_t>(i + p)] * w);
      top = std::max(top, scale * w);
    }
  }
  if (static_cast<long>(rows.size()) < 2 * p + 4) return std::nullopt;
  Mat a(static_cast<Index>(rows.size()), p);
  Vec b(static_cast<Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    a.row(static_cast<Index>(r)) = rows[r].first.transpose();
    b(static_cast<Index>(r)) = rows[r].second;
  }
  const Vec c = a.colPivHouseholderQr().solve(b);
  const double residual = (a * c - b).cwiseAbs().maxCoeff() / top;
  return std::make_pair(c, residual);
}
}  // namespace

RecurrenceFit fit_step_multiplier(const std::vector<std::vector<double>>& series, int skip,
                                  double tolerance, int order, double floor) {
  RecurrenceFit fit;
  for (int p = order > 0 ? order : 2; p <= (order > 0 ? order : 6); p += 2) {
    const auto f = order > 0 ? fit_order(series, skip, p, false, kNoiseFloor)
                             : fit_order(series, skip, p, true, floor);
    if (!f) {
      fit.reason =
          "too few samples above the noise floor (round-off or underflow) for a "
          "recurrence of order " +
          std::to_string(p);
      return fit;
    }
    fit.order = p;
    fit.residual = f->second;
    if (order == 0 && !(f->second <= tolerance)) continue;
    // Roots of ζ^p − Σ c_j ζ^j: eigenvalues of the companion matrix.
    Mat comp = Mat::Zero(p, p);
    for (int j = 0; j < p; ++j) comp(0, j) = f->first(p - 1 - j);
    for (int j = 1; j < p; ++j) comp(j, j - 1) = 1.0;
    const Eigen::EigenSolver<Mat> es(comp, false);
    Index best = 0;
    es.eigenvalues().cwiseAbs().maxCoeff(&best);
    const cd mu = es.eigenvalues()(best);
    fit.multiplier = mu.imag() < 0 ? std::conj(mu) : mu;
    fit.ok = true;
    return fit;
  }
  fit.reason = "no linear recurrence of order <= 6 fits the samples (residual " +
               format_short(fit.residual) + "): the run is not a fixed linear map";
  return fit;
}

namespace {

std::vector<double> parse_steps(const std::string& text);

// The options of `stiffbench fidelity`, bound to FidelitySpec's fields (defaults: its
// initialisers); the per-mode step list is read and recorded by its own functions.
const OptionTable<FidelitySpec>& fidelity_options() {
  static const OptionTable<FidelitySpec> table =
      OptionTable<FidelitySpec>()
          .add("nu_min", &FidelitySpec::nu_min, "smallest nu = h*omega", Bounds::positive())
          .add("nu_max", &FidelitySpec::nu_max, "largest nu", Bounds::positive())
          .add("curve_points", &FidelitySpec::curve_points, "nu values of the curve, log-spaced",
               Bounds::in(1, 10000))
          .add("measure", &FidelitySpec::measure,
               "also measure the curve on harmonic_oscillator (one run per nu)")
          .add("steps", &FidelitySpec::steps, "steps of each measured oscillator run",
               Bounds::in(40, 100000000))
          .add(
              ParamSpec{"h", ParamType::text, "",
                        "per-mode runs (--model): step sizes, comma-separated (default: nu = 0.1 "
                        "at the lowest and nu = 2 at the highest selected mode)"},
              [](const Params& o, FidelitySpec& s) {
                if (o.contains("h") && !o.text("h").empty()) s.h = parse_steps(o.text("h"));
              },
              [](const FidelitySpec& s, nlohmann::json& j) { j["h"] = s.h; })
          .add("modes", &FidelitySpec::modes, "lowest modes analysed (--model)",
               Bounds::in(1, 4000))
          .add("amplitude", &FidelitySpec::amplitude,
               "mode excitation relative to the RMS spread of the rest positions (--model)",
               Bounds::positive())
          .add("mode_steps", &FidelitySpec::mode_steps, "steps of each per-mode run (--model)",
               Bounds::in(40, 100000000));
  return table;
}

}  // namespace

void FidelitySpec::validate() const {
  require_input(!integrators.empty(), "--integrators: no integrator given");
  fidelity_options().check(*this);
  require_input(std::isfinite(nu_min) && std::isfinite(nu_max) && nu_min > 0 && nu_max > nu_min,
                "--nu-min/--nu-max: need 0 < nu_min < nu_max (got " + format_short(nu_min) + ", " +
                    format_short(nu_max) + ")");
  for (double x : h)
    require_input(std::isfinite(x) && x > 0, "--h: every step must be positive and finite");
  std::set<std::string> seen;
  for (const auto& n : integrators)
    require_input(seen.insert(n).second, "--integrators: '" + n + "' is listed twice");
}

nlohmann::json FidelitySpec::to_json() const {
  nlohmann::json j;
  j["integrators"] = integrators;
  j["model"] = model;
  j["params"] = params.values();
  fidelity_options().to_json(*this, j);
  return j;
}

namespace {

std::vector<double> nu_grid(const FidelitySpec& s) {
  std::vector<double> nu;
  const double l0 = std::log10(s.nu_min), l1 = std::log10(s.nu_max);
  for (int i = 0; i < s.curve_points; ++i)
    nu.push_back(s.curve_points == 1 ? s.nu_min
                                     : std::pow(10.0, l0 + (l1 - l0) * i / (s.curve_points - 1)));
  return nu;
}

// The user's parameters that the integrator `name` of `in` declares.
Params integrator_params(const StudyInputs& in, const std::string& name, const Params& user) {
  Params p;
  for (const auto& spec : in.integrator_entry(name).params)
    if (user.contains(spec.key)) p.set(spec.key, user.values().at(spec.key));
  return p;
}

// Every --param key must belong to the model (when given) or to one of the integrators.
void check_param_keys(const StudyInputs& in, const FidelitySpec& s) {
  std::set<std::string> keys;
  if (in.has_model())
    for (const auto& p : in.model_entry().params) keys.insert(p.key);
  for (const auto& n : s.integrators)
    for (const auto& p : in.integrator_entry(n).params) keys.insert(p.key);
  for (const auto& [key, value] : s.params.values())
    require_input(keys.count(key) != 0, "--param " + key + "=" + value +
                                            ": neither the model nor any of the integrators "
                                            "declares '" +
                                            key + "'");
}

// A system with one undamped linear mode on which a method's curve is measured: the deviation
// of dof `dof` from `rest` and its velocity are the samples; h = ν/ω.
struct TestOscillator {
  std::string label;
  std::unique_ptr<OdeSystem> sys;
  Index dof = 0;
  double rest = 0.0, omega = 1.0;
  // The deviation y(dof) − rest reaches its round-off (u·|rest|) long before it underflows:
  // equations below this fraction of the start are dropped.
  double floor = 0.0;
  double tolerance = 1e-8;  // of the exact fit
};

// harmonic_oscillator (m = k = 1, x0 = 1); for methods that need a spring network (xpbd,
// projective dynamics), a spring_chain of one free mass between two pinned ends (k = m = 1,
// springs along a line, so the force is linear in the displacement while the springs are not
// inverted): ω = 2 sin(π/4) = √2.
std::vector<TestOscillator> test_oscillators() {
  std::vector<TestOscillator> out;
  TestOscillator ho;
  ho.label = "harmonic_oscillator";
  ho.sys = model_registry().create("harmonic_oscillator", Params{}, nullptr);
  out.push_back(std::move(ho));
  TestOscillator chain;
  chain.label = "spring_chain n=1";
  chain.sys =
      model_registry().create("spring_chain", Params{{"n", "1"}, {"amplitude", "0.1"}}, nullptr);
  const auto rest =
      model_registry().create("spring_chain", Params{{"n", "1"}, {"mode", "0"}}, nullptr);
  chain.dof = 1;
  chain.rest = rest->initial_state()(1);
  chain.omega = std::sqrt(2.0);
  chain.tolerance = 1e-7;
  chain.floor = 1e-6;  // the coordinate 1's round-off 1e-16 is 1e-9 of a deviation of 1e-7
  out.push_back(std::move(chain));
  return out;
}

struct Samples {
  std::vector<double> x, v;
};

Samples run_samples(const TestOscillator& osc, Integrator& integ, double h, long steps) {
  Samples s;
  FixedStepOptions fopt;
  fopt.h = h;
  fopt.t_end = h * static_cast<double>(steps);
  fopt.outputs = steps;
  fopt.blowup_factor = 1e100;
  const Index n = static_cast<Index>(osc.sys->dimension() / 2);
  run_fixed_step(*osc.sys, integ, fopt, [&](double, CVecRef y) {
    s.x.push_back(y(osc.dof) - osc.rest);
    s.v.push_back(y(n + osc.dof));
  });
  return s;
}

void measure_oscillator(const StudyInputs& in, const FidelitySpec& spec, FidelityResult& out,
                        Progress& progress) {
  const std::vector<TestOscillator> oscillators = test_oscillators();
  const std::vector<double> nus = nu_grid(spec);
  for (const auto& name : spec.integrators) {
    const TestOscillator* osc = nullptr;
    std::string why;
    for (const auto& candidate : oscillators) {
      try {
        const auto probe = in.create_integrator(name, integrator_params(in, name, spec.params));
        check_compatible(probe->info(), *candidate.sys);
        require_input(probe->supports_fixed_step(), name + " has no fixed-step mode");
        osc = &candidate;
        break;
      } catch (const BadInput& e) {
        why += (why.empty() ? "" : "; ") + candidate.label + ": " + e.what();
      }
    }
    if (!osc) {
      out.skipped.emplace_back(name, why);
      for (std::size_t i = 0; i < nus.size(); ++i) progress.tick(name + ": skipped");
      continue;
    }
    out.measured_on.emplace_back(name, osc->label);
    for (double nu : nus) {
      auto integ = in.create_integrator(name, integrator_params(in, name, spec.params));
      const Samples s = run_samples(*osc, *integ, nu / osc->omega, spec.steps);
      const RecurrenceFit fit = fit_step_multiplier({s.x, s.v}, 8, osc->tolerance, 0, osc->floor);
      if (fit.ok)
        out.curve.push_back({name, "measured", oscillator_response(fit.multiplier, nu)});
      else
        out.unfitted.push_back({name, nu, fit.reason});
      progress.tick(name + ", nu = " + format_short(nu));
    }
  }
}
// Per integrator: its analytic values at ν = 0.1, 1 and 10 and the largest differences of its
// measured points from its analytic curve (FidelityResult::analytic).
void compare_with_analytic(const StudyInputs& in, const FidelitySpec& spec, FidelityResult& out) {
  for (const auto& name : spec.integrators) {
    const auto integ = in.create_integrator(name, integrator_params(in, name, spec.params));
    const auto stab = integ->linear_stability();
    FidelityResult::Analytic a;
    a.integrator = name;
    a.stability = stab.has_value();
    a.curve = stab && stab->mechanical_multiplier;
    for (const auto& p : out.curve) {
      if (p.integrator != name || p.source != "measured") continue;
      ++a.measured;
      if (!a.curve) continue;
      const auto an = *oscillator_response(*stab, p.r.nu);
      // Relative to max(1, A): a growing mode's A^N is measured to the run's relative precision.
      a.max_da = std::max(a.max_da, std::abs(p.r.amplification - an.amplification) /
                                        std::max(1.0, an.amplification));
      a.max_dtheta = std::max(a.max_dtheta, std::abs(p.r.phase - an.phase));
    }
    if (a.curve)
      for (double nu : {0.1, 1.0, 10.0})
        if (nu >= spec.nu_min && nu <= spec.nu_max)
          a.glance.push_back(*oscillator_response(*stab, nu));
    out.analytic.push_back(std::move(a));
  }
}

std::vector<double> parse_steps(const std::string& text) {
  std::vector<double> out;
  for (const auto& item : split_list(text, "--h")) {
    out.push_back(parse_real(item, "--h"));
    require_input(out.back() > 0, "--h: '" + item + "' is not a positive number");
  }
  return out;
}

}  // namespace

FidelitySpec with_rest_state(const StudyInputs& in, FidelitySpec spec,
                             std::vector<std::string>* applied) {
  if (spec.model.empty()) return spec;
  for (const auto& [key, value] : in.model_entry().info.rest_state)
    if (!spec.params.contains(key)) {
      spec.params.set(key, value);
      if (applied) applied->push_back(key + "=" + value);
    }
  return spec;
}

FidelityResult run_fidelity(const StudyInputs& in, const FidelitySpec& given,
                            std::ostream* progress) {
  FidelityResult out;
  const FidelitySpec spec = with_rest_state(in, with_inputs(given, in), &out.rest_state_applied);
  spec.validate();
  check_param_keys(in, spec);
  // Every refusal of the model (not mechanical, not at rest, damped) comes before any run.
  std::optional<fidelity_internal::ModalSetup> modal;
  if (!spec.model.empty()) modal = fidelity_internal::prepare_modes(in, spec);
  for (const auto& name : spec.integrators) {
    const auto integ = in.create_integrator(name, integrator_params(in, name, spec.params));
    const auto stab = integ->linear_stability();
    if (!stab || !stab->mechanical_multiplier) continue;
    for (double nu : nu_grid(spec))
      out.curve.push_back({name, "analytic", *oscillator_response(*stab, nu)});
  }
  if (spec.measure) {
    Progress prog(progress, "fidelity oscillator",
                  static_cast<long>(spec.integrators.size()) * spec.curve_points);
    measure_oscillator(in, spec, out, prog);
  }
  if (modal) fidelity_internal::run_modes(in, spec, *modal, out, progress);
  compare_with_analytic(in, spec, out);
  return out;
}

namespace {

const StudyFunctions<FidelitySpec, FidelityResult> kFidelity{
    .run = [](const StudyInputs& in, const FidelitySpec& s,
              std::ostream* progress) { return run_fidelity(in, s, progress); },
    .unit_table = [](const FidelitySpec&, const FidelityResult& r) { return fidelity_table(r); },
    .write = fidelity_internal::write_fidelity_outputs,
    .print_summary = fidelity_internal::print_fidelity_summary,
    .report_markdown = fidelity_internal::fidelity_report_markdown,
    .default_title =
        [](const FidelitySpec&) {
          return std::string("Numerical damping and period error per nu = h*omega");
        },
    .helpers = {}};

using FidelityJob = TypedStudyJob<FidelitySpec, FidelityResult>;

}  // namespace

StudyKind fidelity_study_kind() {
  StudyKind k;
  k.name = "fidelity";
  k.stem = "fidelity";
  k.summary =
      "numerical damping and period error per nu = h*omega: analytic from the coefficients, "
      "measured on harmonic_oscillator, and per mode of a mechanical --model; writes "
      "fidelity.{csv,md,json,png} (and modes.csv, modes.png)";
  k.model_required = false;
  k.options = fidelity_options().declarations();
  k.extra_files = {"modes.csv"};
  k.unit_columns = fidelity_table(FidelityResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    FidelitySpec s = with_inputs(FidelitySpec{}, t);
    fidelity_options().read(o, s);
    // The model's rest state is applied here, so that fidelity.json records the parameters run.
    s = with_rest_state(t, std::move(s));
    s.validate();
    return std::make_unique<FidelityJob>(kFidelity, t, std::move(s));
  };
  return k;
}

const FidelityResult& fidelity_result(const StudyJob& job) {
  return typed_result<FidelitySpec, FidelityResult>(job);
}

FidelityResult run_fidelity(const FidelitySpec& spec, std::ostream* progress) {
  return run_fidelity(inputs_of(spec), spec, progress);
}

FidelityResult fidelity_study(const StudyInputs& in, FidelitySpec spec,
                              const std::filesystem::path& dir, const StudyContext& ctx) {
  spec = with_rest_state(in, with_inputs(std::move(spec), in));
  spec.validate();
  FidelityJob job(kFidelity, in, std::move(spec));
  run_study_job(study_kind("fidelity"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
