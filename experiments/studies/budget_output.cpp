#include "experiments/studies/budget_output.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>

#include "experiments/support/invariant_error.hpp"
#include "experiments/support/timing.hpp"

namespace stiffbench {

using budget_internal::best_markdown;
using budget_internal::budget_markdown_table;
using budget_internal::families_markdown;
using budget_internal::kIterationsKey;
using budget_internal::kSubstepsKey;

namespace {

std::string opt_full(double v) { return std::isnan(v) ? "" : format_full(v); }
std::string opt_short(double v, int digits = 3) {
  return std::isnan(v) ? "" : format_short(v, digits);
}

}  // namespace

Table budget_table(const BudgetResult& r) {
  Table t{{"model",
           "integrator",
           kSubstepsKey,
           kIterationsKey,
           "total_iterations",
           "h",
           "ms_per_frame_median",
           "ms_per_frame_min",
           "ms_per_frame_max",
           "ms_per_frame_ci_low",
           "ms_per_frame_ci_high",
           "timed_runs",
           "strain_max",
           "strain_rms",
           "strain_peak",
           "strain_error_max",
           "strain_error_rms",
           "constraint_residual",
           "constraint_residual_peak",
           "energy_rel",
           "angular_momentum_drift",
           "fits",
           "status"},
          {}};
  for (const auto& row : r.rows) {
    const auto total = row.total_iterations();
    t.rows.push_back({r.model,
                      row.integrator,
                      std::to_string(row.substeps),
                      row.iterations ? std::to_string(*row.iterations) : "",
                      total ? std::to_string(*total) : "",
                      format_full(row.h),
                      opt_full(row.ms.median),
                      opt_full(row.ms.min),
                      opt_full(row.ms_max),
                      opt_full(row.ms.ci_low),
                      opt_full(row.ms.ci_high),
                      std::to_string(row.ms.repeats),
                      opt_full(row.strain_max),
                      opt_full(row.strain_rms),
                      opt_full(row.strain_peak),
                      opt_full(row.strain_error_max),
                      opt_full(row.strain_error_rms),
                      opt_full(row.constraint),
                      opt_full(row.constraint_peak),
                      opt_full(row.energy_rel),
                      row.angular_drift ? format_full(*row.angular_drift) : "",
                      row.fits ? "yes" : "no",
                      to_string(row.stats.status)});
  }
  return t;
}

const BudgetRow* best_at_budget(const BudgetResult& r, const std::string& integrator) {
  const BudgetRow* best = nullptr;
  for (const auto& row : r.rows) {
    if (row.integrator != integrator || !row.fits || std::isnan(row.error())) continue;
    if (!best || row.error() < best->error()) best = &row;
  }
  return best;
}

std::vector<BudgetFamily> equal_total_families(const BudgetResult& r) {
  std::map<std::pair<std::string, long>, std::vector<const BudgetRow*>> groups;
  std::vector<std::pair<std::string, long>> order;
  for (const auto& row : r.rows) {
    const auto total = row.total_iterations();
    if (!total) continue;
    const auto key = std::make_pair(row.integrator, *total);
    if (!groups.count(key)) order.push_back(key);
    groups[key].push_back(&row);
  }
  // Each method's families by increasing total, methods in the order of the table.
  std::map<std::string, std::size_t> first;
  for (const auto& key : order) first.emplace(key.first, first.size());
  std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
    return first.at(a.first) != first.at(b.first) ? first.at(a.first) < first.at(b.first)
                                                  : a.second < b.second;
  });
  std::vector<BudgetFamily> out;
  for (const auto& key : order) {
    auto rows = groups[key];
    if (rows.size() < 2) continue;
    std::sort(rows.begin(), rows.end(),
              [](const BudgetRow* a, const BudgetRow* b) { return a->substeps < b->substeps; });
    BudgetFamily f{key.first, key.second, rows, true, true};
    for (const BudgetRow* row : rows) f.all_ok = f.all_ok && !std::isnan(row->error());
    for (std::size_t i = 1; i < rows.size(); ++i)
      f.falls = f.falls && rows[i]->error() < rows[i - 1]->error();
    f.falls = f.falls && f.all_ok;
    out.push_back(std::move(f));
  }
  return out;
}

namespace {

std::string config_name(const BudgetRow& row) {
  return std::to_string(row.substeps) + (row.iterations ? "×" + std::to_string(*row.iterations)
                                         : row.substeps == 1 ? " substep"
                                                             : " substeps");
}

std::string ms_text(const BudgetRow& row) {
  if (std::isnan(row.ms.median)) return "";
  return format_short(row.ms.median, 3) + " [" + format_short(row.ms.min, 3) + ", " +
         format_short(row.ms_max, 3) + "]";
}

}  // namespace

namespace budget_internal {

Table budget_markdown_table(const BudgetResult& r) {
  const bool has_ref = r.error_measure == "strain_error_max";
  const bool springs = has_ref || r.error_measure == "strain_max";
  const bool constraints = r.error_measure == "constraint_residual";
  bool angular = false;
  for (const auto& row : r.rows) angular = angular || row.angular_drift.has_value();
  Table t{{"integrator", "substeps × iterations", "total", "h", "ms/frame median [min, max]"}, {}};
  if (springs) t.columns.insert(t.columns.end(), {"strain max", "strain rms", "strain peak"});
  if (has_ref) t.columns.insert(t.columns.end(), {"strain error max", "strain error rms"});
  if (constraints) t.columns.insert(t.columns.end(), {"constraint", "constraint peak"});
  t.columns.push_back("energy rel");
  if (angular) t.columns.push_back("L drift");
  t.columns.insert(t.columns.end(), {"fits", "status"});
  for (const auto& row : r.rows) {
    const auto total = row.total_iterations();
    std::vector<std::string> out = {row.integrator, config_name(row),
                                    total ? std::to_string(*total) : "", format_short(row.h, 4),
                                    ms_text(row)};
    if (springs)
      for (double v : {row.strain_max, row.strain_rms, row.strain_peak})
        out.push_back(opt_short(v));
    if (has_ref)
      for (double v : {row.strain_error_max, row.strain_error_rms}) out.push_back(opt_short(v));
    if (constraints)
      for (double v : {row.constraint, row.constraint_peak}) out.push_back(opt_short(v));
    out.push_back(opt_short(row.energy_rel));
    if (angular) out.push_back(row.angular_drift ? format_short(*row.angular_drift) : "");
    out.push_back(row.fits ? "yes" : "no");
    out.push_back(to_string(row.stats.status));
    t.rows.push_back(std::move(out));
  }
  return t;
}

std::string best_markdown(const BudgetResult& r, const std::vector<std::string>& integrators) {
  std::ostringstream md;
  const std::string err = r.error_measure.empty() ? "error" : r.error_measure;
  md << "## Best configuration at the frame budget (" << format_short(1e3 * r.frame, 4)
     << " ms/frame)\n\nThe smallest " << err
     << " among the configurations that are ok and fit.\n\n";
  for (const auto& name : integrators) {
    md << "- **" << name << "**: ";
    if (const BudgetRow* b = best_at_budget(r, name)) {
      md << config_name(*b) << " (h = " << format_short(b->h, 4) << "): " << err << " "
         << format_short(b->error()) << " at " << format_short(b->ms.median, 3) << " ms/frame\n";
    } else {
      int fits = 0;
      for (const auto& row : r.rows) fits += row.integrator == name && row.fits;
      md << (r.error_measure.empty() ? "no error measure for this model"
             : fits == 0             ? "no configuration fits the frame budget"
                                     : "no configuration that fits has a finite error")
         << "\n";
    }
  }
  return md.str();
}

std::string families_markdown(const BudgetResult& r) {
  const auto families = equal_total_families(r);
  if (families.empty() || r.error_measure.empty()) return "";
  std::ostringstream md;
  md << "\n## Equal total iterations: substeps against iterations\n\nAt a constant substeps × "
        "iterations per frame, Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke and Müller "
        "(\"Small steps in physics simulation\", SCA 2019) found that more substeps with fewer "
        "iterations give a smaller constraint error for XPBD. Per family, "
     << r.error_measure << " by ascending substeps:\n\n";
  for (const auto& f : families) {
    md << "- " << f.integrator << ", total " << f.total << ": ";
    for (std::size_t i = 0; i < f.rows.size(); ++i)
      md << (i ? ", " : "") << config_name(*f.rows[i]) << " " << opt_short(f.rows[i]->error());
    md << " — "
       << (!f.all_ok ? "not every configuration ran ok"
           : f.falls ? "falls monotonically with substeps"
                     : "does not fall monotonically with substeps")
       << "\n";
  }
  return md.str();
}

}  // namespace budget_internal

void write_budget_outputs(const std::filesystem::path& dir, const BudgetSpec& spec,
                          const BudgetResult& r) {
  write_file_atomic(dir / "budget.csv", budget_table(r).to_csv());
  std::ostringstream md;
  md << "# Frame budget: " << spec.model << "\n\n"
     << r.frame_count << " frames of " << format_short(r.frame, 6) << " s (budget "
     << format_short(1e3 * r.frame, 4)
     << " ms/frame) from the model's initial state; h = "
        "frame/substeps. Wall time: the frame loop (set-up in reset() excluded) per frame, the "
        "median [min, max] over up to "
     << spec.timing_repeats << " runs per configuration in rounds shuffled with seed " << spec.seed
     << ". ";
  if (r.error_measure == "strain_max" || r.error_measure == "strain_error_max") {
    md << "Strain: |l - L|/L over every spring with k > 0 and L > 0 (the cloth: structural, shear "
          "and bend), largest and RMS at the last frame, peak: the largest over the frames; the "
          "initial state's largest strain is "
       << format_short(r.initial_strain_max) << ". ";
    // 1e-12: above the round-off of a grid at its rest lengths (~1e-15).
    if (r.error_measure == "strain_error_max")
      md << "Strain error: |strain_i - strain_i(reference)| over the springs at the last frame, "
            "largest and RMS: the error of the motion's stretch, not the stretch itself (which "
            "holds the true motion's own strain, e.g. of the cloth's `perturbation`); "
         << r.ref_note << ". ";
    else if (r.initial_strain_max > 1e-12)
      md << "The scene does not start at its rest lengths (e.g. the cloth's `perturbation`), so "
            "the strain measured includes what is left of that initial stretch, which larger "
            "steps damp faster ("
         << r.ref_note << "). ";
  } else if (r.error_measure == "constraint_residual")
    md << "Constraint: the model's constraint residual max |C| at the last frame and its peak "
          "over the frames. ";
  else
    md << "The model has neither springs nor constraints: no stretch or constraint error (the "
          "columns are empty and no plot is drawn). ";
  for (const auto& row : r.rows)
    if (row.angular_drift) {
      md << "L drift: the largest |L_c(end) - L_c(0)| over the model's angular momentum "
            "components, relative to |L_c(0)| unless that is <= "
         << format_short(kZeroInvariant, 1) << " (then absolute). ";
      break;
    }
  md << "energy rel: (E_N - E_0)/max(|E_0|, the largest kinetic energy over the frames). "
        "fits: ok and median ms/frame <= the frame time.\n\n"
     << budget_markdown_table(r).to_markdown() << "\n"
     << best_markdown(r, spec.integrators) << families_markdown(r);
  std::vector<RunNote> notes;
  for (const auto& row : r.rows)
    notes.push_back({row.integrator + " " + config_name(row), &row.stats});
  md << failed_runs_markdown(notes) << "\nFull precision: `budget.csv`; metadata: `budget.json`.\n";
  write_file_atomic(dir / "budget.md", md.str());
  nlohmann::json meta = run_metadata("budget", spec.to_json());
  meta["error_measure"] = r.error_measure;
  meta["initial_strain_max"] = r.initial_strain_max;
  meta["strain_reference"] = r.ref_note;
  if (!r.ref_strains.empty()) meta["strain_reference_check"] = r.ref_check;
  meta["timing"] = {{"seed", spec.seed},
                    {"max_runs", spec.timing_repeats},
                    {"repeat_long_run_s", kRepeatLongRun},
                    {"repeat_budget_s", kRepeatBudget},
                    {"bootstrap_resamples", kBootstrapResamples},
                    {"ms_per_frame", "frame loop wall time / frames (reset() excluded)"}};
  meta["energy_rel"] =
      "(E_N - E_0) / max(|E_0|, max over frames of 1/2 v^T M v); |E_0| left out when the "
      "energy's zero is arbitrary (gravity's potential zero at x = 0)";
  write_file_atomic(dir / "budget.json", meta.dump(2) + "\n");
}

bool plot_budget(const std::filesystem::path& csv, const std::string& title, const PlotOptions& opt,
                 std::ostream& err) {
  std::filesystem::path stem = csv;
  stem.replace_extension();
  const auto model = csv_column_values(csv, "model");
  const auto strain = csv_column_values(csv, "strain_max");
  const auto strain_error = csv_column_values(csv, "strain_error_max");
  bool has_ref = false;
  for (const auto& v : strain_error) has_ref = has_ref || !v.empty();
  const auto constraint = csv_column_values(csv, "constraint_residual");
  const bool springs = strain.size() > 1 || (strain.size() == 1 && !strain[0].empty());
  const bool constrained =
      constraint.size() > 1 || (constraint.size() == 1 && !constraint[0].empty());
  if (!springs && !constrained) return false;
  const Table cols = budget_table(BudgetResult{});
  const auto index = [&](const std::string& name) {
    return std::to_string(std::find(cols.columns.begin(), cols.columns.end(), name) -
                          cols.columns.begin() + 1);
  };
  // The frame budget from the JSON beside the CSV (1/60 s when it is missing).
  double frame = 1.0 / 60.0;
  std::filesystem::path json = csv;
  json.replace_extension(".json");
  try {
    std::ifstream in(json);
    if (in) frame = nlohmann::json::parse(in).at("spec").at("frame").get<double>();
  } catch (const std::exception&) {
  }
  const std::vector<std::string> methods = csv_column_values(csv, "integrator");
  return run_plot(
      "budget.gp", stem,
      {{"csvfile", csv.string()},
       {"ttl", title},
       {"xcol", index("ms_per_frame_median")},
       {"ycol", index(has_ref   ? "strain_error_max"
                      : springs ? "strain_max"
                                : "constraint_residual")},
       {"ylab", has_ref   ? "largest strain error |strain - strain(ref)| at the last frame"
                : springs ? "largest relative strain |l - L|/L at the last frame"
                          : "constraint residual max |C| at the last frame"},
       {"budget_ms", format_full(1e3 * frame)}},
      {PlotPanel{"all methods", methods}}, opt, err);
}

}  // namespace stiffbench
