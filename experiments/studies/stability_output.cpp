#include "experiments/studies/stability_output.hpp"

#include <algorithm>
#include <ostream>
#include <sstream>

#include "experiments/studies/stability_search.hpp"

namespace stiffbench {

using stability_internal::num;

namespace {

std::string cell(const std::optional<double>& x) { return x ? format_full(*x) : ""; }

}  // namespace

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

void print_stability_summary(const StabilitySpec& spec, const StabilityResult& r,
                             std::ostream& out) {
  out << stability_table(r).to_markdown();
  for (const auto& f : r.fits)
    if (f.measured_slope)
      out << "slope of log h_max vs log " << spec.sweep_param << ", " << f.integrator << ": "
          << format_fixed(*f.measured_slope, 3)
          << (f.predicted_slope ? " (predicted " + format_fixed(*f.predicted_slope, 3) + ")"
                                : std::string())
          << "\n";
}

std::string stability_report_markdown(const StabilitySpec& spec, const StabilityResult& res,
                                      const std::string& note) {
  std::ostringstream md;
  md << note << " Spectrum: " << res.spectrum_source << ".";
  if (!res.explicit_spectrum_source.empty())
    md << " IMEX and splitting methods are predicted from their explicit treatment on the "
          "spectrum of f_E: "
       << res.explicit_spectrum_source << ".";
  md << "\n\n";
  Table summary{{"integrator", "statuses", "h_max/predicted (range)", "slope of log h_max",
                 "predicted slope"},
                {}};
  for (const auto& name : spec.integrators) {
    std::string statuses;
    double rmin = 1e300, rmax = -1e300;
    for (const auto& r : res.rows) {
      if (r.integrator != name) continue;
      if (statuses.find(r.status) == std::string::npos)
        statuses += (statuses.empty() ? "" : ", ") + r.status;
      if (r.status == "ok" && r.h_measured && r.h_predicted && *r.h_predicted > 0) {
        rmin = std::min(rmin, *r.h_measured / *r.h_predicted);
        rmax = std::max(rmax, *r.h_measured / *r.h_predicted);
      }
    }
    std::string slope = "-", pslope = "-";
    for (const auto& f : res.fits)
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

}  // namespace stiffbench
