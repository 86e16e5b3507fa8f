#include "experiments/commands/plot.hpp"

#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/csv.hpp"
#include "experiments/studies/analyze.hpp"
#include "experiments/studies/budget.hpp"
#include "experiments/studies/energy.hpp"
#include "experiments/studies/region.hpp"
#include "experiments/studies/stability.hpp"

namespace stiffbench {

namespace {

namespace fs = std::filesystem;

using Replotter = std::function<bool(const fs::path& csv, const std::string& title,
                                     const PlotOptions& opt, std::ostream& err)>;

// How a table is redrawn: the plot's title prefix, its plot function, and the table beside it
// that has a `family` column for the integrators (empty: the table itself, when it has one).
struct Replot {
  std::string title;
  Replotter draw;
  std::string families = {};
};

// The plot of each table stiffbench writes, by file name.
const std::map<std::string, Replot>& replotters() {
  static const std::map<std::string, Replot> table = {
      {"convergence.csv",
       {"Global error", [](const fs::path& csv, const std::string& t, const PlotOptions& o,
                           std::ostream& e) { return plot_convergence(csv, t, false, o, e); }}},
      {"local_error.csv",
       {"Local error", [](const fs::path& csv, const std::string& t, const PlotOptions& o,
                          std::ostream& e) { return plot_convergence(csv, t, true, o, e); }}},
      {"work_precision.csv", {"Work-precision", plot_work_precision}},
      {"stability.csv", {"Stability limit", plot_stability}},
      {"energy.csv", {"Energy drift", plot_energy}},
      {"region.csv", {"Stability regions", plot_region, "region_limits.csv"}},
      {"analyze_dispersion.csv", {"Dissipation and dispersion", plot_analyze}},
      {"budget.csv", {"Frame budget", plot_budget}},
  };
  return table;
}

// "PREFIX: MODEL" with the model from NAME.json beside the CSV (just PREFIX without one).
std::string replot_title(const fs::path& csv, const std::string& prefix) {
  fs::path json = csv;
  json.replace_extension(".json");
  std::ifstream in(json);
  if (!in) return prefix;
  try {
    const auto meta = nlohmann::json::parse(in);
    if (meta.contains("spec") && meta["spec"].contains("model") &&
        meta["spec"]["model"].is_string())
      return prefix + ": " + meta["spec"]["model"].get<std::string>();
  } catch (const std::exception&) {
  }
  return prefix;
}

// The integrator -> family pairs of a table with `integrator` and `family` columns (empty when
// it has none).
std::map<std::string, std::string> families_in(const fs::path& csv) {
  std::map<std::string, std::string> out;
  std::ifstream in(csv);
  std::string line;
  if (!std::getline(in, line)) return out;
  const std::vector<std::string> cols = parse_csv_line(line);
  const auto integ = std::find(cols.begin(), cols.end(), "integrator");
  const auto family = std::find(cols.begin(), cols.end(), "family");
  if (integ == cols.end() || family == cols.end()) return out;
  const auto i = static_cast<std::size_t>(integ - cols.begin());
  const auto f = static_cast<std::size_t>(family - cols.begin());
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = parse_csv_line(line);
    if (cells.size() > std::max(i, f)) out.emplace(cells[i], cells[f]);
  }
  return out;
}

// The families for redrawing `csv`: the caller's, else the table's family column (or that of
// the table beside it), else the registry's.
FamilyOf families_for(const fs::path& csv, const Replot& how, const PlotOptions& opt) {
  if (opt.family) return opt.family;
  auto known = std::make_shared<const std::map<std::string, std::string>>(
      families_in(how.families.empty() ? csv : csv.parent_path() / how.families));
  return [known](const std::string& name) {
    const auto it = known->find(name);
    return it != known->end() ? it->second : registered_family(name);
  };
}

}  // namespace

int replot_directory(const fs::path& dir, const PlotOptions& opt, std::ostream& out,
                     std::ostream& err) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw BadInput("plot: '" + dir.string() + "' is not a directory");
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir, ec))
    if (entry.is_regular_file() && replotters().count(entry.path().filename().string()))
      found.push_back(entry.path());
  if (found.empty()) {
    std::string names;
    for (const auto& [name, unused] : replotters()) names += (names.empty() ? "" : ", ") + name;
    throw BadInput("plot: no stiffbench table under '" + dir.string() + "' (looked for " + names +
                   ")");
  }
  std::sort(found.begin(), found.end());
  int drawn = 0;
  for (const auto& csv : found) {
    const Replot& how = replotters().at(csv.filename().string());
    PlotOptions plot = opt;
    plot.family = families_for(csv, how, opt);
    if (how.draw(csv, replot_title(csv, how.title), plot, err)) {
      fs::path png = csv;
      png.replace_extension(".png");
      // analyze's curves are in analyze_dispersion.csv, its plot is analyze.png.
      if (csv.filename() == "analyze_dispersion.csv") png = csv.parent_path() / "analyze.png";
      out << "plot: " << png.string() << "\n";
      ++drawn;
    }
  }
  return drawn;
}

}  // namespace stiffbench
