#include "experiments/studies/fidelity_output.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>

namespace stiffbench {

namespace fs = std::filesystem;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

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
// measured points (the analytic value recomputed at the measured ν; FidelityResult::analytic).
Table agreement_table(const FidelityResult& r) {
  Table t;
  t.columns = {"integrator",       "measured on",  "measured points",
               "max dA/max(1, A)", "max d(theta)", "on the curve"};
  for (const auto& a : r.analytic) {
    const std::string& name = a.integrator;
    const long count = a.measured;
    std::string verdict = "no stability data (measured only)";
    if (a.curve)
      verdict =
          count == 0 ? "not measured" : (a.max_da <= 1e-6 && a.max_dtheta <= 1e-6 ? "yes" : "NO");
    for (const auto& [n, why] : r.skipped)
      if (n == name) verdict = "not measured: " + why;
    std::string on;
    for (const auto& [n, label] : r.measured_on)
      if (n == name) on = label;
    t.rows.push_back({name, on, std::to_string(count),
                      a.stability && count ? format_short(a.max_da) : "",
                      a.stability && count ? format_short(a.max_dtheta) : "", verdict});
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
Table glance_table(const FidelityResult& r) {
  Table t;
  t.columns = {"integrator", "nu", "amplification", "damping ratio", "period error"};
  for (const auto& an : r.analytic)
    for (const auto& a : an.glance)
      t.rows.push_back({an.integrator, format_short(a.nu), format_short(a.amplification, 6),
                        format_short(a.damping_ratio, 4), format_short(a.period_error, 4)});
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
     << glance_table(r).to_markdown() << "\n"
     << "## Measured against analytic\n\n"
     << agreement_table(r).to_markdown() << "\n";
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

}  // namespace

namespace fidelity_internal {

bool write_fidelity_outputs(const fs::path& dir, const FidelitySpec& spec, const FidelityResult& r,
                            const std::string& title, const PlotOptions& plot, std::ostream& err) {
  write_file_atomic(dir / "fidelity.csv", fidelity_table(r).to_csv());
  write_file_atomic(dir / "modes.csv", modes_table(r).to_csv());  // header only without --model
  write_file_atomic(dir / "fidelity.md", markdown(spec, r));
  nlohmann::json meta = run_metadata("fidelity", spec.to_json());
  meta["rest_state_applied"] = r.rest_state_applied;
  meta["mode_steps_used"] = r.mode_steps_used;
  nlohmann::json skipped = nlohmann::json::object();
  for (const auto& [n, why] : r.skipped) skipped[n] = why;
  meta["not_measured"] = skipped;
  write_file_atomic(dir / "fidelity.json", meta.dump(2) + "\n");
  return plot_fidelity(dir, title, plot, err, spec.integrators, !spec.model.empty());
}

void print_fidelity_summary(const FidelitySpec& spec, const FidelityResult& r, std::ostream& out) {
  if (!r.rest_state_applied.empty()) {
    std::string list;
    for (const auto& kv : r.rest_state_applied) list += (list.empty() ? "" : ", ") + kv;
    out << "Modes of " + spec.model + " at its rest state: " + list +
               " applied (the defaults load or displace it; the modes are those of an "
               "equilibrium)."
        << "\n\n";
  }
  out << agreement_table(r).to_markdown();
  if (!r.modes.empty()) out << "\n" << mode_summary(r).to_markdown();
}

std::string fidelity_report_markdown(const FidelitySpec& spec, const FidelityResult& r,
                                     const std::string& note) {
  std::string md = note + "\n\n" + glance_table(r).to_markdown() + "\n" +
                   agreement_table(r).to_markdown() + "\n" + unfitted_summary(r);
  if (!r.modes.empty())
    md += "Per mode of " + spec.model + " (modes.png, modes.csv):\n\n" +
          mode_summary(r).to_markdown() + "\n";
  return md;
}

}  // namespace fidelity_internal

}  // namespace stiffbench
