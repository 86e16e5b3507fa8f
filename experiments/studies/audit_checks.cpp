// The checks of `stiffbench audit` on one method (audit_integrator in audit.hpp): evaluation
// counts against the counting wrapper, the local-error slope, adaptive exactness on polynomials
// and the claims of the method's coefficients.
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/theory/additive_conditions.hpp"
#include "core/theory/method_analysis.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/studies/audit.hpp"
#include "experiments/studies/audit_systems.hpp"

namespace stiffbench {

namespace {

using audit_parts::count_systems;
using audit_parts::CountSystem;
using audit_parts::monomial_system;
using audit_parts::rotation_decay_system;

// ---- Helpers ------------------------------------------------------------------------------

std::string num(double x, int digits = 4) {
  std::ostringstream os;
  os.precision(digits);
  os << x;
  return os.str();
}

AuditRow row(const std::string& integ, const std::string& check, const std::string& system,
             const std::string& claimed, const std::string& measured, bool ok,
             const std::string& reason) {
  return {integ, check, system, claimed, measured, ok ? "ok" : "fail", reason};
}

AuditRow skip(const std::string& integ, const std::string& check, const std::string& system,
              const std::string& reason) {
  return {integ, check, system, "-", "-", "skip", reason};
}

// The Butcher tableau of a method: its own butcher_tableau() (explicit, embedded, DIRK, fully
// implicit and Radau IIA steppers).
const ButcherTableau* tableau_of(const Integrator& integ) { return integ.butcher_tableau(); }

// Why the method cannot run on `sys`, or empty.
std::string incompatibility(const Integrator& integ, const OdeSystem& sys) {
  try {
    check_compatible(integ.info(), sys);
  } catch (const BadInput& e) {
    return e.what();
  }
  return {};
}

std::string run_note(const RunResult& r) {
  if (r.stats.status == Status::ok) return {};
  return "the run ended with status " + to_string(r.stats.status) +
         (r.stats.message.empty() ? "" : ": " + r.stats.message);
}

// One run on the counting wrapper around `sys`.
struct CountedRun {
  RunResult result;
  CallCounts counts;
  long reset_jac = 0;  // force-Jacobian calls inside reset() (pattern analysis, not counted)
};

// Force-Jacobian calls a fresh method makes inside reset() alone: structure (pattern)
// analysis, which the system boundary does not count as evaluations (like jacobian_pattern()).
long reset_jacobian_calls(const IntegratorFactory& create, const OdeSystem& sys) {
  CallCounts c;
  const auto w = make_counting_system(sys, c);
  auto integ = create();
  const Vec y0 = w->initial_state();
  const long before_analytic = w->counters().jac_evals;
  integ->reset(*w, w->initial_time(), y0);
  // Analytic jacobian() calls at reset are counted at the boundary (and reported): keep them.
  return c.jac - (w->counters().jac_evals - before_analytic);
}

CountedRun counted_fixed(const IntegratorFactory& create, const OdeSystem& sys, double span,
                         long steps) {
  CountedRun out;
  out.reset_jac = reset_jacobian_calls(create, sys);
  const auto w = make_counting_system(sys, out.counts);
  auto integ = create();
  FixedStepOptions o;
  o.t_end = sys.initial_time() + span;
  o.h = span / static_cast<double>(steps);
  out.result = run_fixed_step(*w, *integ, o);
  return out;
}

CountedRun counted_adaptive(const IntegratorFactory& create, const OdeSystem& sys, double span) {
  CountedRun out;
  out.reset_jac = reset_jacobian_calls(create, sys);
  const auto w = make_counting_system(sys, out.counts);
  auto integ = create();
  AdaptiveOptions o;
  o.t_end = sys.initial_time() + span;
  out.result = run_adaptive(*w, *integ, o);
  return out;
}

void count_rows(std::vector<AuditRow>& rows, const std::string& name, const std::string& mode,
                const std::string& system, const CountedRun& run) {
  const std::string note = run_note(run.result);
  const long f = run.counts.f, jac = run.counts.jac - run.reset_jac;
  const SolveStats& s = run.result.stats;
  std::string why =
      "counting wrapper " + std::to_string(f) + " vs reported " + std::to_string(s.f_evals);
  // The counts are compared whatever the run's outcome (up to where it ended; the note says).
  rows.push_back(row(name, "f_evals_" + mode, system, std::to_string(s.f_evals), std::to_string(f),
                     f == s.f_evals,
                     f == s.f_evals ? note : why + (note.empty() ? "" : "; " + note)));
  why = "counting wrapper " + std::to_string(jac) + " (" + std::to_string(run.reset_jac) +
        " pattern call" + (run.reset_jac == 1 ? "" : "s") +
        " in reset() not counted) vs reported " + std::to_string(s.jac_evals);
  rows.push_back(row(
      name, "jac_evals_" + mode, system, std::to_string(s.jac_evals), std::to_string(jac),
      jac == s.jac_evals,
      jac == s.jac_evals ? (run.reset_jac ? why : note) : why + (note.empty() ? "" : "; " + note)));
}

// f_evals, jac_evals (fixed step and adaptive) and f_per_step on the three systems.
void count_checks(std::vector<AuditRow>& rows, const std::string& name,
                  const IntegratorFactory& create) {
  const auto probe = create();
  const MethodInfo& info = probe->info();
  const bool per_step =
      (info.family == Family::explicit_rk || info.family == Family::symplectic) && info.stages > 0;
  std::vector<CountSystem> systems = count_systems(info.requires_.split);
  if (info.requires_.constraints) {
    // Methods that enforce holonomic constraints (rattle) run on none of the three: their counts
    // are checked on a constrained pendulum chain of 3 bobs instead.
    Params chain;
    chain.set("n", "3");
    chain.set("constrained", "true");
    systems.push_back(
        {"pendulum_chain(n=3,constrained)", model_registry().create("pendulum_chain", chain), 0.1});
  }
  for (const CountSystem& cs : systems) {
    if (const std::string why = incompatibility(*probe, *cs.sys); !why.empty()) {
      rows.push_back(skip(name, "f_evals", cs.label, why));
      continue;
    }
    if (probe->supports_fixed_step()) {
      const CountedRun r16 = counted_fixed(create, *cs.sys, cs.span, 16);
      count_rows(rows, name, "fixed", cs.label, r16);
      if (per_step) {
        const CountedRun r8 = counted_fixed(create, *cs.sys, cs.span / 2, 8);
        const long diff = r16.counts.f - r8.counts.f;
        const std::string note = run_note(r16.result) + run_note(r8.result);
        rows.push_back(row(name, "f_per_step", cs.label, std::to_string(info.stages),
                           num(static_cast<double>(diff) / 8.0),
                           diff == 8L * info.stages && note.empty(),
                           "f evaluations of 16 steps minus those of 8 (start-up cancels): " +
                               std::to_string(r16.counts.f) + " - " + std::to_string(r8.counts.f) +
                               (note.empty() ? "" : "; " + note)));
      }
    }
    if (probe->supports_adaptive())
      count_rows(rows, name, "adaptive", cs.label, counted_adaptive(create, *cs.sys, cs.span));
  }
  if (info.family == Family::reference)
    rows.push_back(skip(name, "library_f_evals", "-",
                        "the library's own count (library_f_evals) includes evaluations it makes "
                        "inside (difference quotients, restarts) and is not a claim about the "
                        "system boundary; f_evals above is checked instead"));
  else if (!per_step)
    rows.push_back(skip(name, "f_per_step", "-",
                        info.stages > 0
                            ? "f evaluations per step are not fixed: they follow the Newton "
                              "iterations or the Jacobian's source (finite differences)"
                            : "the method states no fixed number of evaluations per step"));
}

// ---- Local error slope ------------------------------------------------------------------------

constexpr double kSlopeTol = 0.3;
constexpr double kErrMax = 1e-3, kFloorMin = 1e-13, kFloorFactor = 100;
constexpr int kSlopePoints = 3, kLadderLevels = 28;

// The least-squares slope of ly against lx from the raw sums (n Σxy − Σx Σy)/(n Σxx − (Σx)²).
double slope_from_sums(const std::vector<double>& lx, const std::vector<double>& ly) {
  const double n = static_cast<double>(lx.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    sx += lx[i];
    sy += ly[i];
    sxx += lx[i] * lx[i];
    sxy += lx[i] * ly[i];
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

void slope_check(std::vector<AuditRow>& rows, const std::string& name,
                 const IntegratorFactory& create) {
  const std::string check = "local_error_slope";
  auto probe = create();
  const MethodInfo& info = probe->info();
  // Kepler (e = 0.5); methods that need a split: rotation_decay, whose parts do not commute.
  const bool split = info.requires_.split;
  Params kp;
  kp.set("e", "0.5");
  const std::unique_ptr<OdeSystem> sys =
      split ? rotation_decay_system() : model_registry().create("kepler", kp);
  const std::string label = split ? "rotation_decay" : "kepler(e=0.5)";
  if (const std::string why = incompatibility(*probe, *sys); !why.empty())
    return rows.push_back(skip(name, check, label, why));
  if (info.order <= 0)
    return rows.push_back(skip(name, check, label, "variable order: no fixed slope"));
  if (!probe->supports_fixed_step())
    return rows.push_back(skip(name, check, label, "adaptive only: no fixed step h"));
  const double t0 = sys->initial_time();
  const Vec y0 = sys->initial_state();
  // h_k = 0.5 · 2^(-k/2): a fine ladder, so that even an order-8 method has several errors
  // between its pre-asymptotic range and its floor.
  std::vector<double> hs, errs;
  std::string note;
  for (int k = 0; k < kLadderLevels; ++k) {
    const double h = 0.5 * std::pow(2.0, -0.5 * k);
    auto integ = create();
    FixedStepOptions o;
    o.t_end = t0 + h;
    o.h = h;
    const RunResult r = run_fixed_step(*sys, *integ, o);
    if (r.stats.status != Status::ok) {
      if (note.empty()) note = "h = " + num(h, 3) + ": " + run_note(r);
      continue;
    }
    Vec exact(y0.size());
    sys->exact(o.t_end, exact);
    hs.push_back(h);
    errs.push_back(max_abs_diff(r.y, exact));
  }
  // The floor: 100 times the largest error among the four smallest steps, where a high-order
  // method's error is round-off or its solver's tolerance (Newton noise of 1e-12 stays out of
  // the fit), at least 1e-13. The slope is fitted on the three smallest h whose errors lie in
  // [floor, 1e-3]: the asymptotic end of the ladder, far above the floor.
  double noise = 0;
  for (std::size_t i = errs.size() >= 4 ? errs.size() - 4 : 0; i < errs.size(); ++i)
    noise = std::max(noise, errs[i]);
  const double floor = std::max(kFloorMin, kFloorFactor * noise);
  std::vector<double> lx, ly;
  for (std::size_t i = hs.size(); i-- > 0 && lx.size() < kSlopePoints;)
    if (errs[i] >= floor && errs[i] <= kErrMax) {
      lx.push_back(std::log(hs[i]));
      ly.push_back(std::log(errs[i]));
    }
  const int expected = info.order + 1;
  if (lx.size() < kSlopePoints) {
    std::string errs_text;
    for (std::size_t i = 0; i < hs.size(); i += 2) errs_text += (i ? ", " : "") + num(errs[i], 2);
    return rows.push_back(row(name, check, label, std::to_string(expected), "-", false,
                              "fewer than 3 errors lie in [" + num(floor, 2) +
                                  ", 1e-3] (errors at h = 0.5/2^k: " + errs_text + ")" +
                                  (note.empty() ? "" : "; " + note)));
  }
  const double slope = slope_from_sums(lx, ly);
  const double h_min = std::exp(*std::min_element(lx.begin(), lx.end()));
  const double h_max = std::exp(*std::max_element(lx.begin(), lx.end()));
  rows.push_back(row(name, check, label, std::to_string(expected), num(slope, 3),
                     std::abs(slope - expected) <= kSlopeTol,
                     "least-squares slope over " + std::to_string(lx.size()) + " steps h in [" +
                         num(h_min, 3) + ", " + num(h_max, 3) + "] (errors above the floor " +
                         num(floor, 2) + "), tolerance 0.3" + (note.empty() ? "" : "; " + note)));
}

// ---- Adaptive exactness -----------------------------------------------------------------------

constexpr long kFewSteps = 30;
constexpr double kExactTol = 1e-13;

void adaptive_checks(std::vector<AuditRow>& rows, const std::string& name,
                     const IntegratorFactory& create) {
  auto probe = create();
  const MethodInfo& info = probe->info();
  if (!probe->supports_adaptive()) return;
  const bool split = info.requires_.split;  // then both parts carry half of t^q
  if (info.order <= 0) {
    const std::string why =
        "variable order: a polynomial is exact only at the order the method has reached";
    rows.push_back(skip(name, "adaptive_constant", "y'=1", why));
    rows.push_back(skip(name, "adaptive_polynomial", "y'=t^(p-1)", why));
    return;
  }
  const auto run = [&](const OdeSystem& sys) {
    auto integ = create();
    AdaptiveOptions o;
    o.t_end = 1.0;
    return run_adaptive(sys, *integ, o);
  };
  {
    const auto sys = monomial_system(0, split);
    const RunResult r = run(*sys);
    const double err = std::abs(r.y[0] - 1.0);
    const bool ok = r.stats.status == Status::ok && err <= kExactTol && r.stats.steps <= kFewSteps;
    rows.push_back(
        row(name, "adaptive_constant", sys->name(), "error <= 1e-13 in <= 30 steps",
            "error " + num(err, 2) + " in " + std::to_string(r.stats.steps) + " steps", ok,
            ok                    ? ""
            : run_note(r).empty() ? "every error estimate should be zero up to round-off "
                                    "(embedded weights that do not sum to 1?)"
                                  : run_note(r)));
  }
  {
    const auto sys = monomial_system(info.order - 1, split);
    const RunResult r = run(*sys);
    const double exact = 1.0 / info.order;
    const double err = std::abs(r.y[0] - exact);
    const bool ok = r.stats.status == Status::ok && err <= kExactTol;
    rows.push_back(row(
        name, "adaptive_polynomial", sys->name(), "error <= 1e-13",
        "error " + num(err, 2) + " in " + std::to_string(r.stats.steps) + " steps", ok,
        ok                    ? ""
        : run_note(r).empty() ? "an order-" + std::to_string(info.order) + " method integrates t^" +
                                    std::to_string(info.order - 1) + " exactly"
                              : run_note(r)));
  }
}

// ---- Tableau checks ----------------------------------------------------------------------------

// Claimed order p exact: conditions up to min(p, 6) hold, some of order p + 1 fails (p < 6).
AuditRow order_row(const std::string& name, const std::string& check, const ButcherTableau& t,
                   const Vec& weights, int claimed) {
  const int measured = t.satisfied_order(weights, 1e-12, 6);
  const std::string label = t.name;
  if (claimed >= 6)
    return row(name, check, label, std::to_string(claimed),
               measured >= 6 ? ">= 6" : std::to_string(measured), measured >= 6,
               "conditions up to order 6 checked (the rooted trees are generated up to order 6)");
  const bool ok = measured == claimed;
  std::string reason;
  if (measured < claimed)
    reason = "an order-" + std::to_string(measured + 1) + " condition fails by " +
             num(t.order_defect(weights, measured + 1), 3);
  else if (measured > claimed)
    reason = "every condition of order " + std::to_string(claimed + 1) +
             " holds as well: the claim is not the order";
  return row(name, check, label, std::to_string(claimed), std::to_string(measured), ok, reason);
}

// The same for an additive pair: the conditions of both tables and the coupling ones
// (core/theory/additive_conditions.hpp) with the weights wE, wI, checked to order 6.
AuditRow additive_order_row(const std::string& name, const std::string& check,
                            const AdditiveTableau& t, const Vec& wE, const Vec& wI, int claimed) {
  constexpr int kMax = 6;
  const int measured =
      additive_satisfied_order(t.explicit_table, t.implicit_table, wE, wI, kMax, 1e-12);
  const std::string label = t.name + " (additive)";
  if (claimed >= kMax)
    return row(name, check, label, std::to_string(claimed),
               measured >= kMax ? ">= 6" : std::to_string(measured), measured >= kMax,
               "additive conditions up to order 6 checked");
  std::string reason;
  if (measured < claimed) {
    const auto conditions =
        additive_order_conditions(t.explicit_table, t.implicit_table, wE, wI, measured + 1, "b");
    if (const auto c = first_violated_additive_condition(conditions, measured + 1, false, 1e-12))
      reason = std::string(c->coupling ? "the coupling condition " : "the condition ") + c->name +
               " fails by " + num(c->residual, 3);
  } else if (measured > claimed) {
    reason = "every additive condition of order " + std::to_string(claimed + 1) +
             " holds as well: the claim is not the order";
  }
  return row(name, check, label, std::to_string(claimed), std::to_string(measured),
             measured == claimed, reason);
}

// An additive pair's claims: its order and embedded order from the additive conditions (the
// tables' sizes and shared nodes are checked when the pair is built).
void additive_checks(std::vector<AuditRow>& rows, const std::string& name, const Integrator& integ,
                     const AdditiveTableau& t) {
  rows.push_back(additive_order_row(name, "tableau_order", t, t.explicit_table.b,
                                    t.implicit_table.b, integ.info().order));
  if (t.has_embedded())
    rows.push_back(additive_order_row(name, "embedded_order", t, t.explicit_table.b_embedded,
                                      t.implicit_table.b_embedded, t.embedded_order));
  rows.push_back(
      skip(name, "stage_order", t.name + " (additive)", "an additive pair claims no stage order"));
}

// A claimed order against the achieved one of a set of conditions (Rosenbrock: the classical
// conditions of core/theory/method_analysis.hpp to order 8, or the W-conditions to kMaxWOrder): the
// claim must be the order, no more and no less.
AuditRow conditions_row(const std::string& name, const std::string& check, const std::string& label,
                        const std::vector<OrderCondition>& conditions, int measured, int max_order,
                        int claimed, const std::string& what) {
  if (claimed >= max_order)
    return row(name, check, label, std::to_string(claimed),
               measured >= max_order ? ">= " + std::to_string(max_order) : std::to_string(measured),
               measured >= max_order,
               what + " up to order " + std::to_string(max_order) + " checked");
  std::string reason;
  if (measured < claimed) {
    if (const auto c = first_violated_condition(conditions, measured + 1))
      reason = "the " + what + " of tree " + c->name + " (order " + std::to_string(c->order) +
               ") fails by " + num(c->residual, 3);
  } else if (measured > claimed) {
    reason = "every " + what + " of order " + std::to_string(claimed + 1) +
             " holds as well: the claim is not the order";
  }
  return row(name, check, label, std::to_string(claimed), std::to_string(measured),
             measured == claimed, reason);
}

// A Rosenbrock method's claims: its order and embedded order from the order conditions of
// Hairer & Wanner II, IV.7 (rooted trees to order 8, β = α + Γ on a vertex with one son), its
// W-order when it claims one (the conditions with an arbitrary matrix in place of J).
void rosenbrock_checks(std::vector<AuditRow>& rows, const std::string& name,
                       const Integrator& integ, const RosenbrockTableau& t) {
  const MethodAnalysis m = analyze_rosenbrock(t);
  const std::string label = t.name + " (Rosenbrock)";
  rows.push_back(conditions_row(name, "tableau_order", label, m.conditions, m.order, 8,
                                integ.info().order, "order condition"));
  if (t.b_embedded.size() == t.stages()) {
    RosenbrockTableau embedded = t;
    embedded.b = t.b_embedded;
    const MethodAnalysis e = analyze_rosenbrock(embedded);
    rows.push_back(conditions_row(name, "embedded_order", label, e.conditions, e.order, 8,
                                  t.embedded_order, "order condition"));
  }
  if (t.w_order > 0)
    rows.push_back(conditions_row(name, "w_order", label, m.w_conditions, m.w_order, kMaxWOrder,
                                  t.w_order, "W-condition"));
  else
    rows.push_back(skip(
        name, "w_order", label,
        "no W-order claimed (the W-conditions hold to order " + std::to_string(m.w_order) + ")"));
  rows.push_back(skip(name, "stage_order", label, "a Rosenbrock method has no stage order"));
}

void tableau_checks(std::vector<AuditRow>& rows, const std::string& name,
                    const IntegratorFactory& create) {
  auto integ = create();
  if (const AdditiveTableau* a = integ->additive_tableau())
    return additive_checks(rows, name, *integ, *a);
  if (const RosenbrockTableau* r = integ->rosenbrock_tableau())
    return rosenbrock_checks(rows, name, *integ, *r);
  const ButcherTableau* t = tableau_of(*integ);
  if (!t) {
    rows.push_back(skip(name, "tableau", "-", "not defined by a Butcher tableau"));
    return;
  }
  // Sizes and nodes first: the order conditions need them.
  if (const std::string d = t->defect();
      !d.empty() &&
      (t->c.size() != t->stages() || t->a.rows() != t->stages() || t->a.cols() != t->stages())) {
    rows.push_back(
        row(name, "tableau_order", t->name, std::to_string(integ->info().order), "-", false, d));
    return;
  }
  rows.push_back(order_row(name, "tableau_order", *t, t->b, integ->info().order));
  if (t->b_embedded.size() == t->stages())
    rows.push_back(order_row(name, "embedded_order", *t, t->b_embedded, t->embedded_order));
  const int q = t->satisfied_stage_order();
  if (t->stage_order > 0)
    rows.push_back(row(name, "stage_order", t->name, std::to_string(t->stage_order),
                       std::to_string(q), q >= t->stage_order,
                       q >= t->stage_order ? "" : "C(" + std::to_string(q + 1) + ") fails"));
  else
    rows.push_back(
        skip(name, "stage_order", t->name,
             "the tableau claims no stage order (C(q) holds for q = " + std::to_string(q) + ")"));
  const bool fsal = t->coefficients_fsal();
  rows.push_back(
      row(name, "fsal", t->name, t->fsal ? "yes" : "no", fsal ? "yes" : "no", !t->fsal || fsal,
          t->fsal && !fsal   ? "the last row of A is not b"
          : !t->fsal && fsal ? "the coefficients are FSAL; the method does not claim (or use) it"
                             : ""));
}

// Runs one group of checks; an exception (other than the model or method refusing the system,
// which the checks test first) is a failed row naming it.
template <class Fn>
void guarded(std::vector<AuditRow>& rows, const std::string& name, const std::string& check,
             Fn fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    rows.push_back({name, check, "-", "-", "-", "fail", std::string("exception: ") + e.what()});
  }
}

}  // namespace

std::vector<AuditRow> audit_integrator(const std::string& name, const IntegratorFactory& create) {
  std::vector<AuditRow> rows;
  guarded(rows, name, "counts", [&] { count_checks(rows, name, create); });
  guarded(rows, name, "local_error_slope", [&] { slope_check(rows, name, create); });
  guarded(rows, name, "adaptive", [&] { adaptive_checks(rows, name, create); });
  guarded(rows, name, "tableau", [&] { tableau_checks(rows, name, create); });
  return rows;
}

}  // namespace stiffbench
