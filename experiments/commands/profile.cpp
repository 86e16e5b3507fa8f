// `stiffbench profile SUITE`: performance and data profiles over a suite of work-precision
// studies (experiments/commands/profile.hpp).
#include "experiments/commands/profile.hpp"

#include "experiments/output/html.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "core/params.hpp"
#include "experiments/build_info.hpp"
#include "experiments/commands/run.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/csv.hpp"
#include "experiments/output/html.hpp"

namespace stiffbench {

// suites/{mechanical,stiff}/*.toml, compiled in (cmake/embed_files.cmake).
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_profile_suite_stiff();
const std::vector<std::pair<std::string_view, std::string_view>>&
embedded_profile_suite_mechanical();

namespace fs = std::filesystem;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

const std::vector<std::pair<std::string_view, std::string_view>>* builtin_files(
    const std::string& name) {
  if (name == "stiff") return &embedded_profile_suite_stiff();
  if (name == "mechanical") return &embedded_profile_suite_mechanical();
  return nullptr;
}

// "03_hires.toml" -> "hires".
std::string problem_name(const std::string& file) {
  std::string stem = fs::path(file).stem().string();
  std::size_t i = 0;
  while (i < stem.size() && std::isdigit(static_cast<unsigned char>(stem[i]))) ++i;
  if (i > 0 && i < stem.size() && stem[i] == '_') stem = stem.substr(i + 1);
  return stem;
}

// The problem's own part of a spec: model, t_end and the model's parameters.
bool is_model_param(const std::string& model, const std::string& key) {
  const auto* e = model_registry().find(model);
  if (!e) return false;
  return std::any_of(e->params.begin(), e->params.end(),
                     [&](const ParamSpec& p) { return p.key == key; });
}

nlohmann::json quick_json(const SpecFile& s) {
  nlohmann::json q = nlohmann::json::object();
  for (const auto& e : s.quick) {
    nlohmann::json v = nlohmann::json::array();
    for (const auto& x : e.values) v.push_back(x.to_json());
    q[e.path] = v;
  }
  return q;
}

// The study settings of a spec (canonical form without the problem's part) and the problem's
// part.
std::pair<nlohmann::json, nlohmann::json> split_settings(const SpecFile& s) {
  nlohmann::json shared = s.to_json();
  nlohmann::json problem = {{"model", shared.value("model", "")}};
  shared.erase("model");
  if (shared.contains("t_end")) {
    problem["t_end"] = shared["t_end"];
    shared.erase("t_end");
  }
  nlohmann::json params = shared["params"], own = nlohmann::json::object(),
                 rest = nlohmann::json::object();
  for (auto it = params.begin(); it != params.end(); ++it)
    (is_model_param(problem["model"].get<std::string>(), it.key()) ? own : rest)[it.key()] =
        it.value();
  problem["params"] = own;
  shared["params"] = rest;
  nlohmann::json q = quick_json(s);
  q.erase("t_end");
  shared["quick"] = q;
  return {shared, problem};
}

// The settings as "key" or "table.key" -> value (params and quick one level down).
std::map<std::string, nlohmann::json> flatten(const nlohmann::json& j) {
  std::map<std::string, nlohmann::json> out;
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (it.value().is_object()) {
      for (auto in = it.value().begin(); in != it.value().end(); ++in)
        out[in.key().rfind(it.key() + ".", 0) == 0 ? in.key() : it.key() + "." + in.key()] =
            in.value();
    } else {
      out[it.key()] = it.value();
    }
  }
  return out;
}

// "no per-problem tuning": every file's study settings equal the first file's.
void check_uniform(const ProfileSuite& suite, const std::vector<std::string>& files,
                   const std::vector<nlohmann::json>& shared) {
  const auto first = flatten(shared[0]);
  for (std::size_t i = 1; i < shared.size(); ++i) {
    if (shared[i] == shared[0]) continue;
    const auto other = flatten(shared[i]);
    std::set<std::string> keys;
    for (const auto* m : {&first, &other})
      for (const auto& [k, v] : *m) keys.insert(k);
    auto value = [](const std::map<std::string, nlohmann::json>& m, const std::string& k) {
      const auto it = m.find(k);
      return it == m.end() ? std::string("(not set)") : it->second.dump();
    };
    for (const auto& k : keys) {
      if (value(first, k) == value(other, k)) continue;
      throw BadInput("profile: suite " + suite.name + " tunes per problem: " + files[i] +
                     " differs from " + files[0] + " in '" + k + "' (" + value(other, k) +
                     " against " + value(first, k) +
                     "); every file of a suite must share integrators and study settings, only "
                     "model, the model's [params] and t_end may differ");
    }
  }
}

}  // namespace

std::vector<std::string> builtin_profile_suites() { return {"mechanical", "stiff"}; }

ProfileSuite make_profile_suite(const std::string& name, std::vector<SpecFile> specs, bool quick) {
  ProfileSuite suite;
  suite.name = name;
  require_input(!specs.empty(), "profile: suite " + name + " holds no spec file");
  std::vector<std::string> files;
  std::vector<nlohmann::json> shared;
  suite.problem_settings = nlohmann::json::object();
  for (auto& spec : specs) {
    require_input(spec.kind == "work-precision",
                  "profile: " + spec.file + " is a " + spec.kind +
                      " spec; a suite holds work-precision specs only");
    ProfileProblem p;
    p.name = problem_name(spec.file);
    for (const auto& other : suite.problems)
      require_input(other.name != p.name, "profile: two problems named '" + p.name + "' (" +
                                              other.spec.file + ", " + spec.file + ")");
    auto [s, problem] = split_settings(spec);
    shared.push_back(s);
    files.push_back(spec.file);
    if (quick) apply_quick(spec);
    require_input(!spec.skip, "profile: " + spec.file + " sets skip in [quick]");
    make_spec_job(spec, "");  // names, parameters, options, no sweep dimension
    suite.problem_settings[p.name] = problem;
    p.spec = std::move(spec);
    suite.problems.push_back(std::move(p));
  }
  check_uniform(suite, files, shared);
  suite.shared = shared.front();
  // The methods by the names their rows carry: a method file given by path is registered under
  // the name inside it (relative paths from the spec's folder, as the run resolves them), and the
  // cost tables look rows up by that name.
  const SpecFile& first = suite.problems.front().spec;
  suite.methods = resolve_integrator_tokens(
      first.integrators, std::filesystem::path(first.file).parent_path().string());
  return suite;
}

ProfileSuite load_profile_suite(const std::string& name, bool quick) {
  std::vector<SpecFile> specs;
  std::string source;
  if (const auto* files = builtin_files(name)) {
    for (const auto& [file, text] : *files)
      specs.push_back(
          parse_spec_text(std::string(text), "suites/" + name + "/" + std::string(file), {}));
    source = "built-in";
  } else {
    std::error_code ec;
    require_input(fs::is_directory(name, ec),
                  "profile: '" + name + "' is neither a built-in suite (" +
                      join(builtin_profile_suites()) + ") nor a folder of spec files");
    std::vector<std::string> in_dir;
    for (const auto& e : fs::directory_iterator(name))
      if (e.is_regular_file() && e.path().extension() == ".toml")
        in_dir.push_back(e.path().string());
    std::sort(in_dir.begin(), in_dir.end());
    require_input(!in_dir.empty(), "profile: folder " + name + " holds no spec file (*.toml)");
    for (const auto& f : in_dir) specs.push_back(load_spec_file(f, {}));
    source = fs::absolute(name).string();
  }
  ProfileSuite s = make_profile_suite(name, std::move(specs), quick);
  s.source = source;
  return s;
}

// --- The profiles ---------------------------------------------------------------------------

namespace {

double best_cost(const CostTable& t, std::size_t p) {
  double best = kInf;
  for (double c : t.cost[p]) best = std::min(best, c);
  return best;
}

double ratio(const CostTable& t, std::size_t p, std::size_t m) {
  const double c = t.cost[p][m], best = best_cost(t, p);
  if (!std::isfinite(c) || !std::isfinite(best)) return kInf;
  if (best <= 0) return c <= 0 ? 1.0 : kInf;  // a zero cost (e.g. no linear solves) is cheapest
  return c / best;
}

std::vector<ProfilePoint> curve(const CostTable& t, std::size_t m, bool performance) {
  std::set<double> xs;
  if (performance) xs.insert(1.0);
  for (std::size_t p = 0; p < t.problems.size(); ++p)
    for (std::size_t k = 0; k < t.methods.size(); ++k) {
      const double x = performance ? ratio(t, p, k) : t.cost[p][k];
      if (std::isfinite(x)) xs.insert(x);
    }
  if (xs.empty()) xs.insert(1.0);  // nothing solved: one point at fraction 0 (a drawable curve)
  std::vector<ProfilePoint> out;
  for (double x : xs)
    out.push_back({x, performance ? performance_profile(t, m, x) : data_profile(t, m, x)});
  return out;
}

}  // namespace

double performance_profile(const CostTable& t, std::size_t m, double alpha) {
  if (t.problems.empty()) return 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < t.problems.size(); ++p) n += ratio(t, p, m) <= alpha ? 1 : 0;
  return static_cast<double>(n) / static_cast<double>(t.problems.size());
}

double data_profile(const CostTable& t, std::size_t m, double kappa) {
  if (t.problems.empty()) return 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < t.problems.size(); ++p) n += t.cost[p][m] <= kappa ? 1 : 0;
  return static_cast<double>(n) / static_cast<double>(t.problems.size());
}

std::vector<ProfilePoint> performance_curve(const CostTable& t, std::size_t m) {
  return curve(t, m, true);
}
std::vector<ProfilePoint> data_curve(const CostTable& t, std::size_t m) {
  return curve(t, m, false);
}

double performance_area(const CostTable& t, std::size_t m) {
  if (t.problems.empty()) return 0;
  double alpha_max = 1;
  for (std::size_t p = 0; p < t.problems.size(); ++p)
    for (std::size_t k = 0; k < t.methods.size(); ++k)
      if (std::isfinite(ratio(t, p, k))) alpha_max = std::max(alpha_max, ratio(t, p, k));
  double area = 0;
  for (std::size_t p = 0; p < t.problems.size(); ++p)
    if (std::isfinite(ratio(t, p, m))) area += std::log2(alpha_max) - std::log2(ratio(t, p, m));
  return area / static_cast<double>(t.problems.size());
}

std::vector<std::size_t> profile_ranking(const CostTable& t) {
  std::vector<std::size_t> idx(t.methods.size());
  std::vector<double> rho1(idx.size()), area(idx.size());
  for (std::size_t m = 0; m < idx.size(); ++m) {
    idx[m] = m;
    rho1[m] = performance_profile(t, m, 1.0);
    area[m] = performance_area(t, m);
  }
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    if (rho1[a] != rho1[b]) return rho1[a] > rho1[b];
    if (area[a] != area[b]) return area[a] > area[b];
    return t.methods[a] < t.methods[b];
  });
  return idx;
}

CostTable cost_table(const std::vector<std::string>& problems,
                     const std::vector<std::string>& methods, const std::vector<Table>& rows,
                     double tau, const std::string& cost) {
  static const std::map<std::string, std::string> column = {
      {"f_evals", "f_evals"}, {"wall", "wall_s_median"}, {"linear_solves", "lin_solves"}};
  CostTable t{problems, methods, {}, {}};
  for (std::size_t p = 0; p < problems.size(); ++p) {
    const Table& tab = rows[p];
    auto col = [&](const std::string& name) {
      const auto it = std::find(tab.columns.begin(), tab.columns.end(), name);
      if (it == tab.columns.end())
        throw BadInput("profile: the rows of " + problems[p] + " have no column " + name);
      return static_cast<std::size_t>(it - tab.columns.begin());
    };
    const std::size_t ci = col("integrator"), ce = col("error"), cs = col("status"),
                      cc = col(column.at(cost));
    t.cost.emplace_back(methods.size(), kInf);
    t.note.emplace_back(methods.size(), "no rows");
    std::vector<double> best_error(methods.size(), kInf);
    std::vector<std::set<std::string>> statuses(methods.size());
    std::vector<bool> unreported(methods.size(), false);
    for (const auto& r : tab.rows) {
      const auto m = static_cast<std::size_t>(std::find(methods.begin(), methods.end(), r[ci]) -
                                              methods.begin());
      if (m == methods.size()) continue;
      if (r[cs] != "ok") {
        statuses[m].insert(r[cs].empty() ? "error" : r[cs]);
        continue;
      }
      if (r[cc].empty()) {  // a library that keeps no such count (SolveStats::kNotReported)
        unreported[m] = true;
        continue;
      }
      const double e = std::stod(r[ce]);
      best_error[m] = std::min(best_error[m], e);
      if (e <= tau) t.cost[p][m] = std::min(t.cost[p][m], std::stod(r[cc]));
    }
    for (std::size_t m = 0; m < methods.size(); ++m) {
      if (std::isfinite(t.cost[p][m]))
        t.note[p][m].clear();
      else if (unreported[m])  // unsolved in this measure: its cost is unknown, not zero
        t.note[p][m] = column.at(cost) + " not reported by the library";
      else if (std::isfinite(best_error[m]))
        t.note[p][m] = "best error " + format_short(best_error[m], 2);
      else if (!statuses[m].empty())
        t.note[p][m] = join(std::vector<std::string>(statuses[m].begin(), statuses[m].end()));
    }
  }
  return t;
}

void ProfileOptions::validate() const {
  require_input(!taus.empty(), "--tau: give at least one target accuracy");
  for (double t : taus)
    require_input(std::isfinite(t) && t > 0,
                  "--tau: " + format_short(t, 3) + " is not a positive accuracy");
  require_input(!costs.empty(), "--cost: give at least one cost measure");
  for (const auto& c : costs) {
    const auto& names = profile_cost_names();
    require_input(std::find(names.begin(), names.end(), c) != names.end(),
                  "--cost: unknown cost '" + c + "'" + did_you_mean(c, names) + " (one of " +
                      join(names) + ")");
  }
}

// --- Running and writing ----------------------------------------------------------------------

namespace {

// DIR/<problem>/work_precision.csv as a table (the run CSV's columns).
Table read_rows(const fs::path& csv) {
  std::ifstream in(csv);
  std::stringstream text;
  text << in.rdbuf();
  const CsvContent c = parse_run_csv(text.str());
  Table t;
  std::string header = c.header;
  while (!header.empty() && (header.back() == '\n' || header.back() == '\r')) header.pop_back();
  t.columns = parse_csv_line(header);
  for (const auto& [u, unit] : c.units)
    for (const auto& line : unit.lines) {
      std::string l = line;
      while (!l.empty() && (l.back() == '\n' || l.back() == '\r')) l.pop_back();
      t.rows.push_back(parse_csv_line(l));
    }
  return t;
}

// What DIR holds of `spec`: a run of it (run.json's hash, computed like `run` computes it: after
// the spec's method files are resolved, from their content), and every unit of it in the CSV;
// for a run of another spec, the keys that differ.
struct HeldRun {
  bool same_spec = false, complete = false;
  std::string difference;  // another spec's run: what differs (spec_difference)
};
HeldRun held_run(const fs::path& dir, const SpecFile& spec) {
  HeldRun h;
  std::ifstream in(dir / "run.json");
  if (!in) return h;
  nlohmann::json run;
  try {
    run = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception&) {
    h.difference = (dir / "run.json").string() + " is not valid JSON";
    return h;
  }
  h.same_spec = run.value("spec_hash", "") == spec_hash(spec);
  if (!h.same_spec) {
    h.difference = run.contains("spec") ? spec_difference(run["spec"], spec_record(spec))
                                        : (dir / "run.json").string() + " records no \"spec\"";
    if (h.difference.empty())  // equal identities under another hash: a record of another version
      h.difference = "spec_hash = \"" + run.value("spec_hash", "") + "\" there, \"" +
                     spec_hash(spec) + "\" here";
  }
  if (!h.same_spec || !run.value("missing_units", nlohmann::json::array()).empty()) return h;
  std::ifstream csv_in(dir / "work_precision.csv");
  std::stringstream text;
  text << csv_in.rdbuf();
  h.complete = static_cast<long>(parse_run_csv(text.str()).units.size()) ==
               static_cast<long>(spec.integrators.size());
  return h;
}

std::string tau_text(double tau) { return format_short(tau, 0); }

void rank_and_flag(ProfileResult& r, std::ostream& out) {
  for (std::size_t i = 0; i < r.taus.size(); ++i) {
    out << "tau = " << tau_text(r.taus[i]) << "\n";
    std::vector<std::vector<std::string>> orders;
    for (std::size_t c = 0; c < r.costs.size(); ++c) {
      const CostTable& t = r.table(i, c);
      std::vector<std::string> order;
      out << "  " << r.costs[c] << ":";
      for (const std::size_t m : profile_ranking(t)) {
        order.push_back(t.methods[m]);
        out << " " << t.methods[m] << " (rho(1) " << format_short(performance_profile(t, m, 1), 2)
            << ", area " << format_short(performance_area(t, m), 2) << ")";
      }
      out << "\n";
      orders.push_back(order);
    }
    const auto wall = std::find(r.costs.begin(), r.costs.end(), "wall") - r.costs.begin();
    if (static_cast<std::size_t>(wall) == r.costs.size()) continue;
    for (std::size_t c = 0; c < r.costs.size(); ++c) {
      if (r.costs[c] == "wall" || orders[c] == orders[static_cast<std::size_t>(wall)]) continue;
      const std::string flag = "tau " + tau_text(r.taus[i]) + ": the wall-time ranking (" +
                               join(orders[static_cast<std::size_t>(wall)]) +
                               ") differs from the " + r.costs[c] + " ranking (" + join(orders[c]) +
                               ")" +
                               (orders[c].front() != orders[static_cast<std::size_t>(wall)].front()
                                    ? ", also in first place"
                                    : "");
      r.disagreements.push_back(flag);
      out << "  DISAGREE: " << flag << "\n";
    }
  }
}

void plot_profiles(const ProfileResult& r, const fs::path& dir, const PlotOptions& plot,
                   std::ostream& err) {
  for (std::size_t i = 0; i < r.taus.size(); ++i)
    for (std::size_t c = 0; c < r.costs.size(); ++c) {
      const std::string stem = "profile_" + tau_text(r.taus[i]) + "_" + r.costs[c];
      const PlotVars vars = {{"csvfile", (dir / "profile.csv").string()},
                             {"ttl", "suite " + r.suite.name + ", tau = " + tau_text(r.taus[i]) +
                                         ", cost = " + r.costs[c]},
                             {"tau", tau_text(r.taus[i])},
                             {"cost", r.costs[c]}};
      const std::vector<PlotPanel> panels = {
          {"performance profile (Dolan & More 2002)", r.suite.methods},
          {"data profile (More & Wild 2009)", r.suite.methods}};
      if (!run_plot("profile.gp", dir / stem, vars, panels, plot, err)) return;
    }
}

// What DIR/profile.json records and compares: the suite (its problems' specs), not tau and cost,
// which only change the profiles drawn from the same rows (another --tau reuses every problem
// and rewrites profile.{csv,md,json}).
nlohmann::json profile_spec(const ProfileSuite& suite, const ProfileOptions& opt) {
  nlohmann::json problems = nlohmann::json::array();
  for (const auto& p : suite.problems)
    problems.push_back({{"name", p.name}, {"spec", spec_record(p.spec)}});
  return {{"suite", suite.name}, {"quick", opt.quick}, {"problems", problems}};
}

// The units of one problem's rows that did not end ok, into r.not_ok (one entry per method).
void note_units_not_ok(ProfileResult& r, const std::string& problem, const Table& rows) {
  const auto col = [&](const char* name) {
    return std::find(rows.columns.begin(), rows.columns.end(), name) - rows.columns.begin();
  };
  const auto integ = col("integrator"), status = col("unit_status"), message = col("unit_message");
  const auto n = static_cast<std::ptrdiff_t>(rows.columns.size());
  if (integ == n || status == n || message == n) return;
  std::set<std::string> seen;
  for (const auto& row : rows.rows) {
    if (static_cast<std::ptrdiff_t>(row.size()) != n) continue;
    const std::string& s = row[static_cast<std::size_t>(status)];
    const std::string& m = row[static_cast<std::size_t>(integ)];
    if (s == "ok" || !seen.insert(m).second) continue;
    r.not_ok.push_back({problem, m, s, row[static_cast<std::size_t>(message)]});
  }
}

// Runs or reuses every problem; returns its rows.
std::vector<Table> run_problems(ProfileResult& r, const ProfileOptions& opt, std::ostream& err) {
  std::vector<Table> rows;
  const std::size_t n = r.suite.problems.size();
  // Output safety before the first problem runs: a folder holding another spec's run is refused
  // unless --force (`run` would refuse it only when its turn came).
  for (const auto& p : r.suite.problems) {
    const fs::path dir = fs::path(opt.out_dir) / p.name;
    if (opt.force || !fs::exists(dir / "run.json")) continue;
    const HeldRun held = held_run(dir, p.spec);
    require_input(held.same_spec, "--out " + dir.string() + " holds a run of another spec (" +
                                      (dir / "run.json").string() + ": " + held.difference +
                                      "); choose another --out or pass --force to replace it");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const ProfileProblem& p = r.suite.problems[i];
    const fs::path dir = fs::path(opt.out_dir) / p.name;
    const HeldRun held = held_run(dir, p.spec);
    if (held.complete) {
      err << "== [" << i + 1 << "/" << n << "] " << p.name << ": reusing " << dir.string() << "\n";
      r.reused.push_back(p.name);
    } else {
      err << "== [" << i + 1 << "/" << n << "] " << p.name << "\n";
      RunOptions ro;
      ro.out_dir = dir.string();
      // The units of this spec already there are kept (--resume); --force replaces only a run
      // of another spec.
      ro.force = opt.force && !held.same_spec;
      ro.resume = !ro.force;
      run_loaded_spec(p.spec, ro, err, err);  // exit code 3 (a failed unit): unsolved there
      r.ran.push_back(p.name);
    }
    rows.push_back(read_rows(dir / "work_precision.csv"));
    note_units_not_ok(r, p.name, rows.back());
  }
  return rows;
}

}  // namespace

Table profile_csv_table(const ProfileResult& r) {
  Table t{{"tau", "cost", "kind", "method", "x", "fraction"}, {}};
  for (std::size_t i = 0; i < r.taus.size(); ++i)
    for (std::size_t c = 0; c < r.costs.size(); ++c) {
      const CostTable& tab = r.table(i, c);
      for (int kind = 0; kind < 2; ++kind)
        for (std::size_t m = 0; m < tab.methods.size(); ++m)
          for (const auto& pt : kind == 0 ? performance_curve(tab, m) : data_curve(tab, m))
            t.rows.push_back({tau_text(r.taus[i]), r.costs[c], kind == 0 ? "performance" : "data",
                              tab.methods[m], format_full(pt.x), format_full(pt.fraction)});
    }
  return t;
}

Table profile_status_table(const ProfileResult& r) {
  Table t{{"problem", "method", "unit_status", "unit_message"}, {}};
  for (const auto& p : r.suite.problems)
    for (const auto& m : r.suite.methods) {
      std::vector<std::string> row = {p.name, m, "ok", ""};
      for (const auto& u : r.not_ok)
        if (u.problem == p.name && u.method == m) row = {p.name, m, u.status, u.message};
      t.rows.push_back(std::move(row));
    }
  return t;
}

std::string section_title(const ProfileResult& r, std::size_t i, std::size_t c) {
  return "tau = " + tau_text(r.taus[i]) + ", cost = " + r.costs[c];
}

std::string plot_stem(const ProfileResult& r, std::size_t i, std::size_t c) {
  return "profile_" + tau_text(r.taus[i]) + "_" + r.costs[c];
}

// The cost table (cheapest per problem in bold) and the ranking of one τ and cost measure.
std::string section_markdown(const CostTable& t) {
  std::ostringstream md;
  Table cost{{"problem"}, {}};
  cost.columns.insert(cost.columns.end(), t.methods.begin(), t.methods.end());
  for (std::size_t p = 0; p < t.problems.size(); ++p) {
    std::vector<std::string> row = {t.problems[p]};
    for (std::size_t m = 0; m < t.methods.size(); ++m) {
      const double x = t.cost[p][m];
      const bool best = std::isfinite(x) && x == best_cost(t, p);
      row.push_back(!std::isfinite(x)
                        ? "- (" + t.note[p][m] + ")"
                        : (best ? "**" : "") + format_short(x, 3) + (best ? "**" : ""));
    }
    cost.rows.push_back(row);
  }
  md << cost.to_markdown() << "\n";
  Table rank{{"rank", "method", "rho(1)", "rho(2)", "rho(10)", "area", "solved"}, {}};
  int k = 0;
  for (const std::size_t m : profile_ranking(t))
    rank.rows.push_back(
        {std::to_string(++k), t.methods[m], format_short(performance_profile(t, m, 1), 3),
         format_short(performance_profile(t, m, 2), 3),
         format_short(performance_profile(t, m, 10), 3), format_short(performance_area(t, m), 3),
         format_short(data_profile(t, m, std::numeric_limits<double>::max()), 3)});
  md << rank.to_markdown() << "\n";
  return md.str();
}

std::string disagreement_markdown(const ProfileResult& r) {
  std::ostringstream md;
  if (r.disagreements.empty()) md << "The rankings agree.\n";
  for (const auto& d : r.disagreements) md << "- " << d << "\n";
  return md.str();
}

// The units that did not end ok, as a Markdown list (profile.md and profile.html).
std::string not_ok_markdown(const ProfileResult& r) {
  std::ostringstream md;
  if (r.not_ok.empty()) md << "None: every problem x method unit ended ok.\n";
  for (const auto& u : r.not_ok)
    md << "- " << u.problem << ", " << u.method << ": " << u.status
       << (u.message.empty() ? "" : " (" + u.message + ")")
       << "; its failed runs count as unsolved\n";
  return md.str();
}

std::string profile_markdown(const ProfileResult& r) {
  std::ostringstream md;
  md << "# Performance and data profiles: suite " << r.suite.name << "\n\n";
  md << "stiffbench " << STIFFBENCH_VERSION << ", revision " << git_revision() << "; suite "
     << r.suite.name << " (" << r.suite.source << "), " << r.suite.problems.size()
     << " problems, methods " << join(r.suite.methods) << ". Study settings shared by every "
     << "problem (no per-problem tuning): `" << r.suite.shared.dump() << "`.\n\n";
  md << "Cost of a method on a problem: the least cost among its runs with status ok and error <= "
        "tau (no interpolation); `-` unsolved (why in parentheses). rho_m(alpha): share of "
        "problems with cost <= alpha x the cheapest method's (Dolan & More 2002); d_m(kappa): "
        "share solved within kappa cost units (More & Wild 2009). Ranking: rho(1), then the area "
        "under rho over log2 alpha.\n\n";
  for (std::size_t i = 0; i < r.taus.size(); ++i)
    for (std::size_t c = 0; c < r.costs.size(); ++c) {
      md << "## " << section_title(r, i, c) << "\n\n" << section_markdown(r.table(i, c));
      md << "![profiles](" << plot_stem(r, i, c) << ".png)\n\n";
    }
  md << "## Wall time against counters\n\n" << disagreement_markdown(r);
  md << "\n## Units that did not end ok\n\n" << not_ok_markdown(r);
  return md.str();
}

// DIR/profile.html (--html): one section per τ and cost (its plots inline, the cost table and
// the ranking), then the wall-time/counter disagreements; metadata from profile.json.
void write_profile_html(const ProfileResult& r, const fs::path& dir, const nlohmann::json& meta,
                        std::ostream& out) {
  std::vector<HtmlSection> sections;
  const std::vector<HtmlLink> links = {{"profile.csv", "profile.csv"},
                                       {"profile.md", "profile.md"},
                                       {"profile.json", "profile.json"}};
  for (std::size_t i = 0; i < r.taus.size(); ++i)
    for (std::size_t c = 0; c < r.costs.size(); ++c) {
      HtmlSection h;
      h.id = plot_stem(r, i, c);
      h.title = section_title(r, i, c);
      h.markdown = section_markdown(r.table(i, c));
      h.svgs = {dir / (plot_stem(r, i, c) + ".svg")};
      h.links = links;
      sections.push_back(std::move(h));
    }
  HtmlSection agree;
  agree.id = "wall-against-counters";
  agree.title = "Wall time against counters";
  agree.markdown = disagreement_markdown(r);
  sections.push_back(std::move(agree));
  HtmlSection not_ok;
  not_ok.id = "units-not-ok";
  not_ok.title = "Units that did not end ok";
  not_ok.markdown = not_ok_markdown(r);
  not_ok.links = {{"profile_status.csv", "profile_status.csv"}};
  sections.push_back(std::move(not_ok));
  HtmlMetadata md;
  for (const auto& [k, v] : html_metadata(meta))
    if (k != "shared_settings" && k != "problem_settings" && k != "spec") md.emplace_back(k, v);
  const fs::path page = dir / "profile.html";
  std::ostringstream intro;
  intro << "Suite " << r.suite.name << " (" << r.suite.source << "), " << r.suite.problems.size()
        << " problems, methods " << join(r.suite.methods)
        << ". Cost of a method on a problem: the least cost among its runs with status ok and "
           "error <= tau; rho_m(alpha) (Dolan & More 2002) and d_m(kappa) (More & Wild 2009) as "
           "in [profile.md](profile.md).\n";
  write_html_page(page, "stiffbench profile: suite " + r.suite.name, md, sections, intro.str());
  out << "wrote " << page.string() << "\n";
}

ProfileResult run_profile(const ProfileSuite& suite, const ProfileOptions& opt, std::ostream& out,
                          std::ostream& err) {
  opt.validate();
  require_input(!suite.problems.empty(), "profile: suite " + suite.name + " is empty");
  require_output_dir(opt.out_dir);
  const FolderClaim claim(opt.out_dir, &err);  // no other run writes here until this one is done
  const nlohmann::json spec = profile_spec(suite, opt);
  check_existing_results(opt.out_dir, "profile.json",
                         {"profile.csv", "profile.md", "profile.html", "profile_status.csv"}, spec,
                         opt.force, &err);
  const auto start = std::chrono::steady_clock::now();
  ProfileResult r;
  r.suite = suite;
  r.taus = opt.taus;
  r.costs = opt.costs;
  std::vector<std::string> problems;
  for (const auto& p : suite.problems) problems.push_back(p.name);
  const std::vector<Table> rows = run_problems(r, opt, err);
  for (double tau : opt.taus)
    for (const auto& c : opt.costs)
      r.tables.push_back(cost_table(problems, suite.methods, rows, tau, c));
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rank_and_flag(r, out);

  const fs::path dir = opt.out_dir;
  write_file_atomic(dir / "profile.csv", profile_csv_table(r).to_csv());
  write_file_atomic(dir / "profile.md", profile_markdown(r));
  write_file_atomic(dir / "profile_status.csv", profile_status_table(r).to_csv());
  nlohmann::json meta = run_metadata("profile", spec);
  meta["tau"] = opt.taus;
  meta["cost"] = opt.costs;
  meta["per_problem_settings"] = false;  // checked when the suite was loaded
  // Every setting a spec file states (anything not stated is the study's default).
  meta["shared_settings"] = suite.shared;
  meta["problem_settings"] = suite.problem_settings;
  meta["reused"] = r.reused;
  meta["ran"] = r.ran;
  meta["disagreements"] = r.disagreements;
  nlohmann::json not_ok = nlohmann::json::array();
  for (const auto& u : r.not_ok)
    not_ok.push_back({{"problem", u.problem},
                      {"method", u.method},
                      {"status", u.status},
                      {"message", u.message}});
  meta["units_not_ok"] = not_ok;
  meta["wall_s"] = r.wall_s;
  write_file_atomic(dir / "profile.json", meta.dump(2) + "\n");
  PlotOptions plot = opt.plot;
  plot.svg = plot.svg || opt.html;
  plot_profiles(r, dir, plot, err);
  if (opt.html) write_profile_html(r, dir, meta, out);
  for (const auto& u : r.not_ok)
    err << "note: " << u.problem << ", " << u.method << ": unit " << u.status
        << (u.message.empty() ? "" : " (" + u.message + ")") << ": counted as unsolved there\n";
  out << "wrote " << (dir / "profile.md").string()
      << ", profile.csv, profile_status.csv, profile.json (" << format_short(r.wall_s, 3)
      << " s)\n";
  return r;
}

ProfileResult cmd_profile(const ProfileOptions& opt, std::ostream& out, std::ostream& err) {
  opt.validate();
  return run_profile(load_profile_suite(opt.suite, opt.quick), opt, out, err);
}

}  // namespace stiffbench
