// The tables, Markdown and metadata of convergence and local-error (their CSV contracts and the
// NAME.{csv,md,json} files).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>

#include "experiments/studies/convergence.hpp"
#include "experiments/studies/convergence_output.hpp"

namespace stiffbench {

namespace {

// %g: the documented constants in sentences (10, 0.2, 0.01).
std::string g_short(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

std::string optional_full(const std::optional<double>& x) { return x ? format_full(*x) : ""; }

}  // namespace

namespace {

// The columns every row of both tables ends with, after the existing ones.
void add_trailing_columns(Table& t) {
  for (const auto& c : SolveStats::counter_names()) t.columns.push_back(c);
  t.columns.push_back("roundoff_floor");
  t.columns.push_back("reference_floor");
  t.columns.push_back("floor_used");
  t.columns.push_back("floor_source");
}

void add_trailing_values(std::vector<std::string>& row, const ConvergenceRow& r) {
  for (const auto& v : r.stats.counter_values()) row.push_back(v);
  row.push_back(format_full(r.roundoff_floor));
  row.push_back(format_full(r.reference_floor));
  row.push_back(format_full(r.floor_used));
  row.push_back(r.floor_source);
}

}  // namespace

Table convergence_table(const ConvergenceResult& res) {
  Table t{{"model", "integrator", "order", "h", "steps", "error", "observed_order", "f_evals",
           "jac_evals", "lin_solves", "wall_s", "status"},
          {}};
  add_trailing_columns(t);
  for (const auto& r : res.rows) {
    std::vector<std::string> row = {r.model,
                                    r.integrator,
                                    std::to_string(r.order),
                                    format_full(r.h),
                                    std::to_string(r.steps),
                                    r.stats.status == Status::ok ? format_full(r.error) : "",
                                    optional_full(r.observed_order),
                                    std::to_string(r.stats.f_evals),
                                    std::to_string(r.stats.jac_evals),
                                    SolveStats::count_text(r.stats.lin_solves),
                                    format_full(r.stats.wall_s),
                                    r.status_text()};
    add_trailing_values(row, r);
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table local_error_table(const ConvergenceResult& res) {
  Table t{{"model", "integrator", "order", "h", "local_error", "observed_order", "status",
           "f_evals", "jac_evals", "lin_solves"},
          {}};
  add_trailing_columns(t);
  for (const auto& r : res.rows) {
    std::vector<std::string> row = {r.model,
                                    r.integrator,
                                    std::to_string(r.order),
                                    format_full(r.h),
                                    r.stats.status == Status::ok ? format_full(r.error) : "",
                                    optional_full(r.observed_order),
                                    r.status_text(),
                                    std::to_string(r.stats.f_evals),
                                    std::to_string(r.stats.jac_evals),
                                    SolveStats::count_text(r.stats.lin_solves)};
    add_trailing_values(row, r);
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table orders_table(const ConvergenceResult& res) {
  Table t{{"integrator", "order", "analysed_order", "fitted_order", "fitted_order_se", "h_min",
           "h_max", "levels_used", "reason", "floor_used", "floor_source"},
          {}};
  for (const auto& f : res.fits)
    t.rows.push_back({f.integrator, std::to_string(f.order),
                      f.analysed_order ? std::to_string(*f.analysed_order) : "",
                      optional_full(f.fitted), optional_full(f.fitted_se),
                      f.fitted ? format_full(f.h_min) : "", f.fitted ? format_full(f.h_max) : "",
                      std::to_string(f.levels_used), f.reason, format_full(f.floor_used),
                      f.floor_source});
  return t;
}

// The summary of the fits: the fitted order with its window; the verdict uses the fitted order.
Table fits_markdown_table(const ConvergenceResult& res, bool local) {
  Table t{{"integrator", local ? "expected slope (order+1)" : "order", "fitted", "± SE", "window h",
           "levels used", "within 0.1", "reason"},
          {}};
  for (const auto& f : res.fits) {
    const bool fitted = f.fitted.has_value();
    t.rows.push_back(
        {f.integrator, std::to_string(f.expected_slope), fitted ? format_fixed(*f.fitted) : "-",
         fitted ? format_fixed(*f.fitted_se) : "",
         fitted ? format_short(f.h_min) + " – " + format_short(f.h_max) : "",
         std::to_string(f.levels_used),
         fitted ? (std::abs(*f.fitted - f.expected_slope) <= kOrderTolerance ? "yes" : "no") : "-",
         f.reason});
  }
  return t;
}

// The floors, in words, for the Markdown and the report.
std::string floors_sentence(const ConvergenceResult& res, bool local) {
  std::ostringstream os;
  const std::string model =
      std::string(local ? "u·s" : "N·u·s") + ", u = 2^-53, s = max(1, ‖y0‖∞, ‖y_ref‖∞)";
  os << "Rows with status `floor` have an error within " << g_short(kFloorFactor)
     << "× the round-off floor (";
  if (res.floor_mode == "auto") {
    int measured = 0;
    for (const auto& f : res.floors) measured += f.source == "perturbed" ? 1 : 0;
    os << "measured per method from two reruns at its finest step from y0 scaled by 1 ± 2^-30 "
          "per component: twice the max-norm of (y₊ + y₋)/2 − y, the part of the result that "
          "is rounding"
       << (local ? "" : ", times √(N/N_f) at a level of N steps") << "; the `floor_used` column";
    if (measured < static_cast<int>(res.floors.size()))
      os << "; the model " << model << " for " << res.floors.size() - measured
         << " method(s) with nothing to measure";
    os << "; a row above a measured floor whose pairwise order is within "
       << g_short(kOrderTolerance) << " of the expected slope stays ok";
  } else if (res.floor_mode == "model") {
    os << "the model " << model << ", from --floor model";
  } else {
    os << "--floor " << res.floor_mode;
  }
  os << ")";
  if (res.reference_accuracy)
    os << " or the reference's accuracy (≈ " << format_short(*res.reference_accuracy)
       << (local ? " at worst" : "") << ", from a second run: " << res.reference_check_description
       << ")";
  os << "; fits leave them out. The fitted order is the least-squares slope over the longest run "
        "of consecutive levels above the floors whose pairwise orders agree within "
     << g_short(kOrderAgreement) << ".";
  if (res.ladder == "per-method")
    os << " Per-method ladders: each method's steps come from a probe (coarsest error at most "
          "about "
       << g_short(kLadderTop) << "·s, finest about " << g_short(kLadderFloorMargin)
       << "× the floors where the ladder's length allows).";
  return os.str();
}

namespace {

std::string markdown_report(const std::string& name, const ConvergenceSpec& spec,
                            const ConvergenceResult& res, bool local) {
  std::ostringstream os;
  os << "# " << (local ? "Local error" : "Convergence") << ": " << spec.model << "\n\n";
  os << "Error: max-norm "
     << (local ? "after one step of size h from the initial state"
               : "at t_end = " + format_full(spec.t_end))
     << "; reference: " << res.reference_description;
  if (!res.reference_cache.empty())
    os << " (values in `reference/"
       << std::filesystem::path(res.reference_cache).filename().string() << "`"
       << (res.reference_from_cache ? ", reused from an earlier run" : "") << ")";
  os << ".";
  if (!spec.params.empty()) {
    os << " Parameters:";
    for (const auto& [k, v] : spec.params.values()) os << " " << k << "=" << v;
    os << ".";
  }
  os << "\n\n";
  os << floors_sentence(res, local) << "\n\n";
  os << fits_markdown_table(res, local).to_markdown() << "\n";
  Table detail = local ? local_error_table(res) : convergence_table(res);
  // Shorter numbers in the Markdown copy; the CSV keeps full precision.
  for (auto& row : detail.rows)
    for (std::size_t c = 0; c < detail.columns.size(); ++c) {
      const auto& col = detail.columns[c];
      if ((col == "h" || col == "error" || col == "local_error" || col == "wall_s" ||
           col == "roundoff_floor" || col == "reference_floor" || col == "floor_used") &&
          !row[c].empty())
        row[c] = format_short(std::stod(row[c]), col == "wall_s" ? 2 : 3);
      if (col == "observed_order" && !row[c].empty()) row[c] = format_fixed(std::stod(row[c]));
    }
  os << detail.to_markdown();
  std::vector<RunNote> notes;
  for (const auto& r : res.rows)
    notes.push_back({r.integrator + ", h = " + format_short(r.h), &r.stats});
  os << failed_runs_markdown(notes);
  os << "\nFull-precision values: `" << name << ".csv`; order fits: `" << name
     << "_orders.csv`; metadata: `" << name << ".json`.\n";
  return os.str();
}

}  // namespace

void write_convergence_outputs(const std::string& dir, const std::string& name,
                               const ConvergenceSpec& spec, const ConvergenceResult& res,
                               bool local) {
  const std::filesystem::path d(dir);
  const Table t = local ? local_error_table(res) : convergence_table(res);
  write_file_atomic(d / (name + ".csv"), t.to_csv());
  write_file_atomic(d / (name + "_orders.csv"), orders_table(res).to_csv());
  write_file_atomic(d / (name + ".md"), markdown_report(name, spec, res, local));
  // "spec" is the spec as given (what check_study_output compares before a run); the step it
  // resolved to is recorded beside it.
  nlohmann::json meta = run_metadata(local ? "local-error" : "convergence", spec.to_json());
  add_step_study_metadata(meta, res.h, res.h_source, res.reference_description);
  if (!res.reference_cache.empty()) {
    meta["reference_cache"] = res.reference_cache;
    meta["reference_from_cache"] = res.reference_from_cache;
  }
  meta["error_norm"] = "max-norm of the absolute error";
  meta["floor_factor"] = kFloorFactor;
  meta["unit_roundoff"] = kUnitRoundoff;
  meta["roundoff_floor"] =
      local ? "u*s, s = max(1, |y0|inf, |y_ref|inf)" : "N*u*s, s = max(1, |y0|inf, |y_ref|inf)";
  meta["floor"] = res.floor_mode;
  meta["floor_perturbation"] = kFloorPerturbation;
  meta["floor_seed"] = kFloorSeed;
  nlohmann::json floors = nlohmann::json::array();
  for (const auto& f : res.floors) {
    nlohmann::json j = {{"integrator", f.integrator}, {"floor", f.value}, {"source", f.source}};
    if (f.source == "perturbed" || !f.spreads.empty()) {
      j["h"] = f.h;
      j["steps"] = f.steps;
      nlohmann::json sp = nlohmann::json::array();
      for (double x : f.spreads) sp.push_back(std::isfinite(x) ? nlohmann::json(x) : nullptr);
      j["spreads"] = sp;
    }
    if (!f.note.empty()) j["note"] = f.note;
    floors.push_back(j);
  }
  meta["floors"] = floors;
  meta["order_agreement"] = kOrderAgreement;
  if (res.reference_accuracy) {
    meta["reference_check"] = res.reference_check_description;
    meta["reference_accuracy"] = *res.reference_accuracy;
    if (!res.reference_check_cache.empty())
      meta["reference_check_cache"] = res.reference_check_cache;
  }
  if (!res.reference_accuracy && !res.reference_check_description.empty())
    meta["reference_check"] = res.reference_check_description;
  add_ladder_metadata(meta, res);
  write_file_atomic(d / (name + ".json"), meta.dump(2) + "\n");
}

}  // namespace stiffbench
