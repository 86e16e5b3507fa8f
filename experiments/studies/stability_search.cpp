#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "core/driver.hpp"
#include "core/theory/linear_stability.hpp"
#include "experiments/output/output.hpp"
#include "experiments/studies/stability_search.hpp"

namespace stiffbench::stability_internal {

std::string num(double x) { return format_short(x, 4); }

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace stiffbench::stability_internal
