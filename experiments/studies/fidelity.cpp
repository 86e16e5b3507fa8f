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
#include "experiments/output/progress.hpp"

namespace stiffbench {

namespace fs = std::filesystem;
using cd = std::complex<double>;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
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

void FidelitySpec::validate() const {
  require_input(!integrators.empty(), "--integrators: no integrator given");
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
  j["nu_min"] = nu_min;
  j["nu_max"] = nu_max;
  j["curve_points"] = curve_points;
  j["measure"] = measure;
  j["steps"] = steps;
  j["h"] = h;
  j["modes"] = modes;
  j["amplitude"] = amplitude;
  j["mode_steps"] = mode_steps;
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

// The user's parameters that `name` declares.
Params integrator_params(const std::string& name, const Params& user) {
  Params p;
  for (const auto& spec : integrator_registry().at(name).params)
    if (user.contains(spec.key)) p.set(spec.key, user.values().at(spec.key));
  return p;
}

// Every --param key must belong to the model (when given) or to one of the integrators.
void check_param_keys(const FidelitySpec& s) {
  std::set<std::string> keys;
  if (!s.model.empty())
    for (const auto& p : model_registry().at(s.model).params) keys.insert(p.key);
  for (const auto& n : s.integrators)
    for (const auto& p : integrator_registry().at(n).params) keys.insert(p.key);
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

void measure_oscillator(const FidelitySpec& spec, FidelityResult& out, Progress& progress) {
  const std::vector<TestOscillator> oscillators = test_oscillators();
  const std::vector<double> nus = nu_grid(spec);
  for (const auto& name : spec.integrators) {
    const TestOscillator* osc = nullptr;
    std::string why;
    for (const auto& candidate : oscillators) {
      try {
        const auto probe =
            integrator_registry().create(name, integrator_params(name, spec.params), nullptr);
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
      auto integ =
          integrator_registry().create(name, integrator_params(name, spec.params), nullptr);
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

// ---- Modes of a mechanical model ----------------------------------------------------------

struct ModalBasis {
  Vec x0;
  std::vector<Index> free;  // dofs not fixed
  Vec mass;                 // of the free dofs
  Mat phi;                  // free × modes, M-orthonormal columns
  Vec omega;                // per mode
  double omega_max = 0.0;   // the system's fastest mode
};

ModalBasis modal_basis(const MechanicalSystem& mech, const FidelitySpec& spec) {
  const std::string who = "fidelity --model " + spec.model + ": ";
  require_input(mech.has_force_jacobians(),
                who + "needs the force Jacobian K = da/dx (the model has none)");
  ModalBasis b;
  const Vec y0 = mech.initial_state();
  const Index n = mech.dofs();
  b.x0 = y0.head(n);
  const Vec v0 = Vec::Zero(n);
  std::set<Index> fixed;
  for (Index i : mech.fixed_dofs()) fixed.insert(i);
  for (Index i = 0; i < n; ++i)
    if (!fixed.count(i)) b.free.push_back(i);
  const Index m = static_cast<Index>(b.free.size());
  require_input(m <= 4000, who +
                               "the dense modal analysis is limited to 4000 free dofs (the "
                               "model has " +
                               std::to_string(m) + ")");
  SparseMat k, d;
  mech.force_jacobians(0.0, b.x0, v0, k, d);
  require_input(d.norm() == 0.0, who +
                                     "the model is damped at rest (D = da/dv != 0): the "
                                     "modal curves are those of the undamped oscillator; "
                                     "switch its damping off");
  Vec yr(2 * n);
  yr << b.x0, v0;
  Vec f(2 * n);
  mech.rhs(0.0, yr, f);
  const double acc = f.tail(n).cwiseAbs().maxCoeff();
  const Mat kd = Mat(k);
  const double scale = (kd * b.x0).cwiseAbs().maxCoeff() + kd.cwiseAbs().maxCoeff();
  std::string rest;
  for (const auto& [key, value] : model_registry().at(spec.model).info.rest_state)
    rest += (rest.empty() ? "" : ", ") + key + "=" + value;
  require_input(
      acc <= 1e-9 * std::max(scale, 1.0),
      who + "the initial state is not at rest (max |a| = " + format_short(acc) +
          "): the modes are those of an equilibrium; start the model at rest by "
          "setting what loads or displaces it to 0 (" +
          (rest.empty() ? "gravity, perturbation, an excited mode" : "its rest state: " + rest) +
          ")");
  const Vec masses = mech.masses();
  b.mass.resize(m);
  Mat a(m, m);
  for (Index i = 0; i < m; ++i) {
    b.mass(i) = masses(b.free[static_cast<std::size_t>(i)]);
    for (Index j = 0; j < m; ++j)
      a(i, j) = -kd(b.free[static_cast<std::size_t>(i)], b.free[static_cast<std::size_t>(j)]);
  }
  // −M K is symmetric for forces with a potential; symmetrise against round-off, then solve
  // the symmetric problem S ψ = ω² ψ with S = M^{1/2}(−K)M^{-1/2}, φ = M^{-1/2} ψ.
  const Vec sq = b.mass.cwiseSqrt();
  Mat s = sq.asDiagonal() * a * sq.cwiseInverse().asDiagonal();
  s = 0.5 * (s + s.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Mat> es(s);
  require_input(es.info() == Eigen::Success, who + "the eigensolver failed");
  const double top = std::max(es.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
  b.omega_max = std::sqrt(std::max(es.eigenvalues().maxCoeff(), 0.0));
  std::vector<Index> chosen;
  for (Index i = 0; i < m && static_cast<int>(chosen.size()) < spec.modes; ++i)
    if (es.eigenvalues()(i) > 1e-12 * top) chosen.push_back(i);
  require_input(!chosen.empty(), who + "no mode with omega > 0");
  b.phi.resize(m, static_cast<Index>(chosen.size()));
  b.omega.resize(static_cast<Index>(chosen.size()));
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    b.phi.col(static_cast<Index>(c)) =
        sq.cwiseInverse().asDiagonal() * es.eigenvectors().col(chosen[c]);
    b.omega(static_cast<Index>(c)) = std::sqrt(es.eigenvalues()(chosen[c]));
  }
  return b;
}

// The per-mode runs of one integrator at one step.
void measure_modes(const MechanicalSystem& mech, const ModalBasis& b, Integrator& integ,
                   const std::string& name, double h, const FidelitySpec& spec,
                   FidelityResult& out) {
  const Index n = mech.dofs(), nm = b.phi.cols();
  const Vec y0 = mech.initial_state();
  const double mean = b.x0.mean();
  const double spread = std::sqrt((b.x0.array() - mean).square().mean());
  const double eps = spec.amplitude * (spread > 0 ? spread : 1.0);
  Vec start = y0;
  start.tail(n).setZero();
  for (Index c = 0; c < nm; ++c) {
    const double inf = b.phi.col(c).cwiseAbs().maxCoeff();
    for (std::size_t i = 0; i < b.free.size(); ++i)
      start(b.free[i]) += eps * b.phi(static_cast<Index>(i), c) / inf;
  }
  std::vector<std::vector<double>> q(static_cast<std::size_t>(nm)), p(static_cast<std::size_t>(nm));
  FixedStepOptions fopt;
  fopt.h = h;
  fopt.t_end = h * static_cast<double>(spec.mode_steps);
  fopt.outputs = spec.mode_steps;
  fopt.blowup_factor = 1e100;
  Vec dx(static_cast<Index>(b.free.size())), v(static_cast<Index>(b.free.size()));
  const RunResult res = run_fixed_step_from(mech, integ, 0.0, start, fopt, [&](double, CVecRef y) {
    for (std::size_t i = 0; i < b.free.size(); ++i) {
      dx(static_cast<Index>(i)) = y(b.free[i]) - b.x0(b.free[i]);
      v(static_cast<Index>(i)) = y(n + b.free[i]);
    }
    const Vec mq = b.phi.transpose() * b.mass.cwiseProduct(dx);
    const Vec mp = b.phi.transpose() * b.mass.cwiseProduct(v);
    for (Index c = 0; c < nm; ++c) {
      q[static_cast<std::size_t>(c)].push_back(mq(c));
      p[static_cast<std::size_t>(c)].push_back(mp(c));
    }
  });
  const auto stab = integ.linear_stability();
  for (Index c = 0; c < nm; ++c) {
    ModePoint mp;
    mp.integrator = name;
    mp.h = h;
    mp.mode = static_cast<int>(c + 1);
    mp.omega = b.omega(c);
    const double nu = h * mp.omega;
    if (stab) mp.predicted = oscillator_response(*stab, nu);
    // The order of the recurrence is known for methods with stability data (2 × the state
    // state_levels); the fit is then least squares over the nonlinear and solver noise of the run.
    const int state_levels = stab ? stab->state_levels : 0;
    if (res.stats.status != Status::ok) {
      mp.note = "run " + to_string(res.stats.status) +
                " at this h (nu = " + format_short(h * b.omega_max) +
                " on the fastest mode of the system)";
    } else {
      const RecurrenceFit fit =
          fit_step_multiplier({q[static_cast<std::size_t>(c)], p[static_cast<std::size_t>(c)]},
                              2 * std::max(state_levels, 1), 1e-4, 2 * state_levels);
      if (fit.ok)
        mp.measured = oscillator_response(fit.multiplier, nu);
      else
        mp.note = fit.reason;
    }
    if (!stab) mp.note += (mp.note.empty() ? "" : "; ") + std::string("no stability data");
    out.modes.push_back(std::move(mp));
  }
}

// The model, its integrators and its modes, checked and computed before anything runs.
struct ModalSetup {
  Setup setup;
  const MechanicalSystem* mech = nullptr;
  ModalBasis basis;
};

ModalSetup prepare_modes(const FidelitySpec& spec) {
  ModalSetup m;
  m.setup = make_setup(spec.model, spec.integrators, spec.params);
  m.mech = dynamic_cast<const MechanicalSystem*>(m.setup.model.get());
  require_input(m.mech != nullptr, "fidelity --model " + spec.model +
                                       ": per-mode analysis needs a mechanical model (y = [x; v])");
  m.basis = modal_basis(*m.mech, spec);
  return m;
}

void run_modes(const FidelitySpec& spec, const ModalSetup& m, FidelityResult& out,
               std::ostream* progress) {
  const ModalBasis& b = m.basis;
  std::vector<double> hs = spec.h;
  const double top = b.omega(b.omega.size() - 1);
  if (hs.empty()) hs = {0.1 / b.omega(0), 2.0 / top};
  out.mode_steps_used = hs;
  Progress prog(progress, "fidelity modes", static_cast<long>(hs.size() * spec.integrators.size()));
  for (std::size_t i = 0; i < spec.integrators.size(); ++i) {
    for (double h : hs) {
      auto integ = integrator_registry().create(spec.integrators[i], spec.params, nullptr);
      measure_modes(*m.mech, b, *integ, spec.integrators[i], h, spec, out);
      prog.tick(spec.integrators[i] + ", h = " + format_short(h));
    }
  }
}

}  // namespace

FidelitySpec with_rest_state(FidelitySpec spec, std::vector<std::string>* applied) {
  if (spec.model.empty()) return spec;
  for (const auto& [key, value] : model_registry().at(spec.model).info.rest_state)
    if (!spec.params.contains(key)) {
      spec.params.set(key, value);
      if (applied) applied->push_back(key + "=" + value);
    }
  return spec;
}

FidelityResult run_fidelity(const FidelitySpec& user_spec, std::ostream* progress) {
  const FidelitySpec spec = with_rest_state(user_spec);
  spec.validate();
  for (const auto& n : spec.integrators) integrator_registry().at(n);
  if (!spec.model.empty()) model_registry().at(spec.model);
  check_param_keys(spec);
  // Every refusal of the model (not mechanical, not at rest, damped) comes before any run.
  std::optional<ModalSetup> modal;
  if (!spec.model.empty()) modal = prepare_modes(spec);
  FidelityResult out;
  for (const auto& name : spec.integrators) {
    const auto integ =
        integrator_registry().create(name, integrator_params(name, spec.params), nullptr);
    const auto stab = integ->linear_stability();
    if (!stab || !stab->mechanical_multiplier) continue;
    for (double nu : nu_grid(spec))
      out.curve.push_back({name, "analytic", *oscillator_response(*stab, nu)});
  }
  if (spec.measure) {
    Progress prog(progress, "fidelity oscillator",
                  static_cast<long>(spec.integrators.size()) * spec.curve_points);
    measure_oscillator(spec, out, prog);
  }
  if (modal) run_modes(spec, *modal, out, progress);
  return out;
}

Table fidelity_table(const FidelityResult& r) {
  Table t;
  t.columns = {"integrator",      "nu",    "amplification", "damping_ratio", "period_error",
               "frequency_error", "source"};
  for (const auto& p : r.curve)
    t.rows.push_back({p.integrator, format_full(p.r.nu), format_full(p.r.amplification),
                      format_full(p.r.damping_ratio), format_full(p.r.period_error),
                      format_full(p.r.frequency_error), p.source});
  return t;
}

namespace {
std::string opt_field(const std::optional<OscillatorResponse>& r,
                      double OscillatorResponse::*field) {
  return r ? format_full((*r).*field) : "";
}
// |measured − predicted| / max(|predicted|, floor): relative, and absolute below `floor` (an
// undamped method's damping ratio is 0 up to the run's noise).
double rel_diff(double measured, double predicted, double floor = 0.0) {
  return std::abs(measured - predicted) / std::max(std::abs(predicted), floor);
}
constexpr double kDampingFloor = 1e-4;
}  // namespace

Table modes_table(const FidelityResult& r) {
  Table t;
  t.columns = {"integrator",
               "h",
               "mode",
               "omega",
               "nu",
               "amplification_measured",
               "amplification_predicted",
               "damping_ratio_measured",
               "damping_ratio_predicted",
               "period_error_measured",
               "period_error_predicted",
               "damping_rel_diff",
               "frequency_rel_diff",
               "note"};
  for (const auto& m : r.modes) {
    std::string dd, fd;
    if (m.measured && m.predicted) {
      dd = format_full(
          rel_diff(m.measured->damping_ratio, m.predicted->damping_ratio, kDampingFloor));
      fd = format_full(rel_diff(m.measured->phase, m.predicted->phase));
    }
    using R = OscillatorResponse;
    t.rows.push_back(
        {m.integrator, format_full(m.h), std::to_string(m.mode), format_full(m.omega),
         format_full(m.h * m.omega), opt_field(m.measured, &R::amplification),
         opt_field(m.predicted, &R::amplification), opt_field(m.measured, &R::damping_ratio),
         opt_field(m.predicted, &R::damping_ratio), opt_field(m.measured, &R::period_error),
         opt_field(m.predicted, &R::period_error), dd, fd, m.note});
  }
  return t;
}

namespace {

// Per integrator: the largest |A_measured − A_analytic| and |θ_measured − θ_analytic| over the
// measured points (the analytic value recomputed at the measured ν).
Table agreement_table(const FidelitySpec& spec, const FidelityResult& r) {
  Table t;
  t.columns = {"integrator",       "measured on",  "measured points",
               "max dA/max(1, A)", "max d(theta)", "on the curve"};
  for (const auto& name : spec.integrators) {
    const auto integ =
        integrator_registry().create(name, integrator_params(name, spec.params), nullptr);
    const auto stab = integ->linear_stability();
    long count = 0;
    double da = 0, dt = 0;
    for (const auto& p : r.curve) {
      if (p.integrator != name || p.source != "measured") continue;
      ++count;
      if (!stab || !stab->mechanical_multiplier) continue;
      const auto a = *oscillator_response(*stab, p.r.nu);
      // Relative to max(1, A): a growing mode's A^N is measured to the run's relative precision.
      da = std::max(da,
                    std::abs(p.r.amplification - a.amplification) / std::max(1.0, a.amplification));
      dt = std::max(dt, std::abs(p.r.phase - a.phase));
    }
    std::string verdict = "no stability data (measured only)";
    if (stab && stab->mechanical_multiplier)
      verdict = count == 0 ? "not measured" : (da <= 1e-6 && dt <= 1e-6 ? "yes" : "NO");
    for (const auto& [n, why] : r.skipped)
      if (n == name) verdict = "not measured: " + why;
    std::string on;
    for (const auto& [n, label] : r.measured_on)
      if (n == name) on = label;
    t.rows.push_back({name, on, std::to_string(count), stab && count ? format_short(da) : "",
                      stab && count ? format_short(dt) : "", verdict});
  }
  return t;
}

// Per integrator and step: the largest relative differences over the modes, and whether every
// mode is within 5%.
Table mode_summary(const FidelityResult& r) {
  Table t;
  t.columns = {
      "integrator", "h", "modes", "nu range", "max damping rel diff", "max frequency rel diff",
      "within 5%"};
  std::vector<std::pair<std::string, double>> keys;
  for (const auto& m : r.modes)
    if (std::find(keys.begin(), keys.end(), std::make_pair(m.integrator, m.h)) == keys.end())
      keys.emplace_back(m.integrator, m.h);
  for (const auto& [name, h] : keys) {
    double dd = 0, fd = 0, lo = kNaN, hi = kNaN;
    long count = 0, compared = 0;
    for (const auto& m : r.modes) {
      if (m.integrator != name || m.h != h) continue;
      ++count;
      const double nu = h * m.omega;
      lo = std::isnan(lo) ? nu : std::min(lo, nu);
      hi = std::isnan(hi) ? nu : std::max(hi, nu);
      if (!m.measured || !m.predicted) continue;
      ++compared;
      dd = std::max(dd,
                    rel_diff(m.measured->damping_ratio, m.predicted->damping_ratio, kDampingFloor));
      fd = std::max(fd, rel_diff(m.measured->phase, m.predicted->phase));
    }
    const bool ok = compared == count && dd <= 0.05 && fd <= 0.05;
    t.rows.push_back({name, format_short(h), std::to_string(count),
                      format_short(lo) + " - " + format_short(hi), compared ? format_short(dd) : "",
                      compared ? format_short(fd) : "",
                      compared == count ? (ok ? "yes" : "NO") : "not compared"});
  }
  return t;
}

// The analytic values at ν = 0.1, 1 and 10 (those inside the range), per integrator.
Table glance_table(const FidelitySpec& spec) {
  Table t;
  t.columns = {"integrator", "nu", "amplification", "damping ratio", "period error"};
  for (const auto& name : spec.integrators) {
    const auto integ =
        integrator_registry().create(name, integrator_params(name, spec.params), nullptr);
    const auto stab = integ->linear_stability();
    if (!stab || !stab->mechanical_multiplier) continue;
    for (double nu : {0.1, 1.0, 10.0}) {
      if (nu < spec.nu_min || nu > spec.nu_max) continue;
      const auto a = *oscillator_response(*stab, nu);
      t.rows.push_back({name, format_short(nu), format_short(a.amplification, 6),
                        format_short(a.damping_ratio, 4), format_short(a.period_error, 4)});
    }
  }
  return t;
}

// One line per integrator and reason: the points whose runs the recurrence did not fit.
std::string unfitted_summary(const FidelityResult& r) {
  std::ostringstream md;
  for (std::size_t i = 0; i < r.unfitted.size();) {
    std::size_t j = i;
    double lo = r.unfitted[i].nu, hi = lo;
    while (j < r.unfitted.size() && r.unfitted[j].integrator == r.unfitted[i].integrator &&
           r.unfitted[j].reason == r.unfitted[i].reason) {
      lo = std::min(lo, r.unfitted[j].nu);
      hi = std::max(hi, r.unfitted[j].nu);
      ++j;
    }
    md << "- " << r.unfitted[i].integrator << ": " << (j - i) << " point(s) not measured (nu "
       << format_short(lo) << (j - i > 1 ? " to " + format_short(hi) : std::string())
       << "): " << r.unfitted[i].reason << "\n";
    i = j;
  }
  if (!r.unfitted.empty()) md << "\n";
  return md.str();
}

std::string param_list(const Params& p) {
  std::string out;
  for (const auto& [k, v] : p.values()) out += (out.empty() ? "" : ", ") + k + "=" + v;
  return out.empty() ? "the defaults" : out;
}

std::string markdown(const FidelitySpec& spec, const FidelityResult& r) {
  std::ostringstream md;
  md << "# Fidelity: numerical damping and period error\n\n"
     << "Undamped oscillator at nu = h*omega; per step the mode is multiplied by mu = A "
        "e^{i theta} (exact: e^{i nu}). amplification A, damping ratio -ln(A)/theta, period "
        "error nu/theta - 1 (Hilber, Hughes & Taylor 1977). Analytic from the coefficients; "
        "measured from "
     << spec.steps
     << "-step runs on harmonic_oscillator (spring_chain n=1 for methods that need springs) "
        "by a recurrence fit.\n\n"
     << "## Analytic values\n\n"
     << glance_table(spec).to_markdown() << "\n"
     << "## Measured against analytic\n\n"
     << agreement_table(spec, r).to_markdown() << "\n";
  md << unfitted_summary(r);
  if (!r.modes.empty()) {
    md << "## Modes of " << spec.model << "\n\n"
       << "The lowest " << spec.modes
       << " modes of -M K phi = omega^2 M phi at rest (parameters: " << param_list(spec.params)
       << "; the model's rest state, shown by `describe`, fills the loads not given); measured "
          "by projecting one run per step on each mode.\n\n"
       << mode_summary(r).to_markdown() << "\n";
  }
  return md.str();
}

bool plot_fidelity(const fs::path& dir, const std::string& title, const PlotOptions& plot,
                   std::ostream& err, const std::vector<std::string>& integrators, bool modes) {
  const std::vector<PlotPanel> panels = {{"numerical damping ratio -ln(A)/theta", integrators},
                                         {"|period error| nu/theta - 1", integrators}};
  bool drew =
      run_plot("fidelity.gp", dir / "fidelity",
               {{"csvfile", (dir / "fidelity.csv").string()}, {"ttl", title}}, panels, plot, err);
  if (modes)
    drew = run_plot("fidelity_modes.gp", dir / "modes",
                    {{"csvfile", (dir / "modes.csv").string()}, {"ttl", title + ": modes"}}, panels,
                    plot, err) &&
           drew;
  return drew;
}

class FidelityJob : public StudyJob {
 public:
  // The model's rest state is applied here, so that fidelity.json records the parameters run.
  explicit FidelityJob(FidelitySpec spec) : spec_(with_rest_state(std::move(spec), &rest_)) {
    spec_.validate();
  }
  nlohmann::json spec_json() const override { return spec_.to_json(); }
  void run(std::ostream* progress) override { result_ = run_fidelity(spec_, progress); }
  Table unit_table() const override { return fidelity_table(result_); }
  bool write(const fs::path& dir, const std::string& title, const PlotOptions& plot,
             std::ostream& err) const override {
    write_file_atomic(dir / "fidelity.csv", fidelity_table(result_).to_csv());
    write_file_atomic(dir / "modes.csv",
                      modes_table(result_).to_csv());  // header only without --model
    write_file_atomic(dir / "fidelity.md", markdown(spec_, result_));
    nlohmann::json meta = run_metadata("fidelity", spec_.to_json());
    meta["rest_state_applied"] = rest_;
    meta["mode_steps_used"] = result_.mode_steps_used;
    nlohmann::json skipped = nlohmann::json::object();
    for (const auto& [n, why] : result_.skipped) skipped[n] = why;
    meta["not_measured"] = skipped;
    write_file_atomic(dir / "fidelity.json", meta.dump(2) + "\n");
    return plot_fidelity(dir, title, plot, err, spec_.integrators, !spec_.model.empty());
  }
  void print_summary(std::ostream& out) const override {
    if (!rest_.empty()) out << rest_note() << "\n\n";
    out << agreement_table(spec_, result_).to_markdown();
    if (!result_.modes.empty()) out << "\n" << mode_summary(result_).to_markdown();
  }
  std::string report_markdown(const std::string& note) const override {
    std::string md = note + "\n\n" + glance_table(spec_).to_markdown() + "\n" +
                     agreement_table(spec_, result_).to_markdown() + "\n" +
                     unfitted_summary(result_);
    if (!result_.modes.empty())
      md += "Per mode of " + spec_.model + " (modes.png, modes.csv):\n\n" +
            mode_summary(result_).to_markdown() + "\n";
    return md;
  }
  std::string default_title() const override {
    return "Numerical damping and period error per nu = h*omega";
  }
  const FidelityResult& result() const { return result_; }

 private:
  std::string rest_note() const {
    std::string list;
    for (const auto& kv : rest_) list += (list.empty() ? "" : ", ") + kv;
    return "Modes of " + spec_.model + " at its rest state: " + list +
           " applied (the defaults load or displace it; the modes are those of an equilibrium).";
  }
  std::vector<std::string> rest_;  // key=value of the model's rest state the user did not set
  FidelitySpec spec_;
  FidelityResult result_;
};

std::vector<double> parse_steps(const std::string& text) {
  std::vector<double> out;
  for (const auto& item : split_list(text, "--h")) {
    out.push_back(parse_real(item, "--h"));
    require_input(out.back() > 0, "--h: '" + item + "' is not a positive number");
  }
  return out;
}

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
  k.options = {
      {"nu_min", ParamType::real, "0.01", "smallest nu = h*omega", Bounds::positive()},
      {"nu_max", ParamType::real, "100", "largest nu", Bounds::positive()},
      {"curve_points", ParamType::integer, "41", "nu values of the curve, log-spaced",
       Bounds::in(1, 10000)},
      {"measure", ParamType::boolean, "true",
       "also measure the curve on harmonic_oscillator (one run per nu)"},
      {"steps", ParamType::integer, "400", "steps of each measured oscillator run",
       Bounds::in(40, 100000000)},
      {"h", ParamType::text, "",
       "per-mode runs (--model): step sizes, comma-separated (default: nu = 0.1 at the lowest "
       "and nu = 2 at the highest selected mode)"},
      {"modes", ParamType::integer, "20", "lowest modes analysed (--model)", Bounds::in(1, 4000)},
      {"amplitude", ParamType::real, "1e-7",
       "mode excitation relative to the RMS spread of the rest positions (--model)",
       Bounds::positive()},
      {"mode_steps", ParamType::integer, "400", "steps of each per-mode run (--model)",
       Bounds::in(40, 100000000)}};
  k.extra_files = {"modes.csv"};
  k.unit_columns = fidelity_table(FidelityResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    FidelitySpec s;
    s.integrators = t.integrators;
    s.model = t.model;
    s.params = t.params;
    s.nu_min = o.real("nu_min");
    s.nu_max = o.real("nu_max");
    s.curve_points = static_cast<int>(o.integer("curve_points"));
    s.measure = o.boolean("measure");
    s.steps = o.integer("steps");
    if (o.contains("h") && !o.text("h").empty()) s.h = parse_steps(o.text("h"));
    s.modes = static_cast<int>(o.integer("modes"));
    s.amplitude = o.real("amplitude");
    s.mode_steps = o.integer("mode_steps");
    return std::make_unique<FidelityJob>(std::move(s));
  };
  return k;
}

const FidelityResult& fidelity_result(const StudyJob& job) {
  return dynamic_cast<const FidelityJob&>(job).result();
}

}  // namespace stiffbench
