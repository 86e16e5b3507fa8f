#include "experiments/commands/compare.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

#include "core/params.hpp"
#include "core/solve_stats.hpp"
#include "core/types.hpp"
#include "experiments/output/csv.hpp"
#include "experiments/studies/work_precision.hpp"

namespace stiffbench {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The run-record keys compared beside the spec (experiments/output/output.cpp, run_metadata).
const std::vector<std::string> kRecordKeys = {
    "experiment",    "stiffbench_version", "git_revision", "compiler",  "build_type", "flags",
    "eigen_version", "sundials_version",   "gsl_version",  "cpu_model", "threads",    "seed",
    "caller"};
// At most this many differing spec keys are listed per file.
constexpr std::size_t kMaxSpecDifferences = 20;
// At most this many rows per table in the Markdown (every row is in compare.csv).
constexpr std::size_t kMaxMarkdownRows = 200;

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

// The whole text as a number (NaN, inf and -inf included); nullopt otherwise.
std::optional<double> as_number(const std::string& s) {
  if (s.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return std::nullopt;
  return x;
}

bool is_integer_text(const std::string& s) {
  std::size_t i = s.size() > 1 && s[0] == '-' ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

bool is_timing_column(const std::string& c) {
  return c.find("wall") != std::string::npos || c.rfind("ms_per_frame", 0) == 0 ||
         c == kWallTimingColumns.runs || c == "timed_runs";
}

// The relative paths of the *.csv and *.json files below DIR, sorted; hidden files and folders
// are left out.
std::vector<std::string> result_files(const fs::path& dir) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator();
       ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory()) {
      if (!name.empty() && name[0] == '.') it.disable_recursion_pending();
      continue;
    }
    if (!it->is_regular_file() || name.empty() || name[0] == '.') continue;
    const std::string ext = it->path().extension().string();
    if (ext != ".csv" && ext != ".json") continue;
    files.push_back(fs::relative(it->path(), dir).generic_string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

CsvTable read_csv(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw BadInput("compare: cannot read " + path.string());
  CsvTable t;
  std::string line;
  long number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    // Comment lines (a reference cache's key and its note with the time it took) are not data.
    if (line.empty() || line[0] == '#') continue;
    auto cells = parse_csv_line(line);
    if (t.header.empty()) {
      t.header = std::move(cells);
      continue;
    }
    if (cells.size() != t.header.size())
      throw BadInput("compare: " + path.string() + " line " + std::to_string(number) + " has " +
                     std::to_string(cells.size()) + " fields, its header " +
                     std::to_string(t.header.size()) + " (a torn or damaged table)");
    t.rows.push_back(std::move(cells));
  }
  return t;
}

std::size_t column_index(const std::vector<std::string>& header, const std::string& name) {
  return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
}

// The key of every row: "name=value, ..." of the key columns, "#k" for the k-th repeat of a key.
std::vector<std::string> row_keys(const CsvTable& t, const std::vector<std::string>& keys) {
  std::vector<std::size_t> cols;
  for (const auto& name : keys) cols.push_back(column_index(t.header, name));
  std::vector<std::string> out;
  std::map<std::string, int> seen;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    std::string k;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (!k.empty()) k += ", ";
      k += keys[i] + "=" + t.rows[r][cols[i]];
    }
    if (keys.empty()) k = "row " + std::to_string(r + 1);
    const int n = ++seen[k];
    out.push_back(n == 1 ? k : k + " #" + std::to_string(n));
  }
  return out;
}

std::string change_text(const std::string& column, const std::string& a, const std::string& b) {
  const auto x = as_number(a), y = as_number(b);
  std::string s = column + " " + (a.empty() ? "(empty)" : a) + " -> " + (b.empty() ? "(empty)" : b);
  if (x && y) s += " (ratio " + compare_ratio(*x, *y) + ")";
  return s;
}

double number_or_nan(const std::string& s) { return as_number(s).value_or(kNaN); }

// The timing of one row: the median and interval columns the table has.
struct TimingColumns {
  std::string median, low, high, runs;
};
std::optional<TimingColumns> timing_columns(const std::vector<std::string>& header) {
  const auto has = [&](const std::string& c) { return contains(header, c); };
  const auto& w = kWallTimingColumns;
  if (has(w.ci_low) && has(w.ci_high))
    return TimingColumns{has(w.median) ? w.median : "wall_s", w.ci_low, w.ci_high,
                         has(w.runs) ? w.runs : ""};
  if (has("ms_per_frame_ci_low") && has("ms_per_frame_ci_high") && has("ms_per_frame_median"))
    return TimingColumns{"ms_per_frame_median", "ms_per_frame_ci_low", "ms_per_frame_ci_high",
                         has("timed_runs") ? "timed_runs" : ""};
  if (has("wall_s")) return TimingColumns{"wall_s", "", "", ""};
  return std::nullopt;
}

TimingComparison compare_timing(const TimingColumns& c, const CsvTable& a,
                                const std::vector<std::string>& ra, const CsvTable& b,
                                const std::vector<std::string>& rb) {
  TimingComparison t;
  t.quantity = c.median;
  const auto cell = [](const CsvTable& tab, const std::vector<std::string>& row,
                       const std::string& col) {
    return col.empty() ? kNaN : number_or_nan(row[column_index(tab.header, col)]);
  };
  t.old_median = cell(a, ra, c.median);
  t.new_median = cell(b, rb, c.median);
  t.has_interval = !c.low.empty();
  t.old_low = t.has_interval ? cell(a, ra, c.low) : t.old_median;
  t.old_high = t.has_interval ? cell(a, ra, c.high) : t.old_median;
  t.new_low = t.has_interval ? cell(b, rb, c.low) : t.new_median;
  t.new_high = t.has_interval ? cell(b, rb, c.high) : t.new_median;
  const auto runs = [&](const CsvTable& tab, const std::vector<std::string>& row) {
    if (c.runs.empty()) return 1;
    const double n = cell(tab, row, c.runs);
    return std::isfinite(n) ? static_cast<int>(std::clamp(n, 0.0, 1e9)) : 0;
  };
  t.old_runs = runs(a, ra);
  t.new_runs = runs(b, rb);
  if (!std::isfinite(t.old_median) || !std::isfinite(t.new_median) ||
      !std::isfinite(t.old_low + t.old_high + t.new_low + t.new_high)) {
    t.verdict = "not measured";
  } else if (!t.has_interval) {
    t.verdict = "not resolved (a single run each)";
  } else if (t.old_runs < kCompareMinTimedRuns || t.new_runs < kCompareMinTimedRuns) {
    t.verdict = "not resolved (" + std::to_string(t.old_runs) + " and " +
                std::to_string(t.new_runs) + " runs; a verdict needs " +
                std::to_string(kCompareMinTimedRuns) + " on each side)";
  } else if (t.new_high < t.old_low) {
    t.verdict = "faster";
  } else if (t.new_low > t.old_high) {
    t.verdict = "slower";
  } else {
    t.verdict = "not resolved (intervals overlap)";
  }
  return t;
}

// A column compared cell by cell (common to both tables, neither key nor timing), with its place
// in each. Compared exactly: the counters (named ones) and every column whose every value on both
// sides is an integer (a claimed order, a count of levels).
struct ComparedColumn {
  std::string name;
  std::size_t ia, ib;
  bool exact, counter;
};

std::vector<ComparedColumn> compared_columns(const CsvTable& a, const CsvTable& b,
                                             const std::vector<std::string>& common,
                                             const std::vector<std::string>& keys) {
  const std::vector<std::string> counters = compare_counter_columns();
  std::vector<ComparedColumn> compared;
  for (const auto& c : common) {
    if (contains(keys, c) || is_timing_column(c)) continue;
    const std::size_t ia = column_index(a.header, c), ib = column_index(b.header, c);
    bool all_integers = true, any = false;
    for (const auto& [t, i] : {std::pair{&a, ia}, std::pair{&b, ib}})
      for (const auto& row : t->rows) {
        if (row[i].empty()) continue;
        any = true;
        all_integers = all_integers && is_integer_text(row[i]);
      }
    const bool counter = contains(counters, c);
    compared.push_back({c, ia, ib, counter || (any && all_integers), counter});
  }
  return compared;
}

// The cells of one matched row: counters that changed go to row.counter_changes, cells that
// differ beyond the tolerance to row.differences (not for a row of measured times).
void compare_cells(const std::vector<ComparedColumn>& columns, const std::vector<std::string>& ra,
                   const std::vector<std::string>& rb, const CompareOptions& opt, bool timed_row,
                   RowComparison& row) {
  for (const ComparedColumn& c : columns) {
    const std::string &x = ra[c.ia], &y = rb[c.ib];
    if (x == y) continue;
    bool equal = false;
    if (!c.exact) {
      const auto p = as_number(x), q = as_number(y);
      if (p && q)
        equal = (std::isnan(*p) && std::isnan(*q)) ||
                (std::isfinite(*p) && std::isfinite(*q) &&
                 std::abs(*p - *q) <= opt.rtol * std::max(std::abs(*p), std::abs(*q)) + opt.atol);
    }
    if (c.counter) row.counter_changes.push_back(change_text(c.name, x, y));
    if (!equal && !timed_row) row.differences.push_back(change_text(c.name, x, y));
  }
  row.changed = !row.differences.empty();
}

void compare_table_files(const fs::path& old_path, const fs::path& new_path, FileComparison& f,
                         std::vector<RowComparison>& out, const CompareOptions& opt) {
  const CsvTable a = read_csv(old_path), b = read_csv(new_path);
  for (const auto& k : kCompareKeyColumns)
    if (contains(a.header, k) && contains(b.header, k)) f.key_columns.push_back(k);
  std::vector<std::string> common, only_old, only_new;
  for (const auto& c : a.header) (contains(b.header, c) ? common : only_old).push_back(c);
  for (const auto& c : b.header)
    if (!contains(a.header, c)) only_new.push_back(c);
  if (!only_old.empty()) f.notes.push_back("columns only in OLD: " + join(only_old, ", "));
  if (!only_new.empty()) f.notes.push_back("columns only in NEW: " + join(only_new, ", "));

  const std::vector<ComparedColumn> compared = compared_columns(a, b, common, f.key_columns);
  std::string error_column;
  for (const auto& c : kCompareErrorColumns)
    if (contains(common, c)) {
      error_column = c;
      break;
    }
  const bool has_f_evals = contains(common, "f_evals");
  const auto timing = timing_columns(common);
  // A wall-time cost (profile.csv) is a measurement, like the timing columns.
  const bool has_cost = contains(f.key_columns, "cost");
  // The error and f_evals of a row on one side.
  const auto fill = [&](const CsvTable& t, const std::vector<std::string>& cells,
                        std::string& error, std::string& f_evals) {
    if (!error_column.empty()) error = cells[column_index(t.header, error_column)];
    if (has_f_evals) f_evals = cells[column_index(t.header, "f_evals")];
  };

  const auto ka = row_keys(a, f.key_columns), kb = row_keys(b, f.key_columns);
  std::map<std::string, std::size_t> new_index;
  for (std::size_t i = 0; i < kb.size(); ++i) new_index[kb[i]] = i;
  std::vector<bool> matched(kb.size(), false);
  const std::size_t first = out.size();
  for (std::size_t i = 0; i < ka.size(); ++i) {
    RowComparison row;
    row.file = f.file;
    row.key = ka[i];
    row.error_column = error_column;
    const auto& ra = a.rows[i];
    fill(a, ra, row.error_old, row.f_evals_old);
    const auto it = new_index.find(ka[i]);
    if (it == new_index.end()) {
      row.presence = RowComparison::Presence::old_only;
      row.changed = true;
      row.differences.push_back("row only in OLD");
      out.push_back(std::move(row));
      continue;
    }
    matched[it->second] = true;
    const auto& rb = b.rows[it->second];
    fill(b, rb, row.error_new, row.f_evals_new);
    const bool timed_row = has_cost && ra[column_index(a.header, "cost")] == "wall";
    compare_cells(compared, ra, rb, opt, timed_row, row);
    if (timing) {
      row.has_timing = true;
      row.timing = compare_timing(*timing, a, ra, b, rb);
    }
    out.push_back(std::move(row));
  }
  for (std::size_t j = 0; j < kb.size(); ++j) {
    if (matched[j]) continue;
    RowComparison row;
    row.file = f.file;
    row.key = kb[j];
    row.presence = RowComparison::Presence::new_only;
    row.changed = true;
    row.error_column = error_column;
    fill(b, b.rows[j], row.error_new, row.f_evals_new);
    row.differences.push_back("row only in NEW");
    out.push_back(std::move(row));
  }
  f.rows = static_cast<long>(out.size() - first);
  f.changed_rows =
      static_cast<long>(std::count_if(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
                                      [](const RowComparison& r) { return r.changed; }));
}

// The run record of a JSON file: the object holding "experiment" (at the top, or under
// "metadata" for `run`); null when the file records no run.
nlohmann::json run_record(const nlohmann::json& j) {
  if (j.is_object() && j.contains("experiment")) return j;
  if (j.is_object() && j.contains("metadata") && j["metadata"].is_object() &&
      j["metadata"].contains("experiment"))
    return j["metadata"];
  return nullptr;
}

// Every leaf where two JSON values differ, as (key, old, new).
void json_differences(const nlohmann::json& a, const nlohmann::json& b, const std::string& path,
                      std::vector<RecordDifference>& out, const std::string& file) {
  if (a == b) return;
  if (a.is_object() && b.is_object()) {
    std::set<std::string> keys;
    for (const auto& [k, v] : a.items()) keys.insert(k);
    for (const auto& [k, v] : b.items()) keys.insert(k);
    for (const auto& k : keys) {
      const std::string sub = path + "." + k;
      if (!a.contains(k))
        out.push_back({file, sub, "(absent)", b[k].dump()});
      else if (!b.contains(k))
        out.push_back({file, sub, a[k].dump(), "(absent)"});
      else
        json_differences(a[k], b[k], sub, out, file);
    }
    return;
  }
  out.push_back({file, path, a.dump(), b.dump()});
}

void compare_records(const fs::path& old_path, const fs::path& new_path, FileComparison& f,
                     std::vector<RecordDifference>& out) {
  nlohmann::json a, b;
  try {
    std::ifstream ia(old_path, std::ios::binary), ib(new_path, std::ios::binary);
    a = nlohmann::json::parse(ia);
    b = nlohmann::json::parse(ib);
  } catch (const std::exception&) {
    f.notes.push_back("not valid JSON on one side: not compared");
    return;
  }
  // Through text, as written: NaN is null on both sides.
  const nlohmann::json ma = run_record(a), mb = run_record(b);
  if (ma.is_null() || mb.is_null()) {
    f.notes.push_back("records no run (no \"experiment\"): not compared");
    return;
  }
  // The spec: at the top of run.json, else in the record.
  const nlohmann::json sa = a.contains("spec") ? a["spec"] : ma.value("spec", nlohmann::json());
  const nlohmann::json sb = b.contains("spec") ? b["spec"] : mb.value("spec", nlohmann::json());
  std::vector<RecordDifference> spec;
  json_differences(nlohmann::json::parse(sa.dump()), nlohmann::json::parse(sb.dump()), "spec", spec,
                   f.file);
  if (spec.size() > kMaxSpecDifferences) {
    const std::size_t more = spec.size() - kMaxSpecDifferences;
    spec.resize(kMaxSpecDifferences);
    spec.push_back({f.file, "spec", "(" + std::to_string(more) + " more keys differ)", ""});
  }
  out.insert(out.end(), spec.begin(), spec.end());
  for (const auto& k : kRecordKeys) {
    const std::string x = ma.contains(k) ? ma[k].dump() : "(absent)";
    const std::string y = mb.contains(k) ? mb[k].dump() : "(absent)";
    if (x != y) out.push_back({f.file, k, x, y});
  }
}

void require_folder(const fs::path& p, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(p, ec)) throw BadInput("compare: " + what + " " + p.string() + " does not exist");
  if (!fs::is_directory(p, ec))
    throw BadInput("compare: " + what + " " + p.string() +
                   " is not a folder (give the output folders of two runs)");
}

// Whether `inner` is `outer` or below it (both made absolute and normal).
bool is_within(const fs::path& inner, const fs::path& outer) {
  const fs::path i = fs::weakly_canonical(fs::absolute(inner));
  const fs::path o = fs::weakly_canonical(fs::absolute(outer));
  auto ii = i.begin();
  for (auto oi = o.begin(); oi != o.end(); ++oi, ++ii) {
    if (oi->empty()) continue;  // a trailing separator
    if (ii == i.end() || *ii != *oi) return false;
  }
  return true;
}

std::string presence_text(FileComparison::Presence p) {
  return p == FileComparison::Presence::old_only   ? "only in OLD"
         : p == FileComparison::Presence::new_only ? "only in NEW"
                                                   : "both";
}

std::string row_status(const RowComparison& r) {
  if (r.presence == RowComparison::Presence::old_only) return "only_old";
  if (r.presence == RowComparison::Presence::new_only) return "only_new";
  return r.changed ? "changed" : "same";
}

std::string ratio_of_texts(const std::string& a, const std::string& b) {
  const auto x = as_number(a), y = as_number(b);
  return x && y ? compare_ratio(*x, *y) : (a == b && !a.empty() ? "1" : "-");
}

std::string error_ratio(const RowComparison& r) {
  return r.error_column.empty() ? "-" : ratio_of_texts(r.error_old, r.error_new);
}

std::string counters_text(const RowComparison& r) {
  if (r.presence != RowComparison::Presence::both) return "-";
  return r.counter_changes.empty() ? "equal" : join(r.counter_changes, "; ");
}

std::string interval_text(double median, double low, double high, int runs, bool interval) {
  if (!std::isfinite(median)) return "-";
  std::string s = format_short(median, 2);
  if (interval) s += " [" + format_short(low, 2) + ", " + format_short(high, 2) + "]";
  return s + " (" + std::to_string(runs) + (runs == 1 ? " run)" : " runs)");
}

}  // namespace

std::vector<std::string> compare_counter_columns() {
  std::vector<std::string> names;
  for (const auto& n : SolveStats::field_names())
    if (n != "status" && n != "wall_s") names.push_back(n);
  return names;
}

long CompareResult::changed_rows() const {
  return static_cast<long>(
      std::count_if(rows.begin(), rows.end(), [](const RowComparison& r) { return r.changed; }));
}

long CompareResult::files_on_one_side() const {
  return static_cast<long>(std::count_if(files.begin(), files.end(), [](const FileComparison& f) {
    return f.presence != FileComparison::Presence::both;
  }));
}

std::string compare_ratio(double old_value, double new_value) {
  if (std::isnan(old_value) || std::isnan(new_value)) return "-";
  if (old_value == new_value) return "1";
  if (old_value == 0) return "inf";
  const double r = new_value / old_value;
  if (std::abs(r - 1) < 1e-5) return (r > 1 ? "1+" : "1-") + format_short(std::abs(r - 1), 1);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", r);
  return buf;
}

nlohmann::json compare_spec(const fs::path& old_dir, const fs::path& new_dir,
                            const CompareOptions& opt) {
  return {{"old", fs::weakly_canonical(fs::absolute(old_dir)).string()},
          {"new", fs::weakly_canonical(fs::absolute(new_dir)).string()},
          {"rtol", opt.rtol},
          {"atol", opt.atol}};
}

CompareResult compare_runs(const fs::path& old_dir, const fs::path& new_dir,
                           const CompareOptions& opt) {
  require_input(std::isfinite(opt.rtol) && opt.rtol >= 0,
                "--rtol " + format_full(opt.rtol) + ": must be a finite number >= 0");
  require_input(std::isfinite(opt.atol) && opt.atol >= 0,
                "--atol " + format_full(opt.atol) + ": must be a finite number >= 0");
  require_folder(old_dir, "OLD");
  require_folder(new_dir, "NEW");
  CompareResult res;
  res.old_dir = old_dir;
  res.new_dir = new_dir;
  res.options = opt;
  const auto old_files = result_files(old_dir), new_files = result_files(new_dir);
  std::vector<std::string> all = old_files;
  all.insert(all.end(), new_files.begin(), new_files.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  bool any_table = false;
  for (const auto& rel : all) {
    FileComparison f;
    f.file = rel;
    f.is_table = fs::path(rel).extension() == ".csv";
    const bool in_old = std::binary_search(old_files.begin(), old_files.end(), rel);
    const bool in_new = std::binary_search(new_files.begin(), new_files.end(), rel);
    f.presence = in_old && in_new ? FileComparison::Presence::both
                 : in_old         ? FileComparison::Presence::old_only
                                  : FileComparison::Presence::new_only;
    any_table = any_table || (f.is_table && in_old && in_new);
    res.files.push_back(std::move(f));
  }
  if (!any_table)
    throw BadInput("compare: OLD " + old_dir.string() + " and NEW " + new_dir.string() +
                   " hold no CSV file of the same relative path (" +
                   std::to_string(old_files.size()) + " and " + std::to_string(new_files.size()) +
                   " CSV/JSON files): nothing to compare");
  for (auto& f : res.files) {
    if (f.presence != FileComparison::Presence::both) continue;
    if (f.is_table)
      compare_table_files(old_dir / f.file, new_dir / f.file, f, res.rows, opt);
    else
      compare_records(old_dir / f.file, new_dir / f.file, f, res.records);
  }
  return res;
}

Table compare_table(const CompareResult& r) {
  Table t{{"file",          "row",         "status",          "differences",
           "error_column",  "error_old",   "error_new",       "error_ratio",
           "f_evals_old",   "f_evals_new", "f_evals_ratio",   "counters",
           "time_column",   "time_old",    "time_old_ci_low", "time_old_ci_high",
           "time_old_runs", "time_new",    "time_new_ci_low", "time_new_ci_high",
           "time_new_runs", "time_ratio",  "time_verdict"},
          {}};
  for (const auto& f : r.files)
    if (f.presence != FileComparison::Presence::both) {
      // A file on one side only: its name, kind and note; the row and ratio columns stay empty.
      std::vector<std::string> v(t.columns.size());
      v[0] = f.file;
      v[2] = f.presence == FileComparison::Presence::old_only ? "file_only_old" : "file_only_new";
      v[3] = "file " + presence_text(f.presence);
      t.rows.push_back(std::move(v));
    }
  for (const auto& row : r.rows) {
    std::vector<std::string> v = {
        row.file,
        row.key,
        row_status(row),
        join(row.differences, "; "),
        row.error_column,
        row.error_old,
        row.error_new,
        row.error_column.empty() ? "" : ratio_of_texts(row.error_old, row.error_new),
        row.f_evals_old,
        row.f_evals_new,
        ratio_of_texts(row.f_evals_old, row.f_evals_new),
        counters_text(row)};
    if (row.has_timing) {
      const auto& tm = row.timing;
      for (const auto& x :
           {tm.quantity, format_full(tm.old_median), format_full(tm.old_low),
            format_full(tm.old_high), std::to_string(tm.old_runs), format_full(tm.new_median),
            format_full(tm.new_low), format_full(tm.new_high), std::to_string(tm.new_runs),
            compare_ratio(tm.old_median, tm.new_median), tm.verdict})
        v.push_back(x);
    } else {
      v.resize(t.columns.size());
    }
    t.rows.push_back(std::move(v));
  }
  return t;
}

// The section of one table present on both sides: its matched rows, the changed ones, and the
// timing of every row when the table was timed with intervals.
void table_markdown(std::ostringstream& md, const CompareResult& r, const FileComparison& f) {
  md << "\n## " << f.file << "\n\n"
     << f.rows << (f.rows == 1 ? " row" : " rows") << " matched by "
     << (f.key_columns.empty() ? "row number" : join(f.key_columns, ", ")) << ": ";
  md << (f.changed_rows ? std::to_string(f.changed_rows) + " differ" : "all agree") << ".\n";
  for (const auto& n : f.notes) md << "- " << n << "\n";
  std::vector<const RowComparison*> rows;
  // A table timed with intervals gets every row's timing; single times (one run per row) say
  // nothing row by row and stay in compare.csv.
  const RowComparison* timed = nullptr;
  for (const auto& row : r.rows)
    if (row.file == f.file) {
      rows.push_back(&row);
      if (!timed && row.has_timing && row.timing.has_interval) timed = &row;
    }
  if (f.changed_rows) {
    Table t{{"row", "error ratio", "f_evals ratio", "counters", "differences"}, {}};
    std::size_t shown = 0;
    for (const auto* row : rows)
      if (row->changed && shown++ < kMaxMarkdownRows)
        t.rows.push_back({row->key, error_ratio(*row),
                          ratio_of_texts(row->f_evals_old, row->f_evals_new), counters_text(*row),
                          join(row->differences, "; ")});
    md << "\nChanged rows (ratios NEW/OLD):\n\n" << t.to_markdown();
    if (shown > kMaxMarkdownRows)
      md << "\n(" << shown - kMaxMarkdownRows << " more in compare.csv)\n";
  }
  if (!timed) {
    for (const auto* row : rows)
      if (row->has_timing) {
        md << "\n"
           << row->timing.quantity
           << ": one run per row on each side, no verdict (both times are in compare.csv).\n";
        break;
      }
    return;
  }
  Table t{{"row", "error ratio", "f_evals ratio", "counters", "OLD time [95% interval]",
           "NEW time [95% interval]", "time ratio", "verdict"},
          {}};
  for (std::size_t k = 0; k < rows.size() && k < kMaxMarkdownRows; ++k) {
    const auto& row = *rows[k];
    const auto& tm = row.timing;
    t.rows.push_back({row.key, error_ratio(row), ratio_of_texts(row.f_evals_old, row.f_evals_new),
                      counters_text(row),
                      row.has_timing ? interval_text(tm.old_median, tm.old_low, tm.old_high,
                                                     tm.old_runs, tm.has_interval)
                                     : "-",
                      row.has_timing ? interval_text(tm.new_median, tm.new_low, tm.new_high,
                                                     tm.new_runs, tm.has_interval)
                                     : "-",
                      row.has_timing ? compare_ratio(tm.old_median, tm.new_median) : "-",
                      row.has_timing ? tm.verdict : "-"});
  }
  md << "\nPer row (ratios NEW/OLD; time: " << timed->timing.quantity
     << ", the median with its bootstrap 95% interval; faster/slower when the intervals are "
        "disjoint and each side has at least "
     << kCompareMinTimedRuns << " runs):\n\n"
     << t.to_markdown();
  if (rows.size() > kMaxMarkdownRows)
    md << "\n(" << rows.size() - kMaxMarkdownRows << " more in compare.csv)\n";
}

std::string compare_markdown(const CompareResult& r) {
  std::ostringstream md;
  md << "# Compare: " << r.old_dir.string() << " (OLD) against " << r.new_dir.string()
     << " (NEW)\n\n";
  long tables = 0, records = 0;
  for (const auto& f : r.files)
    if (f.presence == FileComparison::Presence::both) (f.is_table ? tables : records) += 1;
  const long changed = r.changed_rows(), one_side = r.files_on_one_side();
  md << (r.same() ? "**Same results**: " : "**Results differ**: ") << changed << " of "
     << r.rows.size() << " rows in " << tables << (tables == 1 ? " table" : " tables") << " differ";
  if (one_side) md << ", " << one_side << " files are on one side only";
  md << ". Real numbers agree within |new - old| <= " << format_short(r.options.rtol, 1)
     << "·max(|old|, |new|) + " << format_full(r.options.atol)
     << "; counters and text must be equal; wall times are measurements, reported below and "
        "not compared.\n";
  for (const auto& f : r.files)
    if (f.presence != FileComparison::Presence::both)
      md << "\n- `" << f.file << "`: " << presence_text(f.presence);
  if (one_side) md << "\n";

  md << "\n## Run records\n\n";
  if (r.records.empty()) {
    md << records << " run record" << (records == 1 ? "" : "s")
       << " compared: the same spec, versions (stiffbench, Eigen, SUNDIALS, GSL), git revision, "
          "compiler, build type, flags, CPU model, thread count and seed.\n";
  } else {
    Table t{{"file", "key", "OLD", "NEW"}, {}};
    for (const auto& d : r.records) t.rows.push_back({d.file, d.key, d.old_value, d.new_value});
    md << t.to_markdown();
  }

  for (const auto& f : r.files)
    if (f.presence == FileComparison::Presence::both && f.is_table) table_markdown(md, r, f);
  return md.str();
}

void write_compare_outputs(const fs::path& dir, const CompareResult& r) {
  write_file_atomic(dir / "compare.csv", compare_table(r).to_csv());
  write_file_atomic(dir / "compare.md", compare_markdown(r));
  nlohmann::json meta = run_metadata("compare", compare_spec(r.old_dir, r.new_dir, r.options));
  meta["same"] = r.same();
  meta["rows"] = r.rows.size();
  meta["changed_rows"] = r.changed_rows();
  meta["files_on_one_side"] = r.files_on_one_side();
  nlohmann::json diffs = nlohmann::json::array();
  for (const auto& d : r.records)
    diffs.push_back({{"file", d.file}, {"key", d.key}, {"old", d.old_value}, {"new", d.new_value}});
  meta["record_differences"] = diffs;
  write_file_atomic(dir / "compare.json", meta.dump(2) + "\n");
}

CompareResult compare_study(const fs::path& old_dir, const fs::path& new_dir,
                            const CompareOptions& opt, const fs::path& out_dir,
                            std::ostream* note) {
  require_input(std::isfinite(opt.rtol) && opt.rtol >= 0,
                "--rtol " + format_full(opt.rtol) + ": must be a finite number >= 0");
  require_input(std::isfinite(opt.atol) && opt.atol >= 0,
                "--atol " + format_full(opt.atol) + ": must be a finite number >= 0");
  require_folder(old_dir, "OLD");
  require_folder(new_dir, "NEW");
  for (const auto& [dir, what] : {std::pair{old_dir, "OLD"}, std::pair{new_dir, "NEW"}})
    if (is_within(out_dir, dir))
      throw BadInput("--out " + out_dir.string() + " is inside " + what + " " + dir.string() +
                     ": the comparison would be written into the results it compares; choose "
                     "another --out");
  require_output_dir(out_dir);
  check_study_output(out_dir, "compare", compare_spec(old_dir, new_dir, opt), force_output(), note);
  CompareResult r = compare_runs(old_dir, new_dir, opt);
  write_compare_outputs(out_dir, r);
  return r;
}

}  // namespace stiffbench
