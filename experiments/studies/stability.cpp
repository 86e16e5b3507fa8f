#include "experiments/studies/stability.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <limits>
#include <numbers>
#include <ostream>
#include <random>
#include <sstream>

#include "core/driver.hpp"
#include "core/theory/linear_stability.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/output/progress.hpp"

namespace stiffbench {

namespace {

using cd = std::complex<double>;

std::string num(double x) { return format_short(x, 4); }

double parse_number(const std::string& s, const std::string& what) {
  return parse_real(s, "--sweep " + what);
}

// The spectrum linear theory is evaluated on.
struct Spectrum {
  std::vector<cd> eigenvalues;
  double omega = 0;    // largest modulus (0: unknown)
  std::string source;  // how it was obtained
  // f_E's spectrum on a mechanical split (core/ode_system.hpp: a = a_E + a_I with x' = v in
  // f_I): the explicit acceleration's modes under x' = v, tested on the partitioned map.
  bool mechanical_split = false;
};

// The eigenvalues of a dense Jacobian into `s`; none when the matrix has an inf or NaN entry (an
// overflowing coefficient): the eigensolver's output is then meaningless, finite or not (heat_2d
// with ν = 1e308 on a 4×4 grid gave finite values with a positive real part), so `s.source`
// says why instead.
void dense_eigenvalues(const Mat& j, Spectrum& s) {
  if (!j.allFinite()) {
    s.source = "none: not finite (" + s.source + ": the matrix has inf or NaN entries)";
    return;
  }
  const Eigen::EigenSolver<Mat> es(j, false);
  for (Index k = 0; k < j.rows(); ++k) s.eigenvalues.push_back(es.eigenvalues()(k));
}

// A spectrum with a non-finite eigenvalue (an overflowing stiffness() estimate) predicts nothing:
// it is cleared, its source saying why. Kept, the ray of an infinite eigenvalue would be NaN and
// its limit read as "unbounded".
void drop_non_finite(Spectrum& s) {
  for (const cd& l : s.eigenvalues)
    if (!std::isfinite(l.real()) || !std::isfinite(l.imag())) {
      const std::string z = l.imag() == 0 ? num(l.real())
                                          : num(l.real()) + (l.imag() < 0 ? " - " : " + ") +
                                                num(std::abs(l.imag())) + "i";
      s.source = "none: not finite (" + s.source + "; eigenvalue " + z + ")";
      s.eigenvalues.clear();
      return;
    }
}

Spectrum spectrum_of(const OdeSystem& sys, double t0, const Vec& y0, const StabilitySpec& spec) {
  Spectrum s;
  const Index n = sys.dimension();
  const bool mechanical = sys.as_mechanical() != nullptr;
  // Exact spectrum from an analytic Jacobian; else the model's own stiffness estimate (a
  // finite-difference spectrum of a particle model is dominated by its physical and round-off
  // modes, e.g. SPH pairing, and predicts nothing useful); else finite differences.
  const std::optional<double> rho = sys.stiffness(t0, y0);
  if (n <= spec.dense_limit && (sys.has_jacobian() || !rho)) {
    Mat j(n, n);
    if (sys.has_jacobian()) {
      SparseMat sj;
      sys.jacobian(t0, y0, sj);
      j = Mat(sj);
      s.source = "eigenvalues of the analytic Jacobian at the perturbed initial state";
    } else {
      Vec f0(n), f1(n), y = y0;
      sys.rhs(t0, y0, f0);
      for (Index c = 0; c < n; ++c) {
        const double d = 1e-7 * std::max(1.0, std::abs(y0(c)));
        y(c) = y0(c) + d;
        sys.rhs(t0, y, f1);
        j.col(c) = (f1 - f0) / d;
        y(c) = y0(c);
      }
      s.source = "eigenvalues of a finite-difference Jacobian at the perturbed initial state";
    }
    dense_eigenvalues(j, s);
  } else if (rho) {
    const std::string ray = spec.ray == "auto" ? (mechanical ? "imag" : "real") : spec.ray;
    if (ray == "imag") {
      s.eigenvalues = {cd(0, *rho), cd(0, -*rho)};
      s.source = "stiffness() estimate " + num(*rho) + " on the imaginary axis (undamped modes)";
    } else {
      s.eigenvalues = {cd(-*rho, 0)};
      s.source = "stiffness() estimate " + num(*rho) + " on the negative real axis (decay)";
    }
  } else {
    s.source = "none (dimension " + std::to_string(n) + " above the dense limit " +
               std::to_string(spec.dense_limit) + " and no stiffness() estimate)";
  }
  drop_non_finite(s);
  for (const cd& l : s.eigenvalues) s.omega = std::max(s.omega, std::abs(l));
  int growing = 0;
  for (const cd& l : s.eigenvalues)
    if (l.real() > kGrowingModeTolerance * s.omega) ++growing;
  if (growing > 0)
    s.source += "; " + std::to_string(growing) +
                " eigenvalues with positive real part (modes the model itself lets grow, e.g. "
                "buckling of compressed springs) are left out of the prediction";
  return s;
}

// The spectrum of ∂f_E/∂y of a split model: the eigenvalues of J - J_I when both are analytic and
// the dimension is at most the dense limit, else the model's explicit_part_spectrum() estimate.
// On a mechanical split the explicit acceleration's oscillation under x' = v: the eigenvalues of
// [[0, I], [∂a_E/∂x, ∂a_E/∂v]] (J_E itself is nilpotent in x when x' = v is in f_I).
Spectrum explicit_spectrum_of(const OdeSystem& sys, double t0, const Vec& y0,
                              const StabilitySpec& spec) {
  Spectrum s;
  s.mechanical_split = sys.as_mechanical() != nullptr;
  const Index n = sys.dimension();
  if (n <= spec.dense_limit && sys.has_jacobian() && sys.has_implicit_part_jacobian()) {
    SparseMat j, ji;
    sys.jacobian(t0, y0, j);
    sys.implicit_part_jacobian(t0, y0, ji);
    Mat je = Mat(j) - Mat(ji);
    if (s.mechanical_split) {
      const Index d = n / 2;
      je.topRows(d).setZero();
      je.topRightCorner(d, d).setIdentity();
    }
    s.source = !s.mechanical_split
                   ? "eigenvalues of J - J_I (analytic) at the perturbed initial state"
                   : "eigenvalues of [[0, I], [da_E/dx, da_E/dv]] (a_E from J - J_I, analytic) "
                     "at the perturbed initial state";
    dense_eigenvalues(je, s);
  } else if (const auto est = sys.explicit_part_spectrum(t0, y0)) {
    if (est->ray == SpectrumEstimate::Ray::imaginary) {
      s.eigenvalues = {cd(0, est->radius), cd(0, -est->radius)};
      s.source = "explicit_part_spectrum() estimate " + num(est->radius) + " on the imaginary axis";
    } else {
      s.eigenvalues = {cd(-est->radius, 0)};
      s.source =
          "explicit_part_spectrum() estimate " + num(est->radius) + " on the negative real axis";
    }
  } else {
    s.source = "none (no analytic J and J_I within the dense limit, no explicit_part_spectrum())";
  }
  drop_non_finite(s);
  for (const cd& l : s.eigenvalues) s.omega = std::max(s.omega, std::abs(l));
  return s;
}

Vec perturbed_state(const OdeSystem& sys, const StabilitySpec& spec) {
  Vec y = sys.initial_state();
  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> xi(0.0, 1.0);
  if (const MechanicalSystem* m = sys.as_mechanical()) {
    auto x = y.head(m->dofs());
    const double mean = x.size() ? x.mean() : 0.0;
    double s = x.size() ? std::sqrt((x.array() - mean).square().mean()) : 0.0;
    if (!(s > 0)) s = 1.0;
    for (Index i = 0; i < x.size(); ++i) x(i) += spec.perturbation * s * xi(rng);
  } else {
    // Non-negative components (concentrations) stay non-negative: a negative one would give
    // the model growing modes it does not have (Robertson: an eigenvalue −6e7·y2 > 0).
    const double floor = 1e-3 * (y.size() ? y.cwiseAbs().maxCoeff() : 0.0);
    for (Index i = 0; i < y.size(); ++i) {
      const double d = spec.perturbation * std::max(std::abs(y(i)), floor) * xi(rng);
      y(i) = y(i) >= 0 ? std::abs(y(i) + d) : y(i) + d;
    }
  }
  return y;
}

// Least-squares slope of log y against t.
// The slope of log y against t (y > 0).
std::optional<double> semilog_slope(const std::vector<double>& t, const std::vector<double>& y) {
  std::vector<double> ly;
  for (double v : y) ly.push_back(std::log(v));
  return least_squares_slope(t, ly);
}

struct Probe {
  bool stable = false;
  Status status = Status::ok;
  std::string message;
  SolveStats stats;                         // the run's counters
  std::optional<double> growth_per_period;  // when unstable with enough samples
};

// Ends a row whose probe timed out or failed (status and message of the row).
struct RowEnded {
  std::string status, message;
};

// Thrown by the observer to end a run whose energy crossed the threshold.
struct EnergyGrowth {
  double t;
};

// One run at step h over `mult` horizons; stable by the criterion of the header.
Probe probe(const OdeSystem& sys, Integrator& integ, double t0, const Vec& y0, double h,
            double horizon, double period, int mult, const StabilitySpec& spec,
            const std::function<double(double, CVecRef)>& energy) {
  const double want = std::ceil(mult * horizon / h);
  const long steps = static_cast<long>(
      std::min<double>(std::max<double>(want, static_cast<double>(spec.min_steps) * mult),
                       static_cast<double>(spec.max_steps)));
  FixedStepOptions opt;
  opt.h = h;
  opt.t_end = t0 + static_cast<double>(steps) * h;
  opt.blowup_factor = spec.norm_growth;
  opt.max_steps = spec.max_steps;
  opt.outputs = steps;  // the observer sees every step
  const double e0 = energy ? energy(t0, y0) : 0.0;
  const double e_max = e0 + (spec.energy_growth - 1.0) * std::abs(e0);
  // The max-norm deviation from the start at (up to) 2000 equally spaced steps, for the growth
  // rate of an unstable run.
  const long every = std::max<long>(1, steps / 2000);
  long k = 0;
  std::vector<std::pair<double, double>> dev;
  Probe p;
  RunResult r;
  bool energy_stop = false;
  try {
    r = run_fixed_step_from(sys, integ, t0, y0, opt, [&](double t, CVecRef y) {
      if (k++ % every == 0) dev.emplace_back(t, (y - y0).cwiseAbs().maxCoeff());
      if (energy && !(energy(t, y) <= e_max)) throw EnergyGrowth{t};
    });
  } catch (const EnergyGrowth& g) {
    energy_stop = true;
    p.status = Status::unstable;
    p.message = "energy exceeded " + num(spec.energy_growth) + " x |E0| at t = " + num(g.t);
  }
  if (!energy_stop) {
    p.status = r.stats.status;
    p.message = r.stats.message;
  }
  p.stats = r.stats;
  p.stable = p.status == Status::ok;
  if (p.status == Status::unstable && period > 0) {
    // Growth rate from a least-squares fit of log deviation against t over the last half of
    // the samples (the unstable mode dominates there).
    std::vector<double> ts, ls;
    for (std::size_t i = dev.size() / 2; i < dev.size(); ++i)
      if (dev[i].second > 0 && std::isfinite(dev[i].second)) {
        ts.push_back(dev[i].first);
        ls.push_back(dev[i].second);
      }
    if (auto slope = semilog_slope(ts, ls)) p.growth_per_period = std::exp(*slope * period);
  }
  return p;
}

// The energy a run's growth is judged by, besides the norm (empty: the norm alone).
struct EnergyCriterion {
  std::function<double(double, CVecRef)> energy;
  std::string not_used;  // why `auto` left out a mechanical system's energy (arbitrary zero)
};

// Mechanical systems with an energy invariant are judged by their energy (unless --criterion
// norm), when its zero is a rest state: growth relative to |E0| means nothing for an energy with
// an arbitrary zero (Invariant::arbitrary_zero), so `auto` uses the norm alone there. BadInput
// for --criterion energy on a system without a usable energy.
EnergyCriterion energy_criterion(const OdeSystem& sys, const StabilitySpec& spec) {
  EnergyCriterion c;
  if (sys.as_mechanical() != nullptr && spec.criterion != "norm")
    for (const auto& inv : sys.invariants()) {
      if (inv.name != "energy") continue;
      require_input(inv.arbitrary_zero.empty() || spec.criterion != "energy",
                    "--criterion energy: the energy of model " + spec.model +
                        " has an arbitrary zero (" + inv.arbitrary_zero +
                        "), so its growth relative to |E0| means nothing; use --criterion norm "
                        "(auto does)");
      if (inv.arbitrary_zero.empty())
        c.energy = inv.value;
      else
        c.not_used = "the energy's zero is arbitrary: " + inv.arbitrary_zero;
    }
  require_input(c.energy || spec.criterion != "energy",
                "--criterion energy: model " + spec.model +
                    " is not a mechanical system with an 'energy' invariant");
  return c;
}

// The linear-theory limit of the method on the system's spectrum, into `row`; for a method that
// treats f_E explicitly on a split model, its explicit treatment's limit on the spectrum of f_E.
// Without a prediction, row.no_prediction says why.
void predict(const Integrator& integ, const Spectrum& spec_sys, const Spectrum* spec_explicit,
             bool mechanical, double h_cap, StabilityRow& row) {
  if (integ.explicit_part_stability() && spec_explicit) {
    // A mechanical split puts x' = v in f_I, so the method acts on the explicit acceleration's
    // modes as a partitioned method (x implicit, v explicit): Integrator::partitioned_stability(),
    // not the explicit treatment's R on ±iω (no prediction for a method without one).
    const bool partitioned = spec_explicit->mechanical_split;
    row.predicted_on = partitioned ? "f_E, partitioned (x' = v in f_I)" : "f_E";
    const auto le = partitioned ? integ.partitioned_stability() : integ.explicit_part_stability();
    if (!le) {
      row.no_prediction = partitioned ? "no partitioned stability map (x implicit, v explicit)"
                                      : "no stability data of its explicit treatment";
      return;
    }
    if (spec_explicit->eigenvalues.empty()) {
      row.no_prediction = "no spectrum of f_E: " + spec_explicit->source;
      return;
    }
    const StepLimit lim = predicted_step_limit(*le, spec_explicit->eigenvalues, mechanical, h_cap);
    if (lim.unbounded)
      row.predicted_unbounded = true;
    else
      row.h_predicted = lim.h;
    return;
  }
  const auto ls = integ.linear_stability();
  if (!ls) {
    row.no_prediction = "no linear stability data";
  } else if (spec_sys.eigenvalues.empty()) {
    row.no_prediction = "no spectrum: " + spec_sys.source;
  } else {
    const StepLimit lim = predicted_step_limit(*ls, spec_sys.eigenvalues, mechanical, h_cap);
    if (lim.unbounded)
      row.predicted_unbounded = true;
    else
      row.h_predicted = lim.h;  // 0: unstable for every h (see predicted_unstable_for_all_h)
  }
}

// The time scales of one row: period of the fastest mode, horizon of a run, reference step 2/ω
// and largest step tried.
struct StepScales {
  double period = 0, horizon = 0, h_ref = 0, h_cap = 0;
};

// The time scales from the spectrum's largest modulus ω (or --horizon when ω is unknown).
StepScales step_scales(const Spectrum& spec_sys, const StabilitySpec& spec) {
  StepScales s;
  const double omega = spec_sys.omega;
  s.period = omega > 0 ? 2.0 * std::numbers::pi / omega : 0.0;
  s.horizon = spec.horizon ? *spec.horizon : spec.periods * s.period;
  s.h_ref = omega > 0 ? 2.0 / omega : (spec.horizon ? *spec.horizon / spec.min_steps : 0.0);
  s.h_cap = spec.h_cap_factor * s.h_ref;
  return s;
}

// First guess: 0.8 × the prediction (not the prediction itself, so the bracket never starts
// on the predicted value), else the model's suggested step, else 2/ω.
double first_step(const OdeSystem& sys, const StabilityRow& row, double h_ref) {
  double h0 = h_ref;
  if (row.h_predicted && *row.h_predicted > 0)
    h0 = 0.8 * *row.h_predicted;
  else if (auto sug = sys.suggested_step();
           sug && sug->h > 0 && std::isfinite(sug->h) && !row.predicted_unbounded)
    h0 = sug->h;
  return h0;
}

// The search for h_max of one row (doubling or halving to a bracket, then bisection); fills in
// the row's status, measured step and counters.
class LimitSearch {
 public:
  LimitSearch(const OdeSystem& sys, Integrator& integ, const Vec& y0, const StabilitySpec& spec,
              const StepScales& sc, const std::function<double(double, CVecRef)>& energy,
              StabilityRow& row)
      : sys_(sys),
        integ_(integ),
        t0_(sys.initial_time()),
        y0_(y0),
        spec_(spec),
        sc_(sc),
        energy_(energy),
        row_(row) {}

  // Runs the whole search from h0 (throws RowEnded when a probe times out or fails).
  void search(double h0, double h_floor) {
    Probe first = run(h0, 1);
    if (first.stable ? grow(first, h0) : shrink(std::move(first), h0, h_floor)) return;
    bisect();
    finish();
  }

  // A method predicted stable for every step: one run at the largest step h_cap instead of the
  // search. Stable there: stable_up_to h_cap. Not stable: the search runs downward from h_cap
  // (halving, then bisection) like any other; when that run grew (rather than failing in the
  // solver, which is no stability statement) the message says the prediction is contradicted.
  void check_at_cap(double h_floor) {
    row_.checked_at_cap = true;
    Probe p = run(sc_.h_cap, 1);
    if (p.stable) {
      set_lo(p, sc_.h_cap);
      measured("stable_up_to");
      return;
    }
    const std::string contradiction =
        p.status == Status::unstable
            ? "contradicts the prediction (stable for every step): unstable at the largest step "
              "h = " +
                  num(sc_.h_cap) + (p.message.empty() ? "" : " (" + p.message + ")")
            : "";
    auto with_contradiction = [&](const std::string& m) {
      return contradiction.empty() ? m : m.empty() ? contradiction : contradiction + "; " + m;
    };
    try {
      if (!shrink(std::move(p), sc_.h_cap, h_floor)) {
        bisect();
        finish();
      }
    } catch (RowEnded& e) {
      e.message = with_contradiction(e.message);
      throw;
    }
    row_.message = with_contradiction(row_.message);
  }

 private:
  // A probe that timed out or threw says nothing about stability: the row ends there with
  // status timeout or failed (treating it as unstable would bias h_max low silently).
  Probe run(double h, int mult) {
    ++row_.probes;
    Probe p = probe(sys_, integ_, t0_, y0_, h, sc_.horizon, sc_.period, mult, spec_, energy_);
    if (p.status == Status::timeout || p.status == Status::error)
      throw RowEnded{p.status == Status::timeout ? "timeout" : "failed",
                     "at h = " + num(h) + ": " + p.message};
    return p;
  }

  // A probe that ended in the Newton iteration or the linear solver (newton_failed,
  // solver_error) is not stable, so the bisection brackets it like an unstable one, but it is
  // not growth: the upper end of the bracket remembers which it was, and a bracket whose upper
  // end is a solver failure makes the row solver_limit instead of ok.
  static bool solver_failure(const Probe& p) {
    return p.status == Status::newton_failed || p.status == Status::solver_error;
  }

  // Moves the lower end of the bracket to the stable step h.
  void set_lo(const Probe& p, double h) {
    lo_ = h;
    lo_stats_ = p.stats;
  }

  // Moves the upper end of the bracket to the step h that was not stable.
  void set_hi(const Probe& p, double h) {
    hi_ = h;
    hi_solver_ = solver_failure(p);
    hi_message_ = hi_solver_ ? to_string(p.status) + " at h = " + num(h) + ": " + p.message : "";
  }

  // Fills in the row measured at the lower end of the bracket with the given status.
  void measured(const std::string& status) {
    row_.status = status;
    row_.h_measured = lo_;
    row_.counters = lo_stats_;
    row_.horizon = std::max(sc_.horizon, static_cast<double>(spec_.min_steps) * lo_);
  }

  // Ends the row as solver_limit, measured at lo when a step ran (lo > 0).
  void solver_limit(double lo) {
    row_.status = "solver_limit";
    if (lo > 0) {
      row_.h_measured = lo;
      row_.counters = lo_stats_;
      row_.horizon = std::max(sc_.horizon, static_cast<double>(spec_.min_steps) * lo);
    }
    row_.message = hi_message_;
  }

  // Ends the row as unstable_for_all_h with the growth of the probe p at step h.
  void all_unstable(const Probe& p, double h) {
    row_.status = "unstable_for_all_h";
    row_.growth_per_period = p.growth_per_period;
    row_.growth_h = h;
    row_.message = p.message;
  }

  // Doubles the stable first step h0 up to the cap; true when the row ended stable_up_to.
  bool grow(const Probe& first, double h0) {
    set_lo(first, h0);
    while (hi_ == 0 && lo_ < sc_.h_cap) {
      const double h = std::min(2.0 * lo_, sc_.h_cap);
      Probe p = run(h, 1);
      if (p.stable)
        set_lo(p, h);
      else
        set_hi(p, h);
    }
    if (hi_ == 0) {
      measured("stable_up_to");
      return true;
    }
    return false;
  }

  // Halves the unstable first step h0 down to h_floor; true when the row ended there.
  bool shrink(Probe first, double h0, double h_floor) {
    set_hi(first, h0);
    Probe last = std::move(first);
    double h_last = h0;
    while (lo_ == 0) {
      const double h = 0.5 * hi_;
      if (h < h_floor) {
        if (hi_solver_)
          solver_limit(0.0);  // the solver fails at every step tried
        else
          all_unstable(last, h_last);
        return true;
      }
      Probe p = run(h, 1);
      if (p.stable) {
        set_lo(p, h);
      } else {
        set_hi(p, h);
        last = std::move(p);
        h_last = h;
      }
    }
    return false;
  }

  // Bisects the bracket [lo, hi] geometrically down to the relative tolerance.
  void bisect() {
    while (hi_ - lo_ > spec_.rel_tol * lo_) {
      const double mid = std::sqrt(lo_ * hi_);
      Probe p = run(mid, 1);
      if (p.stable)
        set_lo(p, mid);
      else
        set_hi(p, mid);
    }
  }

  // Classifies the bisected limit: solver_limit, unstable_for_all_h or ok.
  void finish() {
    if (hi_solver_) {
      // The largest stable step is bounded by the solver, not by growth: no stability limit.
      solver_limit(lo_);
      return;
    }
    // A method with a real stability interval is stable at 0.75 h_max on any horizon (linear
    // theory); one whose limit only reflects the finite horizon is not.
    const double h_check = 0.75 * lo_;
    Probe check = run(h_check, 8);
    if (!check.stable && check.status == Status::unstable) {
      all_unstable(check, h_check);
      return;
    }
    measured("ok");
  }

  const OdeSystem& sys_;
  Integrator& integ_;
  const double t0_;
  const Vec& y0_;
  const StabilitySpec& spec_;
  const StepScales sc_;
  const std::function<double(double, CVecRef)>& energy_;
  StabilityRow& row_;
  double lo_ = 0, hi_ = 0;  // the bracket (0: end not found yet)
  bool hi_solver_ = false;  // the current upper end failed in the solver
  std::string hi_message_;
  SolveStats lo_stats_;  // counters of the run at the current lower end (largest stable step)
};

// The measured and predicted stability limit of one integrator on the system.
StabilityRow measure(const OdeSystem& sys, Integrator& integ, const Spectrum& spec_sys,
                     const Spectrum* spec_explicit, const Vec& y0, const StabilitySpec& spec,
                     const std::function<double(double, CVecRef)>& energy) {
  StabilityRow row;
  row.model = spec.model;
  row.integrator = integ.info().name;
  const bool mechanical = sys.as_mechanical() != nullptr;
  const StepScales sc = step_scales(spec_sys, spec);

  predict(integ, spec_sys, spec_explicit, mechanical, sc.h_cap, row);
  row.h_cap = sc.h_cap;

  const double h0 = first_step(sys, row, sc.h_ref);
  const double h_floor = 1e-3 * std::min(h0, sc.h_ref);

  try {
    LimitSearch search(sys, integ, y0, spec, sc, energy, row);
    if (row.predicted_unbounded && !spec.probe_unbounded)
      search.check_at_cap(h_floor);
    else
      search.search(h0, h_floor);
  } catch (const RowEnded& e) {
    row.status = e.status;
    row.message = e.message;
  } catch (const BadInput&) {
    throw;
  } catch (const std::exception& e) {
    row.status = "failed";
    row.message = e.what();
  }
  return row;
}

std::string cell(const std::optional<double>& x) { return x ? format_full(*x) : ""; }

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
std::vector<Setup> stability_setups(const StabilitySpec& spec, const std::vector<double>& values) {
  const bool sweep = !spec.sweep_param.empty();
  std::vector<Setup> setups;
  for (const double v : values) {
    Params p = spec.params;
    if (sweep) p.set(spec.sweep_param, format_full(v));
    setups.push_back(make_setup(spec.model, spec.integrators, p));
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

StabilityResult run_stability(const StabilitySpec& spec, std::ostream* progress) {
  spec.validate();
  StabilityResult res;
  const bool sweep = !spec.sweep_param.empty();
  const std::vector<double> values = sweep ? spec.sweep_values : std::vector<double>{0.0};
  std::vector<Setup> setups = stability_setups(spec, values);
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

std::string limit_kind(const StabilityRow& row) {
  if (!row.h_measured) return "";
  if (row.status == "stable_up_to") return "stable_up_to";
  if (row.status == "ok" || row.status == "solver_limit") return "measured";
  return "";
}

Table stability_table(const StabilityResult& r) {
  Table t;
  t.columns = {"model",           "integrator", "param",  "value",     "h_max_measured",
               "h_max_predicted", "ratio",      "status", "limit_kind"};
  for (const std::string& c : SolveStats::counter_names()) t.columns.push_back(c);
  // Grouped by integrator (in the order of the runs), so a plot draws each one as one line.
  std::vector<const StabilityRow*> order;
  for (const auto& row : r.rows) order.push_back(&row);
  std::stable_sort(order.begin(), order.end(), [&](const StabilityRow* a, const StabilityRow* b) {
    auto first = [&](const std::string& name) {
      for (std::size_t k = 0; k < r.rows.size(); ++k)
        if (r.rows[k].integrator == name) return k;
      return r.rows.size();
    };
    return first(a->integrator) < first(b->integrator);
  });
  for (const StabilityRow* rp : order) {
    const StabilityRow& row = *rp;
    std::optional<double> ratio;
    if (row.status == "ok" && row.h_measured && row.h_predicted && *row.h_predicted > 0)
      ratio = *row.h_measured / *row.h_predicted;
    std::vector<std::string> cells = {row.model,
                                      row.integrator,
                                      row.param,
                                      row.param.empty() ? "" : format_full(row.value),
                                      cell(row.h_measured),
                                      row.predicted_unbounded ? "inf" : cell(row.h_predicted),
                                      cell(ratio),
                                      row.status,
                                      limit_kind(row)};
    const std::vector<std::string> counters =
        row.counters ? row.counters->counter_values()
                     : std::vector<std::string>(SolveStats::counter_names().size());
    cells.insert(cells.end(), counters.begin(), counters.end());
    t.rows.push_back(std::move(cells));
  }
  return t;
}

namespace {

std::string markdown_report(const StabilitySpec& spec, const StabilityResult& r) {
  std::ostringstream md;
  md << "# Stability limit: " << spec.model << "\n\n";
  md << "Largest stable fixed step h_max, measured by bisection to a relative tolerance of "
     << num(spec.rel_tol)
     << ", against linear theory. A run is stable when it stays finite and "
        "its max-norm never exceeds "
     << num(spec.norm_growth) << " x max(1, |y0|)"
     << (r.criterion == "energy"
             ? " and its energy never exceeds E0 + " + num(spec.energy_growth - 1) + " x |E0|"
         : r.criterion_note.empty() ? std::string()
                                    : " (the energy is not used: " + r.criterion_note + ")")
     << ", checked at every step over "
     << (spec.horizon ? "a horizon of " + num(*spec.horizon)
                      : num(spec.periods) + " periods of the fastest mode")
     << " (at least " << spec.min_steps << " steps), from an initial state perturbed by a relative "
     << num(spec.perturbation) << " (seed " << spec.seed
     << ") so that every mode is excited. Predicted: " << r.spectrum_source
     << (r.explicit_spectrum_source.empty()
             ? std::string()
             : " (IMEX and splitting methods: their explicit treatment on the spectrum of f_E, " +
                   r.explicit_spectrum_source + ")")
     << ", scaled into each method's stability region. A ratio near 1 means linear theory "
        "predicts the limit; `unstable_for_all_h` marks methods whose measured limit shrinks "
        "with the horizon (no stable step), `stable_up_to` methods stable up to the largest step "
        "tried, h_cap = "
     << num(spec.h_cap_factor) << " x 2/omega (h_max measured `>= h_cap`: a lower bound, "
     << (spec.probe_unbounded
             ? "searched from 2/omega upward like every method"
             : "one run at h_cap for a method predicted stable for every step, no search below "
               "it; --probe-unbounded searches")
     << "), `solver_limit` rows whose larger steps failed in the Newton iteration or the "
        "linear solver (not growth: h_max measured is the largest step that ran, the note says "
        "why the next one failed). A predicted 0 means unstable for every h (an undamped mode and "
        "an imaginary-axis limit of 0).\n\n";
  Table t;
  t.columns = {"integrator", "param",  "h_max measured", "h_max predicted",
               "ratio",      "status", "limit kind",     "note"};
  for (const auto& row : r.rows) {
    std::string note;
    if (row.status == "unstable_for_all_h") {
      note = row.growth_per_period ? "growth x" + num(*row.growth_per_period) +
                                         " per period at h = " + num(row.growth_h)
                                   : "unstable at every step down to h = " + num(row.growth_h);
      // What ended that run: the energy criterion can end one whose norm does not grow.
      if (!row.message.empty()) note += " (" + row.message + ")";
    } else if (row.status == "failed" || row.status == "solver_limit" || !row.message.empty()) {
      note = row.message;
    } else if (row.status == "stable_up_to" && row.checked_at_cap) {
      note = "1 run, at h_cap (predicted stable for every step)";
    } else {
      note = std::to_string(row.probes) + " runs";
    }
    if (!row.no_prediction.empty())
      note += (note.empty() ? "" : "; ") + std::string("no prediction: ") + row.no_prediction;
    std::string ratio;
    if (row.status == "ok" && row.h_measured && row.h_predicted && *row.h_predicted > 0)
      ratio = format_fixed(*row.h_measured / *row.h_predicted, 4);
    t.rows.push_back(
        {row.integrator, row.param.empty() ? "" : row.param + " = " + num(row.value),
         row.h_measured ? (limit_kind(row) == "stable_up_to" ? ">= " : "") + num(*row.h_measured)
                        : "",
         row.predicted_unbounded ? "unbounded"
         : row.h_predicted       ? (*row.h_predicted == 0 ? std::string("0 (unstable for all h)")
                                                          : num(*row.h_predicted))
                                 : "none",
         ratio, row.status, limit_kind(row), note});
  }
  md << t.to_markdown();
  if (!r.fits.empty()) {
    md << "\nLog-log slope of h_max against " << spec.sweep_param
       << " (least squares over the rows with status ok):\n\n";
    Table f;
    f.columns = {"integrator", "measured slope", "predicted slope", "points"};
    for (const auto& fit : r.fits)
      f.rows.push_back({fit.integrator,
                        fit.measured_slope ? format_fixed(*fit.measured_slope, 3) : "",
                        fit.predicted_slope ? format_fixed(*fit.predicted_slope, 3) : "",
                        std::to_string(fit.points)});
    md << f.to_markdown();
  }
  return md.str();
}

}  // namespace

void write_stability_outputs(const std::filesystem::path& dir, const StabilitySpec& spec,
                             const StabilityResult& r) {
  write_file_atomic(dir / "stability.csv", stability_table(r).to_csv());
  write_file_atomic(dir / "stability.md", markdown_report(spec, r));
  nlohmann::json meta = run_metadata("stability", spec.to_json());
  meta["spectrum"] = r.spectrum_source;
  if (!r.explicit_spectrum_source.empty())
    meta["explicit_part_spectrum"] = r.explicit_spectrum_source;
  meta["criterion_used"] = r.criterion;
  if (!r.criterion_note.empty()) meta["criterion_note"] = r.criterion_note;
  meta["criterion"] =
      "stable: status ok, finite, max-norm <= norm_growth * max(1, |y0|) and (criterion_used "
      "energy: mechanical systems with an energy invariant whose zero is not arbitrary) "
      "E <= E0 + (growth - 1) |E0| at every step of the horizon; "
      "unstable_for_all_h: unstable at 0.75 h_max over 8x the horizon; "
      "solver_limit: the smallest failing step ended in newton_failed or solver_error; "
      "stable_up_to: stable at the largest step h_cap (limit_kind stable_up_to, a lower bound; "
      "a method predicted stable for every step gets one run at h_cap unless probe_unbounded, "
      "search = check_at_h_cap)";
  for (const auto& row : r.rows) {
    nlohmann::json j;
    j["integrator"] = row.integrator;
    if (!row.param.empty()) j[row.param] = row.value;
    j["status"] = row.status;
    j["limit_kind"] = limit_kind(row);
    if (row.h_measured) j["h_max_measured"] = *row.h_measured;
    if (row.predicted_unbounded)
      j["h_max_predicted"] = "unbounded";
    else if (row.h_predicted)
      j["h_max_predicted"] = *row.h_predicted;
    else
      j["no_prediction"] = row.no_prediction;
    j["h_cap"] = row.h_cap;
    j["search"] = !row.checked_at_cap            ? "bisection"
                  : row.status == "stable_up_to" ? "check_at_h_cap"
                                                 : "check_at_h_cap, then bisection below it";
    j["predicted_on"] = row.predicted_on;
    j["probes"] = row.probes;
    if (row.counters) {
      for (std::size_t c = 0; c < SolveStats::counter_names().size(); ++c) {
        const std::string v = row.counters->counter_values()[c];
        auto& slot = j["counters"][SolveStats::counter_names()[c]];
        if (v.empty())
          slot = nullptr;  // not reported by the library (SolveStats::kNotReported)
        else
          slot = std::stol(v);
      }
    }
    j["horizon"] = row.horizon;
    if (row.growth_per_period) {
      j["growth_per_period"] = *row.growth_per_period;
      j["growth_at_h"] = row.growth_h;
    }
    if (!row.message.empty()) j["message"] = row.message;
    meta["rows"].push_back(j);
  }
  for (const auto& f : r.fits) {
    nlohmann::json j;
    j["integrator"] = f.integrator;
    j["points"] = f.points;
    if (f.measured_slope) j["measured_slope"] = *f.measured_slope;
    if (f.predicted_slope) j["predicted_slope"] = *f.predicted_slope;
    meta["fits"].push_back(j);
  }
  write_file_atomic(dir / "stability.json", meta.dump(2) + "\n");
}

bool plot_stability(const std::filesystem::path& csv, const std::string& title,
                    const PlotOptions& opt, std::ostream& err) {
  std::filesystem::path stem = csv;
  stem.replace_extension();
  const auto params = csv_column_values(csv, "param");
  const bool sweep = !params.empty() && !params.front().empty();
  return run_plot("stability.gp", stem,
                  {{"csvfile", csv.string()},
                   {"ttl", title},
                   {"sweep", sweep ? "1" : "0"},
                   {"xlab", sweep ? params.front() : ""}},
                  family_panels(csv_column_values(csv, "integrator"), opt.family), opt, err);
}

namespace {

class StabilityJob : public StudyJob {
 public:
  explicit StabilityJob(StabilitySpec spec) : spec_(std::move(spec)) { spec_.validate(); }
  nlohmann::json spec_json() const override { return spec_.to_json(); }
  void run(std::ostream* progress) override { result_ = run_stability(spec_, progress); }
  Table unit_table() const override { return stability_table(result_); }
  bool write(const std::filesystem::path& dir, const std::string& title, const PlotOptions& plot,
             std::ostream& err) const override {
    write_stability_outputs(dir, spec_, result_);
    return plot_stability(dir / "stability.csv", title, plot, err);
  }
  void print_summary(std::ostream& out) const override {
    out << stability_table(result_).to_markdown();
    for (const auto& f : result_.fits)
      if (f.measured_slope)
        out << "slope of log h_max vs log " << spec_.sweep_param << ", " << f.integrator << ": "
            << format_fixed(*f.measured_slope, 3)
            << (f.predicted_slope ? " (predicted " + format_fixed(*f.predicted_slope, 3) + ")"
                                  : std::string())
            << "\n";
  }
  std::string report_markdown(const std::string& note) const override;
  std::string default_title() const override { return "Stability limit: " + spec_.model; }
  const StabilityResult& result() const { return result_; }

 private:
  StabilitySpec spec_;
  StabilityResult result_;
};

std::string StabilityJob::report_markdown(const std::string& note) const {
  std::ostringstream md;
  md << note << " Spectrum: " << result_.spectrum_source << ".";
  if (!result_.explicit_spectrum_source.empty())
    md << " IMEX and splitting methods are predicted from their explicit treatment on the "
          "spectrum of f_E: "
       << result_.explicit_spectrum_source << ".";
  md << "\n\n";
  Table summary{{"integrator", "statuses", "h_max/predicted (range)", "slope of log h_max",
                 "predicted slope"},
                {}};
  for (const auto& name : spec_.integrators) {
    std::string statuses;
    double rmin = 1e300, rmax = -1e300;
    for (const auto& r : result_.rows) {
      if (r.integrator != name) continue;
      if (statuses.find(r.status) == std::string::npos)
        statuses += (statuses.empty() ? "" : ", ") + r.status;
      if (r.status == "ok" && r.h_measured && r.h_predicted && *r.h_predicted > 0) {
        rmin = std::min(rmin, *r.h_measured / *r.h_predicted);
        rmax = std::max(rmax, *r.h_measured / *r.h_predicted);
      }
    }
    std::string slope = "-", pslope = "-";
    for (const auto& f : result_.fits)
      if (f.integrator == name) {
        if (f.measured_slope) slope = format_fixed(*f.measured_slope, 3);
        if (f.predicted_slope) pslope = format_fixed(*f.predicted_slope, 3);
      }
    summary.rows.push_back(
        {name, statuses, rmin <= rmax ? format_fixed(rmin, 4) + " - " + format_fixed(rmax, 4) : "-",
         slope, pslope});
  }
  md << summary.to_markdown() << "\n";
  return md.str();
}

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
    StabilitySpec s;
    s.model = t.model;
    s.params = t.params;
    s.integrators = t.integrators;
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
    return std::make_unique<StabilityJob>(std::move(s));
  };
  return k;
}

const StabilityResult& stability_result(const StudyJob& job) {
  return dynamic_cast<const StabilityJob&>(job).result();
}

StabilityResult run_stability(StabilitySpec spec, const StudyObjects& objects,
                              std::ostream* progress) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  return run_stability(static_cast<const StabilitySpec&>(spec), progress);
}

StabilityResult stability_study(StabilitySpec spec, const StudyObjects& objects,
                                const std::filesystem::path& dir, const StudyContext& ctx) {
  const ScopedStudyObjects scope(objects, spec.model, spec.integrators);
  StabilityJob job(std::move(spec));
  run_study_job(study_kind("stability"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
