#include "experiments/studies/convergence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "core/driver.hpp"
#include "experiments/studies/convergence_output.hpp"
#include "experiments/support/coefficients.hpp"

namespace stiffbench {

std::optional<double> ConvergenceSpec::given_floor() const {
  if (floor == "auto" || floor == "model") return std::nullopt;
  std::size_t used = 0;
  double v = std::numeric_limits<double>::quiet_NaN();
  try {
    v = std::stod(floor, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  require_input(!floor.empty() && used == floor.size() && std::isfinite(v) && v > 0,
                "--floor must be auto, model or a positive number (got '" + floor + "')");
  return v;
}

void ConvergenceSpec::validate() const {
  require_input(std::isfinite(t_end) && t_end > 0,
                "--t-end must be > 0 (got " + format_full(t_end) + ")");
  require_input(std::isnan(h) || h > 0, "--h must be > 0 (got " + format_full(h) + ")");
  validate_step_study();
  require_input(ladder == "common" || ladder == "per-method",
                "--ladder must be common or per-method (got '" + ladder + "')");
  given_floor();
}

nlohmann::json ConvergenceSpec::to_json() const {
  nlohmann::json j = step_study_json();
  j["ladder"] = ladder;
  j["floor"] = floor;
  return j;
}

namespace {

// splitmix64 (Steele, Lea & Flood, OOPSLA 2014): the perturbations' deterministic generator.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

Vec perturbed_initial_state(const Vec& y0, int sign) {
  std::uint64_t state = kFloorSeed;
  Vec y = y0;
  // y0 = 0: every component moves by ±kFloorPerturbation (absolute: the solution's scale 1).
  const bool all_zero = !(y0.array() != 0.0).any();
  for (Index i = 0; i < y.size(); ++i) {
    // One draw per component, zero or not, so a component's sign depends on its index only.
    const std::uint64_t r = splitmix64(state);
    const double s = ((r >> 32) & 1U) != 0 ? 1.0 : -1.0;
    if (all_zero)
      y[i] = sign * s * kFloorPerturbation;
    else if (y[i] != 0 && std::isfinite(y[i]))
      y[i] *= 1 + sign * s * kFloorPerturbation;
  }
  return y;
}

std::optional<double> measure_roundoff_floor(
    const Vec& y0, const Vec& y, const std::function<std::optional<Vec>(const Vec&)>& run,
    std::vector<double>* spreads) {
  const std::optional<Vec> up = run(perturbed_initial_state(y0, 1));
  const std::optional<Vec> down = run(perturbed_initial_state(y0, -1));
  auto usable = [&](const std::optional<Vec>& v) {
    return v && v->size() == y.size() && v->allFinite();
  };
  if (!usable(up) || !usable(down)) return std::nullopt;
  const double d = (0.5 * (*up + *down) - y).cwiseAbs().maxCoeff();
  if (spreads) {
    spreads->push_back(max_abs_diff(*up, y));
    spreads->push_back(max_abs_diff(*down, y));
    spreads->push_back(d);
  }
  return std::max(kFloorSecondDifferenceFactor * d,
                  kUnitRoundoff * (y.size() ? y.cwiseAbs().maxCoeff() : 0.0));
}

namespace {

bool declares(const std::vector<ParamSpec>& specs, const std::string& key) {
  for (const auto& p : specs)
    if (p.key == key) return true;
  return false;
}

void add_observed_orders(std::vector<ConvergenceRow>& rows) {
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& a = rows[i - 1];
    auto& b = rows[i];
    if (a.integrator != b.integrator) continue;
    if (a.stats.status != Status::ok || b.stats.status != Status::ok) continue;
    if (!(a.error > 0) || !(b.error > 0)) continue;
    b.observed_order = std::log(a.error / b.error) / std::log(a.h / b.h);
  }
}

std::string progress_line(std::size_t k, std::size_t n, const ConvergenceRow& r) {
  std::ostringstream os;
  os << "[" << k << "/" << n << "] " << r.model << " " << r.integrator << " h=" << format_short(r.h)
     << " error="
     << (r.stats.status == Status::ok ? format_short(r.error) : to_string(r.stats.status)) << " ("
     << format_short(r.stats.wall_s, 2) << " s)\n";
  return os.str();
}

// The user's parameters without those only a --reference integrator declares (it takes them;
// make_setup would call them unknown). A key the model or a studied integrator also declares
// stays, so it reaches them as well.
Params setup_params(const StudyInputs& in, const ConvergenceSpec& spec,
                    const ReferenceRequest& reference) {
  const auto* ref = in.find_integrator(reference.method);
  if (!ref) return spec.params;
  auto declared_elsewhere = [&](const std::string& key) {
    if (declares(in.model_entry().params, key)) return true;
    for (const auto& name : spec.integrators)
      if (declares(in.integrator_entry(name).params, key)) return true;
    return false;
  };
  Params out;
  for (const auto& [key, value] : spec.params.values())
    if (!declares(ref->params, key) || declared_elsewhere(key)) out.set(key, value);
  return out;
}

double inf_norm(CVecRef y) { return y.size() ? y.cwiseAbs().maxCoeff() : 0.0; }

// The per-method probe (see the header): the coarsest step of one integrator's ladder.
// error_at(h): the error of a run at h (NaN when it failed); floor_at(h): the larger floor of a
// run at h; q: the expected slope. calibrate(h), when set, is called once before stage 2 with the
// finest step of the coarsest allowed ladder (--floor auto measures the round-off floor there,
// which floor_at then uses). h_start: the study's coarsest step; span: h0 / h_finest.
double probe_ladder(double h_start, double span, double t_span, bool local, double s, int q,
                    const std::function<double(double)>& error_at,
                    const std::function<double(double)>& floor_at,
                    const std::function<void(double)>& calibrate,
                    ConvergenceResult::Ladder& record) {
  const double target = kLadderTop * s;
  // Not below h/64, nor so small that the finest level would exceed the driver's step limit.
  const double lo =
      std::max(h_start / 64,
               local ? 0.0 : t_span * span / static_cast<double>(FixedStepOptions{}.max_steps));
  const double hi = std::max(lo, local ? 16 * h_start : std::min(16 * h_start, t_span / 4));
  int runs = 0;
  // The usable probes (finite, above the floors): (h, error).
  std::vector<std::pair<double, double>> good;
  auto probe = [&](double h) {
    ++runs;
    const double e = error_at(h);
    record.probes.emplace_back(h, e);
    const bool usable = std::isfinite(e) && e > kFloorFactor * floor_at(h);
    if (usable) good.emplace_back(h, e);
    return e;
  };
  // The error model through the usable probe nearest to h (in log h): e ∝ h^q.
  auto predict = [&](double h) {
    const auto* best = &good.front();
    for (const auto& g : good)
      if (std::abs(std::log(g.first / h)) < std::abs(std::log(best->first / h))) best = &g;
    return best->second * std::pow(h / best->first, q);
  };
  const ProbeBracket b =
      probe_coarsest(std::clamp(h_start, lo, hi), lo, hi, target, q, runs, probe, floor_at);
  if (good.empty()) return b.floor_hit ? hi : lo;
  const double h_top = top_step(b, good, target, lo, hi, q);
  return probe_finest(h_top, lo, span, q, runs, probe, predict, floor_at, calibrate);
}

// One convergence or local-error study in progress: the system, its initial state, the reference
// plan and its check, and the reference values once computed. run_step_study's steps share it.
struct StudyState {
  const ConvergenceSpec& spec;
  ReferenceRequest request;  // the spec's reference, looked up in the study's inputs
  const OdeSystem& sys;
  bool local;
  std::ostream* progress;
  double t0 = 0;
  Vec y0;
  double y0_norm = 0;
  ReferencePlan plan, plan2;
  bool numerical_ref = false;
  Vec ref_end;                             // global: the reference at t_end
  double ref_acc_end = 0;                  // global: its accuracy from the check run (0: none)
  double s_end = 1;                        // the solution's size for the round-off floor
  std::vector<Vec> ref_local, ref2_local;  // local: references at every t0 + h, and the check's

  StudyState(const StudyInputs& in, const ConvergenceSpec& s, const OdeSystem& system,
             bool is_local, std::ostream* out)
      : spec(s),
        request(s.reference_request(&in, s.cache_dir)),
        sys(system),
        local(is_local),
        progress(out) {}

  std::optional<double> given_floor;  // --floor VALUE

  RunResult run_at(Integrator& integ, double h) const { return run_from(integ, h, y0); }
  RunResult run_from(Integrator& integ, double h, const Vec& start) const {
    FixedStepOptions opt;
    opt.t_end = local ? t0 + h : spec.t_end;
    opt.h = h;
    return run_fixed_step_from(sys, integ, t0, start, opt);
  }
  // The model round-off floor N·u·s of a run at h (u·s for the local error).
  double model_floor(double h) const {
    if (local) return kUnitRoundoff * std::max(1.0, y0_norm);
    return static_cast<double>(step_count(h)) * kUnitRoundoff * s_end;
  }
  long step_count(double h) const {
    return local ? 1 : fixed_step_count(t0, spec.t_end, h, FixedStepOptions{}.max_steps);
  }
  // --floor auto: the measured round-off floor of `integ` at step h (measure_roundoff_floor),
  // `y` the unperturbed run's final state; empty when it cannot be measured.
  std::optional<double> measured_floor(Integrator& integ, double h, const Vec& y,
                                       std::vector<double>* spreads) const {
    return measure_roundoff_floor(
        y0, y,
        [&](const Vec& start) -> std::optional<Vec> {
          const RunResult r = run_from(integ, h, start);
          if (r.stats.status != Status::ok) return std::nullopt;
          return r.y;
        },
        spreads);
  }
};

// The reference check run (plan2) at `times`; empty when it fails (a tolerance the reference
// cannot meet), which leaves the study without a reference floor and says so.
std::optional<ReferenceValues> reference_check(StudyState& st, const std::vector<double>& times,
                                               ConvergenceResult& result) {
  try {
    ReferenceValues ref2 = reference_values(st.request, st.sys, st.plan2, times, st.progress);
    result.reference_check_cache = ref2.cache;
    return ref2;
  } catch (const std::runtime_error& e) {
    result.reference_check_description += " (failed: " + std::string(e.what()) + ")";
    if (st.progress) *st.progress << "reference check: " << e.what() << "\n";
    return std::nullopt;
  }
}

// The global study's reference at t_end and its check (the probes need them first).
void global_reference(StudyState& st, ConvergenceResult& result) {
  ReferenceValues ref = reference_values(st.request, st.sys, st.plan, {st.spec.t_end}, st.progress);
  result.reference_cache = ref.cache;
  result.reference_from_cache = ref.from_cache;
  st.ref_end = ref.values[0];
  if (!st.numerical_ref) return;
  if (const auto ref2 = reference_check(st, {st.spec.t_end}, result)) {
    st.ref_acc_end = max_abs_diff(st.ref_end, ref2->values[0]);
    result.reference_accuracy = st.ref_acc_end;
  }
}

// The local study's reference (and its check) at every t0 + h of every ladder.
void local_references(StudyState& st, const std::vector<std::vector<double>>& ladders,
                      ConvergenceResult& result) {
  std::vector<double> ref_times;
  for (const auto& ladder : ladders)
    for (double h : ladder) ref_times.push_back(st.t0 + h);
  ReferenceValues ref = reference_values(st.request, st.sys, st.plan, ref_times, st.progress);
  result.reference_cache = ref.cache;
  result.reference_from_cache = ref.from_cache;
  st.ref_local = std::move(ref.values);
  if (!st.numerical_ref) return;
  if (auto ref2 = reference_check(st, ref_times, result)) {
    st.ref2_local = std::move(ref2->values);
    double worst = 0;
    for (std::size_t k = 0; k < st.ref_local.size(); ++k)
      worst = std::max(worst, max_abs_diff(st.ref_local[k], st.ref2_local[k]));
    result.reference_accuracy = worst;
  }
}

// Per-method ladders: each integrator's h0 from a short probe (probe_ladder), recorded in
// result.ladders.
std::vector<std::vector<double>> per_method_ladders(const StudyState& st, Setup& setup,
                                                    ConvergenceResult& result) {
  const ConvergenceSpec& spec = st.spec;
  const bool local = st.local;
  std::vector<std::vector<double>> ladders;
  for (auto& integ_ptr : setup.integrators) {
    Integrator& integ = *integ_ptr;
    ConvergenceResult::Ladder rec;
    rec.integrator = integ.info().name;
    const int q = std::max(1, integ.info().order + (local ? 1 : 0));
    auto error_at = [&](double h) {
      const RunResult r = st.run_at(integ, h);
      if (r.stats.status != Status::ok) return std::numeric_limits<double>::quiet_NaN();
      if (!local) return max_abs_diff(r.y, st.ref_end);
      // The probe's local reference is computed directly (uncached): one short run.
      return max_abs_diff(r.y, compute_reference(st.request, st.plan, st.sys, {st.t0 + h})[0]);
    };
    // The round-off floor of the probe: given, measured once (calibrate; in proportion to the
    // steps below the measured step) or the model.
    std::optional<double> measured;
    double measured_steps = 1;
    auto roundoff_at = [&](double h) {
      if (st.given_floor) return *st.given_floor;
      if (measured)
        return *measured * std::max(1.0, static_cast<double>(st.step_count(h)) / measured_steps);
      return st.model_floor(h);
    };
    auto floor_at = [&](double h) {
      return local ? roundoff_at(h) : std::max(roundoff_at(h), st.ref_acc_end);
    };
    std::function<void(double)> calibrate;
    if (spec.floor == "auto")
      calibrate = [&](double h) {
        const RunResult r = st.run_at(integ, h);
        if (r.stats.status != Status::ok) return;
        std::vector<double> spreads;
        if (const auto f = st.measured_floor(integ, h, r.y, &spreads)) {
          measured = *f;
          measured_steps = static_cast<double>(st.step_count(h));
          rec.floor_h = h;
          rec.floor = *f;
        }
      };
    rec.h0 = probe_ladder(spec.h, spec.ladder_span(), spec.t_end - st.t0, local,
                          local ? std::max(1.0, st.y0_norm) : st.s_end, q, error_at, floor_at,
                          calibrate, rec);
    ladders.push_back(spec.step_ladder(rec.h0));
    for (double h : ladders.back())
      fixed_step_count(st.t0, spec.t_end, h, FixedStepOptions{}.max_steps);
    if (st.progress)
      *st.progress << "ladder: " << rec.integrator << " h0 = " << format_short(rec.h0) << " after "
                   << rec.probes.size() << " probe run(s)\n";
    result.ladders.push_back(std::move(rec));
  }
  return ladders;
}

// One row: the run at h, its error against the reference (index ref_index of the local ones)
// and its model and reference floors (the round-off floor in use comes later: apply_floor).
// `y_end` receives the run's final state.
ConvergenceRow measure_row(const StudyState& st, Integrator& integ, double h, std::size_t ref_index,
                           const ConvergenceResult& result, Vec& y_end) {
  ConvergenceRow row;
  row.model = st.spec.model;
  row.integrator = integ.info().name;
  row.order = integ.info().order;
  const RunResult r = st.run_at(integ, h);
  y_end = r.y;
  row.h = r.h;
  row.steps = r.stats.steps;  // the steps taken: N unless the run ended early
  row.stats = r.stats;
  const Vec& yref = st.local ? st.ref_local[ref_index] : st.ref_end;
  row.error = r.stats.status == Status::ok ? max_abs_diff(r.y, yref)
                                           : std::numeric_limits<double>::quiet_NaN();
  const double s = std::max({1.0, st.y0_norm, inf_norm(yref)});
  row.roundoff_floor =
      (st.local ? 1.0 : static_cast<double>(std::max(1L, row.steps))) * kUnitRoundoff * s;
  if (st.numerical_ref && result.reference_accuracy)
    row.reference_floor =
        st.local ? max_abs_diff(st.ref_local[ref_index], st.ref2_local[ref_index]) : st.ref_acc_end;
  return row;
}

// The round-off floor of one integrator's rows (--floor): given, the model, or measured by
// perturbed reruns at its finest level that ran ok (`finest_y`: each level's final state).
ConvergenceResult::Floor integrator_floor(const StudyState& st, Integrator& integ,
                                          const std::vector<ConvergenceRow>& rows,
                                          const std::vector<Vec>& finals) {
  ConvergenceResult::Floor fl;
  fl.integrator = integ.info().name;
  if (st.given_floor) {
    fl.value = *st.given_floor;
    fl.source = "given";
    return fl;
  }
  fl.source = "model";
  fl.value = rows.empty() ? 0.0 : rows.back().roundoff_floor;
  if (st.spec.floor == "model") return fl;
  std::size_t finest = rows.size();
  for (std::size_t k = 0; k < rows.size(); ++k)
    if (rows[k].stats.status == Status::ok) finest = k;
  if (finest == rows.size()) {
    fl.note = "no level ran ok: nothing to measure";
    return fl;
  }
  const auto measured = st.measured_floor(integ, rows[finest].h, finals[finest], &fl.spreads);
  fl.h = rows[finest].h;
  fl.steps = std::max(1L, rows[finest].steps);
  if (!measured) {
    fl.note = "a perturbed rerun did not end ok";
    return fl;
  }
  fl.value = *measured;
  fl.source = "perturbed";
  return fl;
}

// The floor in use for a row and its status: at a floor when its error is at most kFloorFactor
// times the round-off floor or (numerical reference) the reference's accuracy. A measured floor
// scales to the row's steps N as √(N/N_f) (N_f: the steps of the measurement).
void apply_floor(ConvergenceRow& row, const ConvergenceResult::Floor& fl, bool numerical_ref) {
  row.floor_used = fl.source == "model" ? row.roundoff_floor : fl.value;
  if (fl.source == "perturbed")
    row.floor_used = fl.value * std::sqrt(static_cast<double>(std::max(1L, row.steps)) /
                                          static_cast<double>(std::max(1L, fl.steps)));
  row.floor_source = fl.source;
  row.at_floor = row.stats.status == Status::ok &&
                 (row.error <= kFloorFactor * row.floor_used ||
                  (numerical_ref && row.error <= kFloorFactor * row.reference_floor));
}

// A measured floor estimates the rounding of a level, it does not observe it: a row within
// kFloorFactor of it (but above kFloorKeepFactor times it) whose pairwise order with the coarser
// usable level is within kOrderTolerance of the expected slope still falls at the method's order,
// so rounding does not set its error; it stays ok (and so may the next level, by the same test).
void keep_rows_still_falling(std::vector<ConvergenceRow>& rows, bool local) {
  for (std::size_t k = 1; k < rows.size(); ++k) {
    ConvergenceRow& r = rows[k];
    const ConvergenceRow& prev = rows[k - 1];
    if (!r.at_floor || prev.at_floor || prev.stats.status != Status::ok || !(prev.error > 0) ||
        !(r.error > 0) || r.error <= kFloorKeepFactor * r.floor_used ||
        r.error <= kFloorFactor * r.reference_floor)
      continue;
    const double q = std::log(prev.error / r.error) / std::log(prev.h / r.h);
    if (std::abs(q - (r.order + (local ? 1 : 0))) <= kOrderTolerance) r.at_floor = false;
  }
}

// The rows of one integrator over its ladder, with its round-off floor applied (progress lines
// to st.progress; `done` of `total` rows so far; ref_index: the row's local reference).
void integrator_rows(StudyState& st, Integrator& integ, const std::vector<double>& ladder,
                     std::size_t& ref_index, std::size_t& done, std::size_t total,
                     ConvergenceResult& result) {
  std::ostream* progress = st.progress;
  std::vector<ConvergenceRow> rows;
  std::vector<Vec> finals;
  for (double h : ladder) {
    finals.emplace_back();
    rows.push_back(measure_row(st, integ, h, ref_index++, result, finals.back()));
    if (progress) *progress << progress_line(++done, total, rows.back()) << std::flush;
  }
  ConvergenceResult::Floor fl = integrator_floor(st, integ, rows, finals);
  if (progress && fl.source != "model")
    *progress << "floor: " << fl.integrator << " " << format_short(fl.value) << " (" << fl.source
              << (fl.source == "perturbed" ? ", two reruns at h = " + format_short(fl.h)
                                           : std::string())
              << ")\n";
  if (progress && !fl.note.empty())
    *progress << "floor: " << fl.integrator << " uses the model N·u·s (" << fl.note << ")\n";
  for (auto& row : rows) apply_floor(row, fl, st.numerical_ref);
  if (fl.source == "perturbed") keep_rows_still_falling(rows, st.local);
  for (auto& row : rows) result.rows.push_back(std::move(row));
  result.floors.push_back(std::move(fl));
}

// The order fit of every integrator, with its analysed order and round-off floor.
void add_fits(const Setup& setup, bool local, ConvergenceResult& result) {
  for (std::size_t i = 0; i < setup.integrators.size(); ++i) {
    const Integrator& integ = *setup.integrators[i];
    OrderFit fit = fit_order(result.rows, integ.info().name, local, result.ladder);
    if (const auto a = coefficient_analysis(integ)) fit.analysed_order = a->order;
    fit.floor_used = result.floors[i].value;
    fit.floor_source = result.floors[i].source;
    result.fits.push_back(std::move(fit));
  }
}

ConvergenceResult run_step_study(const StudyInputs& in, const ConvergenceSpec& spec_in,
                                 std::ostream* progress, bool local) {
  const ConvergenceSpec given = with_inputs(spec_in, in);
  given.validate();
  Setup setup =
      make_setup(in, in.integrators, setup_params(in, given, given.reference_request(&in)));
  const OdeSystem& sys = *setup.model;
  ConvergenceSpec spec = given;
  const Resolved h0 = resolve_step(sys, spec.h, spec.model);
  spec.h = h0.value;
  if (progress && h0.source != "--h")
    *progress << "no --h given: starting from the model's suggested step h = "
              << format_full(spec.h) << " (" << h0.source.substr(16) << ")\n";
  StudyState st(in, spec, sys, local, progress);
  st.t0 = sys.initial_time();
  require_input(spec.t_end > st.t0, "--t-end must be > the model's initial time");
  for (const auto& integ : setup.integrators)
    require_input(
        integ->supports_fixed_step(),
        "integrator '" + integ->info().name +
            "' is adaptive only: a step-size study needs fixed steps (use work-precision)");

  // Actual step sizes are fixed by the driver's N = round(T/h) rule (global study); the local
  // study uses h_k exactly.
  const std::vector<double> hs = spec.step_ladder(spec.h);
  for (double h : hs) fixed_step_count(st.t0, spec.t_end, h, FixedStepOptions{}.max_steps);

  st.plan = plan_reference(st.request, sys, hs.back());
  if (!spec.cache_dir.empty() && st.plan.kind != RefKind::exact) require_output_dir(spec.cache_dir);
  st.numerical_ref = st.plan.kind != RefKind::exact;
  st.plan2 = tighter_plan(st.plan);
  ConvergenceResult result;
  result.reference_description = st.plan.description;
  result.h = spec.h;
  result.h_source = h0.source;
  result.ladder = spec.ladder;
  if (st.numerical_ref) result.reference_check_description = st.plan2.description;

  st.given_floor = spec.given_floor();
  result.floor_mode = spec.floor;
  st.y0 = sys.initial_state();
  st.y0_norm = inf_norm(st.y0);
  if (!local) global_reference(st, result);
  st.s_end = std::max({1.0, st.y0_norm, local ? 0.0 : inf_norm(st.ref_end)});

  const std::vector<std::vector<double>> ladders =
      spec.ladder == "per-method" ? per_method_ladders(st, setup, result)
                                  : std::vector<std::vector<double>>(setup.integrators.size(), hs);
  if (local) local_references(st, ladders, result);

  std::size_t total = 0;
  for (const auto& ladder : ladders) total += ladder.size();
  std::size_t done = 0, ref_index = 0;
  for (std::size_t i = 0; i < setup.integrators.size(); ++i)
    integrator_rows(st, *setup.integrators[i], ladders[i], ref_index, done, total, result);
  add_observed_orders(result.rows);
  add_fits(setup, local, result);
  return result;
}

}  // namespace

ConvergenceResult run_convergence(const StudyInputs& in, const ConvergenceSpec& spec,
                                  std::ostream* progress) {
  return run_step_study(in, spec, progress, false);
}

ConvergenceResult run_local_error(const StudyInputs& in, const ConvergenceSpec& spec,
                                  std::ostream* progress) {
  return run_step_study(in, spec, progress, true);
}

ConvergenceResult run_convergence(const ConvergenceSpec& spec, std::ostream* progress) {
  return run_convergence(inputs_of(spec), spec, progress);
}

ConvergenceResult run_local_error(const ConvergenceSpec& spec, std::ostream* progress) {
  return run_local_error(inputs_of(spec), spec, progress);
}

std::string ConvergenceRow::status_text() const {
  return at_floor ? "floor" : to_string(stats.status);
}

FitPoint fit_point(const ConvergenceRow& row) {
  return FitPoint{row.h,          row.error,           row.stats.status, row.at_floor,
                  row.floor_used, row.reference_floor, row.floor_source};
}

namespace {

// The fit's points of one integrator's rows, in ladder order, and its classical order.
std::vector<FitPoint> points_of(const std::vector<ConvergenceRow>& rows,
                                const std::string& integrator, int* order) {
  std::vector<FitPoint> points;
  for (const auto& r : rows)
    if (r.integrator == integrator) {
      if (points.empty() && order) *order = r.order;
      points.push_back(fit_point(r));
    }
  return points;
}

}  // namespace

OrderFit fit_order(const std::vector<ConvergenceRow>& rows, const std::string& integrator,
                   bool local, const std::string& ladder) {
  int order = 0;
  const std::vector<FitPoint> points = points_of(rows, integrator, &order);
  OrderFit fit = fit_order(points, order, local, ladder);
  fit.integrator = integrator;
  return fit;
}

std::optional<double> fitted_order(const std::vector<ConvergenceRow>& rows,
                                   const std::string& integrator, int points) {
  return fitted_order(points_of(rows, integrator, nullptr), points);
}

std::optional<double> last_observed_order(const std::vector<ConvergenceRow>& rows,
                                          const std::string& integrator) {
  std::optional<double> last;
  for (const auto& r : rows)
    if (r.integrator == integrator) last = r.observed_order;
  return last;
}

namespace {

// convergence and local-error in the study registry: one job type, a table per study.
StudyFunctions<ConvergenceSpec, ConvergenceResult> step_size_functions(bool local) {
  const std::string name = local ? "local_error" : "convergence";
  return {.run = [local](const StudyInputs& in, const ConvergenceSpec& s,
                         std::ostream* progress) { return run_step_study(in, s, progress, local); },
          .unit_table =
              [local](const ConvergenceSpec&, const ConvergenceResult& r) {
                return local ? local_error_table(r) : convergence_table(r);
              },
          .write =
              [local, name](const std::filesystem::path& dir, const ConvergenceSpec& s,
                            const ConvergenceResult& r, const std::string& title,
                            const PlotOptions& plot, std::ostream& err) {
                write_convergence_outputs(dir.string(), name, s, r, local);
                return plot_convergence(dir / (name + ".csv"), title, local, plot, err);
              },
          .print_summary =
              [local](const ConvergenceSpec&, const ConvergenceResult& r, std::ostream& out) {
                out << (local ? local_error_table(r) : convergence_table(r)).to_markdown();
              },
          .report_markdown =
              [local](const ConvergenceSpec&, const ConvergenceResult& r, const std::string& note) {
                std::ostringstream md;
                md << note << " Reference: " << r.reference_description << ". "
                   << floors_sentence(r, local) << "\n\n";
                md << fits_markdown_table(r, local).to_markdown() << "\n";
                return md.str();
              },
          .default_title =
              [local](const ConvergenceSpec& s) {
                return (local ? "Local error: " : "Global error: ") + s.model;
              },
          .helpers = [](const ConvergenceSpec& s) { return s.reference_integrators(); }};
}

const StudyFunctions<ConvergenceSpec, ConvergenceResult> kConvergence = step_size_functions(false);
const StudyFunctions<ConvergenceSpec, ConvergenceResult> kLocalError = step_size_functions(true);

using ConvergenceJob = TypedStudyJob<ConvergenceSpec, ConvergenceResult>;

StudyKind step_size_kind(bool local) {
  StudyKind k;
  k.name = local ? "local-error" : "convergence";
  k.stem = local ? "local_error" : "convergence";
  k.summary = local ? "error of one step from the initial state against h; writes "
                      "local_error.{csv,md,json}"
                    : "global error at t_end against h = H/refine^k; writes "
                      "convergence.{csv,md,json}";
  StepStudyDefaults d;
  d.t_end_help = local ? "unused by the local study's error; kept for symmetry" : "final time";
  d.h_help = "coarsest step size (default: the model's suggested step, where it has one)";
  d.ref_help =
      "exact | METHOD: an adaptive integrator (cvode_bdf, cvode_adams, arkode_*, gsl_*) runs "
      "at --reference-rtol/--reference-atol and stops exactly at the reference times; a fixed-step "
      "one (e.g. rk4) runs at (finest h)/16. Default: exact where the model has one; a model "
      "without one needs --reference. A non-exact reference is cached in OUT/reference/<hash>.csv "
      "and reused by a run of the same build with the same model, parameters, reference and "
      "times";
  d.ref_rtol_note = " (default 1e-12)";
  d.ref_atol_note = " (default rtol/100)";
  k.options = step_study_options(d);
  k.options.push_back(
      {"ladder",
       ParamType::text,
       "common",
       "common: every integrator on h/refine^k; per-method: each integrator's coarsest step "
       "found by a short probe so its errors run from about 1e-2 of the solution's size down to "
       "well above its floor",
       {"common", "per-method"}});
  k.options.push_back(
      {"floor", ParamType::text, "auto",
       "the round-off floor a row must stay 10x above to enter the order fit: auto (measured per "
       "method from two reruns at its finest step with y0 scaled by 1 +- 2^-30), model (N*u*s, "
       "an upper bound) or an absolute error VALUE"});
  k.extra_files = {std::string(local ? "local_error" : "convergence") + "_orders.csv"};
  if (!local) k.required = {"t_end"};
  k.unit_columns =
      (local ? local_error_table(ConvergenceResult{}) : convergence_table(ConvergenceResult{}))
          .columns;
  k.make = [local](const StudyInputs& t, const Params& o, const StudyContext& ctx) {
    ConvergenceSpec spec = with_inputs(ConvergenceSpec{}, t);
    read_step_study_options(o, spec);
    spec.ladder = o.text("ladder");
    spec.floor = o.text("floor");
    spec.cache_dir = ctx.cache_dir;
    spec.validate();
    return std::make_unique<ConvergenceJob>(local ? kLocalError : kConvergence, t, std::move(spec));
  };
  return k;
}

}  // namespace

StudyKind convergence_study_kind() { return step_size_kind(false); }
StudyKind local_error_study_kind() { return step_size_kind(true); }

void add_ladder_metadata(nlohmann::json& meta, const ConvergenceResult& res) {
  meta["ladder"] = res.ladder;
  if (res.ladders.empty()) return;
  nlohmann::json lad = nlohmann::json::array();
  for (const auto& l : res.ladders) {
    nlohmann::json probes = nlohmann::json::array();
    for (const auto& [h, e] : l.probes)
      probes.push_back({{"h", h}, {"error", std::isfinite(e) ? nlohmann::json(e) : nullptr}});
    nlohmann::json entry = {{"integrator", l.integrator}, {"h0", l.h0}, {"probes", probes}};
    if (l.floor_h > 0) entry["probe_floor"] = {{"h", l.floor_h}, {"floor", l.floor}};
    lad.push_back(entry);
  }
  meta["ladders"] = lad;
}

const ConvergenceResult& convergence_result(const StudyJob& job) {
  return typed_result<ConvergenceSpec, ConvergenceResult>(job);
}

ConvergenceResult convergence_study(ConvergenceSpec spec, const std::string& dir, bool local,
                                    std::ostream* progress, std::ostream& err,
                                    const PlotOptions& plot) {
  StudyContext ctx;
  ctx.force = force_output();
  ctx.plot = plot;
  ctx.progress = progress;
  ctx.err = &err;
  const StudyInputs in = inputs_of(spec);
  return convergence_study(in, std::move(spec), dir, local, ctx);
}

ConvergenceResult convergence_study(const StudyInputs& in, ConvergenceSpec spec,
                                    const std::filesystem::path& dir, bool local,
                                    const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  if (spec.cache_dir.empty()) spec.cache_dir = ctx.cache_dir.empty() ? dir.string() : ctx.cache_dir;
  spec.validate();
  ConvergenceJob job(local ? kLocalError : kConvergence, in, std::move(spec));
  run_study_job(study_kind(local ? "local-error" : "convergence"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
