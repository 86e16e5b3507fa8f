#include "experiments/commands/run.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>

#include "core/run_control.hpp"
#include "core/types.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/spec_file.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/csv.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/progress.hpp"

namespace stiffbench {

namespace fs = std::filesystem;

namespace {

// ---- expansion ----------------------------------------------------------------------------

struct Point {
  std::map<std::string, SpecScalar> settings;  // top-level key -> value
  Params params;
  std::vector<std::string> tags;  // values of the sweep dimensions, in dimension order
  std::string label;              // "n=8, t_end=1"
};

struct Expansion {
  std::vector<const SpecEntry*> dims;
  std::vector<Point> points;
  long units_per_point = 1;
  long units() const { return static_cast<long>(points.size()) * units_per_point; }
};

Expansion expand(const SpecFile& spec) {
  Expansion ex;
  std::vector<const SpecEntry*> all;
  for (const auto& e : spec.settings) all.push_back(&e);
  for (const auto& e : spec.params) all.push_back(&e);
  for (const auto* e : all)
    if (e->is_list) ex.dims.push_back(e);
  ex.units_per_point = !study_kind(spec.kind).unit_per_integrator
                           ? 1
                           : static_cast<long>(std::max<std::size_t>(1, spec.integrators.size()));
  // The size first, with every product checked against the limit, before anything is expanded.
  long n = 1;
  std::string sizes;
  for (const auto* d : ex.dims)
    sizes += (sizes.empty() ? "" : " x ") + d->path + " (" + std::to_string(d->values.size()) + ")";
  for (const auto* d : ex.dims) {
    const auto size = static_cast<long>(d->values.size());
    if (size > 0 && n > kMaxSweepUnits / size / ex.units_per_point)
      throw BadInput(spec.file + ": the sweep " + sizes + " x " +
                     std::to_string(ex.units_per_point) + " integrator(s) has more than " +
                     std::to_string(kMaxSweepUnits) +
                     " units, the most a run takes; split it into several spec files");
    n *= size;
  }
  for (long p = 0; p < n; ++p) {
    Point pt;
    // Digits of p in the mixed radix of the dimensions, the last dimension fastest.
    std::vector<std::size_t> idx(ex.dims.size());
    long rest = p;
    for (std::size_t d = ex.dims.size(); d-- > 0;) {
      const long size = static_cast<long>(ex.dims[d]->values.size());
      idx[d] = static_cast<std::size_t>(rest % size);
      rest /= size;
    }
    for (const auto* e : all) {
      std::size_t k = 0;
      for (std::size_t d = 0; d < ex.dims.size(); ++d)
        if (ex.dims[d] == e) k = idx[d];
      const SpecScalar& v = e->values[k];
      if (e->path.rfind("params.", 0) == 0)
        pt.params.set(e->key, v.text);
      else
        pt.settings[e->key] = v;
    }
    for (std::size_t d = 0; d < ex.dims.size(); ++d) {
      const std::string& v = ex.dims[d]->values[idx[d]].text;
      pt.tags.push_back(v);
      pt.label += (d ? ", " : "") + ex.dims[d]->path + "=" + v;
    }
    ex.points.push_back(std::move(pt));
  }
  return ex;
}

// ---- the study of one point ------------------------------------------------------------------

const SpecScalar* get(const Point& p, const std::string& key) {
  const auto it = p.settings.find(key);
  return it == p.settings.end() ? nullptr : &it->second;
}
std::string text_or(const Point& p, const std::string& key, const std::string& dflt) {
  const SpecScalar* v = get(p, key);
  return v ? v->text : dflt;
}

const SpecEntry* find_entry(const std::vector<SpecEntry>& list, const std::string& key) {
  for (const auto& e : list)
    if (e.key == key) return &e;
  return nullptr;
}

// A point's study options: its settings but the model, as the command line would give them.
Params point_options(const Point& p) {
  Params o;
  for (const auto& [key, value] : p.settings)
    if (key != "model") o.set(key, value.text);
  return o;
}

// The job of one point for `integrators` (BadInput naming the file, line and key of a bad
// option).
std::unique_ptr<StudyJob> point_job(const SpecFile& s, const Point& p,
                                    const std::vector<std::string>& integrators,
                                    const std::string& cache_dir) {
  const StudyKind& kind = study_kind(s.kind);
  StudyTarget target;
  target.model = text_or(p, "model", "");
  target.params = p.params;
  target.integrators = integrators;
  StudyContext ctx;
  ctx.cache_dir = cache_dir;
  ctx.use_output_cache = false;
  auto how = [&](const std::string& key) {
    const SpecEntry* e = find_entry(s.settings, key);
    return e ? e->where + ": key '" + e->path + "'" : s.file + ": key '" + key + "'";
  };
  return make_study(kind, target, point_options(p), ctx, how);
}

// Runs one unit (integrators: the unit's; all of them for a study of one unit per point).
Table run_unit(const SpecFile& s, const Point& p, const std::vector<std::string>& integrators,
               const std::string& out_dir) {
  auto job = point_job(s, p, integrators, out_dir);
  job->run(nullptr);
  return job->unit_table();
}

// Checks names and parameters of one point with the registries (no model is created) and the
// study's own validation; BadInput naming the file, line and key.
void validate_point(const SpecFile& s, const Point& p) {
  const std::string at = p.label.empty() ? "" : " (sweep point " + p.label + ")";
  const StudyKind& kind = study_kind(s.kind);
  try {
    const ModelRegistry::Entry* model = nullptr;
    const std::string model_name = kind.takes_model ? text_or(p, "model", "") : "";
    if (kind.takes_model && (kind.model_required || !model_name.empty())) {
      model = model_registry().find(model_name);
      if (!model)
        spec_error(*find_entry(s.settings, "model"),
                   "unknown model '" + model_name + "'; known: " + join(model_registry().names()));
    } else if (!kind.takes_model && !p.params.empty()) {
      spec_error(s.params.front(), "a " + s.kind + " spec takes no parameters");
    }
    std::vector<const IntegratorRegistry::Entry*> integ;
    for (const auto& name : s.integrators) {
      const auto* e = integrator_registry().find(name);
      if (!e)
        throw BadInput(s.integrators_where + ": key 'integrators': unknown integrator '" + name +
                       "'; known: " + join(integrator_registry().names()));
      integ.push_back(e);
    }
    // Each parameter is checked against the model and the integrators (its file, line and key
    // in the message) before the job resolves them, then again with the study's helpers (a
    // reference method) for keys that none of them takes.
    auto check_params = [&](bool require_consumed) {
      for (const auto& [key, value] : p.params.values()) {
        const SpecEntry& entry = *find_entry(s.params, key);
        Params one;
        one.set(key, value);
        std::set<std::string> consumed;
        try {
          if (model)
            resolve_params(model->params, one, &consumed, "model '" + model->info.name + "'");
          for (const auto* e : integ)
            resolve_params(e->params, one, &consumed, "integrator '" + e->info.name + "'");
        } catch (const BadInput& err) {
          spec_error(entry, err.what());
        }
        if (require_consumed && !consumed.count(key)) {
          std::string accepted = model ? model_registry().accepted_keys(model->info.name) : "";
          for (const auto* e : integ)
            accepted += "; " + integrator_registry().accepted_keys(e->info.name);
          spec_error(entry, "unknown parameter; " + accepted);
        }
      }
    };
    check_params(false);
    const auto job = point_job(s, p, s.integrators, "");
    for (const auto& helper : job->helper_integrators())
      if (const auto* e = integrator_registry().find(helper)) integ.push_back(e);
    check_params(true);
  } catch (const BadInput& e) {
    const std::string msg = e.what();
    if (msg.rfind(s.file, 0) == 0 || msg.rfind("--set", 0) == 0) throw BadInput(msg + at);
    throw BadInput(s.file + at + ": " + msg);
  }
}

// ---- CSV -------------------------------------------------------------------------------------

// Reads a run CSV (experiments/output/csv.hpp): the header and the complete units.
CsvContent read_run_csv(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_run_csv(ss.str());
}

std::string csv_name(const std::string& kind) {
  std::string n = kind;
  std::replace(n.begin(), n.end(), '-', '_');
  return n + ".csv";
}

std::string md_name(const std::string& kind) {
  return fs::path(csv_name(kind)).replace_extension(".md").string();
}

// `spec` with the method files among its integrators registered and replaced by their names;
// relative paths are relative to the spec file's folder (catalog.hpp).
SpecFile with_method_names(SpecFile spec) {
  try {
    spec.integrators = resolve_integrator_tokens(std::move(spec.integrators),
                                                 fs::path(spec.file).parent_path().string());
  } catch (const BadInput& e) {
    throw BadInput(spec.integrators_where + ": key 'integrators': " + e.what());
  }
  return spec;
}

// The record of a spec whose method files are resolved: its JSON with "method_files".
nlohmann::json resolved_record(const SpecFile& resolved) {
  return with_method_files(resolved.to_json());
}

}  // namespace

nlohmann::json spec_record(const SpecFile& spec) {
  return resolved_record(with_method_names(spec));
}

std::string spec_hash(const SpecFile& spec) {
  return hex16(fnv1a64(spec_identity(spec_record(spec)).dump()));
}

namespace {

void write_all(const fs::path& path, const std::string& header,
               const std::map<long, UnitRows>& units) {
  std::string text = header;
  for (const auto& [u, rows] : units)
    for (const auto& l : rows.lines) text += l;
  write_file_atomic(path, text);
}

// OUT/<kind>.md: the rows as a Markdown table (reals in short form; unit_rows left out), written
// beside the CSV once every unit is present (unsharded run or complete merge).
void write_markdown(const fs::path& csv_path, const std::string& header,
                    const std::map<long, UnitRows>& units) {
  std::string h = header;
  while (!h.empty() && (h.back() == '\n' || h.back() == '\r')) h.pop_back();
  const std::vector<std::string> cols = parse_csv_line(h);
  const auto skip = std::find(cols.begin(), cols.end(), "unit_rows") - cols.begin();
  Table t;
  for (std::size_t i = 0; i < cols.size(); ++i)
    if (static_cast<long>(i) != skip) t.columns.push_back(cols[i]);
  for (const auto& [u, rows] : units)
    for (std::string l : rows.lines) {
      while (!l.empty() && (l.back() == '\n' || l.back() == '\r')) l.pop_back();
      const std::vector<std::string> f = parse_csv_line(l);
      std::vector<std::string> r;
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (static_cast<long>(i) == skip) continue;
        const std::string& v = f[i];
        char* end = nullptr;
        const double x = v.empty() ? 0.0 : std::strtod(v.c_str(), &end);
        const bool real = !v.empty() && end && *end == '\0' &&
                          v.find_first_of(".eE") != std::string::npos && std::isfinite(x);
        r.push_back(real ? format_short(x) : v);
      }
      t.rows.push_back(std::move(r));
    }
  fs::path md = csv_path;
  md.replace_extension(".md");
  write_file_atomic(md, t.to_markdown());
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw BadInput(path.string() + " not found (not a folder written by `stiffbench run`)");
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw BadInput(path.string() + ": " + e.what());
  }
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

void write_slurm(const RunOptions& opt, const SpecFile& spec, const Expansion& ex,
                 std::ostream& out) {
  const int n = opt.slurm_tasks;
  const fs::path dir = fs::absolute(opt.out_dir);
  const fs::path slurm = dir / "slurm";
  require_output_dir(slurm);
  std::error_code ec;
  fs::path bin = fs::read_symlink("/proc/self/exe", ec);
  if (ec) bin = "stiffbench";
  const std::string spec_abs = fs::absolute(opt.spec_file).string();
  std::string sets;
  for (const auto& s : opt.sets) sets += " --set " + shell_quote(s);
  auto header = [&](const std::string& name) {
    std::string h = "#!/bin/bash\n#SBATCH --job-name=" + name + "\n";
    if (!opt.partition.empty()) h += "#SBATCH --partition=" + opt.partition + "\n";
    if (!opt.time_limit.empty()) h += "#SBATCH --time=" + opt.time_limit + "\n";
    return h;
  };
  std::string array = header("stiffbench-" + spec.kind);
  array += "#SBATCH --array=0-" + std::to_string(n - 1) + "\n";
  array += "#SBATCH --ntasks=1\n";
  array += "#SBATCH --output=" + (slurm / "shard-%a.log").string() + "\n";
  array += "# One shard of " + std::to_string(ex.units()) + " units of " + spec_abs +
           " per array task; exit code " + std::to_string(kExitRowsFailed) +
           " (rows failed, recorded in the CSV) counts as success so the merge job runs.\n";
  array += "set -u\n";
  array += "task=${SLURM_ARRAY_TASK_ID}\n";
  array += shell_quote(bin.string()) + " run " + shell_quote(spec_abs) + sets +
           " --shard ${task}/" + std::to_string(n) + " --out " + shell_quote(dir.string()) +
           "/shard-${task} --resume\n";
  array += "rc=$?\n";
  array += "if [ \"$rc\" -eq " + std::to_string(kExitRowsFailed) + " ]; then exit 0; fi\n";
  array += "exit $rc\n";
  std::string merge = header("stiffbench-merge");
  merge += "#SBATCH --ntasks=1\n";
  merge += "#SBATCH --output=" + (slurm / "merge.log").string() + "\n";
  merge += "exec " + shell_quote(bin.string()) + " merge --out " + shell_quote(dir.string());
  for (int i = 0; i < n; ++i)
    merge += " " + shell_quote((dir / ("shard-" + std::to_string(i))).string());
  merge += "\n";
  std::string submit =
      "#!/bin/bash\n# Submits the job array, then the merge job after it succeeded.\nset -euo "
      "pipefail\n";
  submit +=
      "array_id=$(sbatch --parsable " + shell_quote((slurm / "array.sbatch").string()) + ")\n";
  submit += "array_id=${array_id%%;*}\n";
  submit += "merge_id=$(sbatch --parsable --dependency=afterok:${array_id} " +
            shell_quote((slurm / "merge.sbatch").string()) + ")\n";
  submit += "merge_id=${merge_id%%;*}\n";
  submit += "echo \"array job ${array_id}, merge job ${merge_id}\"\n";
  write_file_atomic(slurm / "array.sbatch", array);
  write_file_atomic(slurm / "merge.sbatch", merge);
  write_file_atomic(slurm / "submit.sh", submit);
  fs::permissions(slurm / "submit.sh", fs::perms::owner_exec | fs::perms::group_exec,
                  fs::perm_options::add);
  out << "wrote " << (slurm / "array.sbatch").string() << " (job array of " << n << " tasks over "
      << ex.units() << " units)\n";
  out << "wrote " << (slurm / "merge.sbatch").string() << " (merges into " << dir.string() << ")\n";
  out << "wrote " << (slurm / "submit.sh").string() << "\n";
  out << "submit with: bash " << (slurm / "submit.sh").string() << "\n";
}

}  // namespace

std::unique_ptr<StudyJob> make_spec_job(const SpecFile& given, const std::string& cache_dir) {
  const SpecFile spec = with_method_names(given);
  const Expansion ex = expand(spec);
  if (ex.points.size() != 1)
    throw BadInput(spec.file + ": key '" + ex.dims.front()->path +
                   "': a report section is one study, not a sweep (run sweeps with `stiffbench "
                   "run`)");
  validate_point(spec, ex.points.front());
  return point_job(spec, ex.points.front(), spec.integrators, cache_dir);
}

void parse_shard(const std::string& arg, int& index, int& count) {
  const auto slash = arg.find('/');
  try {
    std::size_t a = 0, b = 0;
    if (slash == std::string::npos) throw BadInput("");
    index = std::stoi(arg.substr(0, slash), &a);
    count = std::stoi(arg.substr(slash + 1), &b);
    if (a != slash || b != arg.size() - slash - 1) throw BadInput("");
  } catch (const std::exception&) {
    throw BadInput("--shard '" + arg + "': expected I/N with integers 0 <= I < N");
  }
  if (count < 1 || index < 0 || index >= count)
    throw BadInput("--shard '" + arg + "': expected I/N with 0 <= I < N");
}

namespace {

// The run CSV's columns: unit, unit_rows, the sweep dimensions, the study's own columns,
// unit_status, unit_message.
std::string run_header(const std::vector<std::string>& study, const Expansion& ex) {
  std::vector<std::string> columns = {"unit", "unit_rows"};
  for (const auto* d : ex.dims) {
    const bool clash = std::find(study.begin(), study.end(), d->path) != study.end() ||
                       d->path == "unit" || d->path == "unit_rows";
    columns.push_back(clash ? "spec." + d->path : d->path);
  }
  columns.insert(columns.end(), study.begin(), study.end());
  columns.push_back("unit_status");
  columns.push_back("unit_message");
  return csv_line(columns);
}

// Output safety: a folder holding a run of a different spec (run.json) is refused unless
// --force; one holding units of this spec needs --resume (run the missing ones) or --force
// (start over). Returns the units kept by --resume.
std::map<long, UnitRows> kept_units(const RunOptions& opt, const SpecFile& spec,
                                    const Expansion& ex, const std::string& header,
                                    const std::string& hash, std::ostream& err) {
  const fs::path dir = opt.out_dir;
  const std::string kind = spec.kind;
  const fs::path csv = dir / csv_name(kind);
  require_input(!(opt.resume && opt.force),
                "--resume and --force: choose one (--resume keeps the units in " + dir.string() +
                    ", --force starts over)");
  const std::string shard = std::to_string(opt.shard_index) + "/" + std::to_string(opt.shard_count);
  if (check_existing_results(dir, "run.json", {csv_name(kind), md_name(kind)},
                             resolved_record(spec), opt.force, opt.force ? &err : nullptr) &&
      !opt.resume && !opt.force) {
    const long present = static_cast<long>(read_run_csv(csv).units.size());
    if (present > 0) {
      long in_shard = 0;
      for (long u = opt.shard_index; u < ex.units(); u += opt.shard_count) ++in_shard;
      throw BadInput("--out " + dir.string() + " holds " + std::to_string(present) + " of " +
                     std::to_string(in_shard) + " unit(s) of this spec (" + csv.string() +
                     "); pass --resume to run the missing ones, --force to start over, or "
                     "choose another --out");
    }
    err << "note: --out " << dir.string()
        << " holds a run of this spec without complete units: starting it again\n";
  }
  if (opt.force) {
    std::error_code ignore;
    fs::remove(dir / md_name(kind), ignore);  // the table of the run being replaced
  }
  std::map<long, UnitRows> done;
  if (opt.resume && fs::exists(csv)) {
    const nlohmann::json prev = read_json(dir / "run.json");
    if (prev.value("spec_hash", "") != hash) {
      const std::string d =
          prev.contains("spec") ? spec_difference(prev["spec"], resolved_record(spec)) : "";
      throw BadInput(
          "--resume: " + dir.string() + " holds a run of a different spec (" +
          (d.empty() ? "hash " + prev.value("spec_hash", "?") + ", this spec " + hash : d) + ")");
    }
    if (prev.value("shard", "") != shard)
      throw BadInput("--resume: " + dir.string() + " holds shard " + prev.value("shard", "?"));
    CsvContent c = read_run_csv(csv);
    if (!c.header.empty() && c.header != header)
      throw BadInput("--resume: " + csv.string() + " has different columns");
    done = std::move(c.units);
    if (c.dropped_rows > 0)
      err << "resume: dropped " << c.dropped_rows
          << " row(s) of incomplete units or units with a duplicated row\n";
    // Rows of a unit this spec and shard do not have are not kept either.
    for (auto it = done.begin(); it != done.end();) {
      if (it->first < ex.units() && it->first % opt.shard_count == opt.shard_index) {
        ++it;
        continue;
      }
      err << "resume: dropped unit " << it->first << " (not a unit of this spec and shard)\n";
      it = done.erase(it);
    }
  }
  return done;
}

// OUT/run.json: the spec, its hash, the sweep dimensions and points, the shard.
void write_run_json(const RunOptions& opt, const SpecFile& spec, const Expansion& ex,
                    const std::string& hash) {
  const std::string kind = spec.kind;
  const std::string shard = std::to_string(opt.shard_index) + "/" + std::to_string(opt.shard_count);
  nlohmann::json run;
  run["spec"] = resolved_record(spec);
  run["spec_file"] = fs::absolute(spec.file).string();
  run["spec_hash"] = hash;
  run["kind"] = kind;
  run["csv"] = csv_name(kind);
  nlohmann::json dims = nlohmann::json::array();
  for (const auto* d : ex.dims) {
    nlohmann::json values = nlohmann::json::array();
    for (const auto& v : d->values) values.push_back(v.to_json());
    dims.push_back({{"key", d->path}, {"values", values}});
  }
  run["dimensions"] = dims;
  run["points"] = ex.points.size();
  nlohmann::json labels = nlohmann::json::array();
  for (const auto& p : ex.points) labels.push_back(p.label);
  run["point_labels"] = labels;  // point i: its sweep values (units i*k .. i*k+k-1)
  run["units"] = ex.units();
  run["shard"] = shard;
  run["sets"] = opt.sets;
  run["metadata"] = run_metadata("run", spec.to_json());
  write_file_atomic(fs::path(opt.out_dir) / "run.json", run.dump(2) + "\n");
}

// Why a unit's rows fail it: "a row has status S" (the last row whose status is none of ok,
// floor, stable_up_to, solver_limit, unstable_for_all_h), or "no rows"; empty when they do not.
std::string unit_failure(const std::vector<std::vector<std::string>>& rows, std::size_t status_col,
                         std::size_t n_study) {
  std::string message;
  for (const auto& r : rows) {
    const std::string st = status_col < n_study ? r[status_col] : "ok";
    if (st != "ok" && st != "floor" && st != "stable_up_to" && st != "solver_limit" &&
        st != "unstable_for_all_h")
      message = "a row has status " + st;
  }
  return rows.empty() ? "no rows" : message;
}

// Runs the units of `todo`, appending each unit's rows to the CSV as it finishes; returns with
// `done` holding every unit's rows.
void run_units(const SpecFile& spec, const Expansion& ex, const std::vector<long>& todo,
               const fs::path& csv, const std::string& out_dir, std::map<long, UnitRows>& done,
               std::ostream& err) {
  const std::vector<std::string> study = study_kind(spec.kind).unit_columns;
  const long per_point = ex.units_per_point;
  const bool unit_per_integrator = study_kind(spec.kind).unit_per_integrator;
  auto unit_integrators = [&](long u) {
    if (!unit_per_integrator) return spec.integrators;
    return std::vector<std::string>{spec.integrators[static_cast<std::size_t>(u % per_point)]};
  };
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(csv.c_str(), "ab"), &std::fclose);
  std::FILE* f = file.get();
  if (!f) throw BadInput("--out: cannot append to " + csv.string());
  Progress progress(&err, "run", static_cast<long>(todo.size()));
  const std::size_t n_study = study.size();
  const auto model_col = std::find(study.begin(), study.end(), "model") - study.begin();
  const auto integ_col = std::find(study.begin(), study.end(), "integrator") - study.begin();
  const auto status_col = std::find(study.begin(), study.end(), "status") - study.begin();
  for (const long u : todo) {
    const Point& p = ex.points[static_cast<std::size_t>(u / per_point)];
    const std::vector<std::string> integ = unit_integrators(u);
    std::vector<std::vector<std::string>> rows;
    std::string unit_status = "ok", message;
    try {
      const Table t = run_unit(spec, p, integ, out_dir);
      rows = t.rows;
      message = unit_failure(rows, static_cast<std::size_t>(status_col), n_study);
      if (!message.empty()) unit_status = "failed";
    } catch (const std::exception& e) {
      unit_status = "error";
      message = e.what();
      rows.clear();
    } catch (const Interrupted&) {
      // The unit in progress is abandoned (none of its rows is written); the units before it
      // are complete lines of the CSV, which --resume keeps.
      err << "run: interrupted in unit " << u << "; " << done.size() << " of " << ex.units()
          << " unit(s) are complete in " << csv.string()
          << ": run the same command with --resume to finish\n";
      throw;
    }
    if (rows.empty()) {
      std::vector<std::string> r(n_study);
      if (static_cast<std::size_t>(model_col) < n_study)
        r[static_cast<std::size_t>(model_col)] = text_or(p, "model", "");
      if (static_cast<std::size_t>(integ_col) < n_study && integ.size() == 1)
        r[static_cast<std::size_t>(integ_col)] = integ.front();
      rows.push_back(std::move(r));
    }
    UnitRows& ur = done[u];
    ur.ok = unit_status == "ok";
    for (const auto& r : rows) {
      std::vector<std::string> fields = {std::to_string(u), std::to_string(rows.size())};
      fields.insert(fields.end(), p.tags.begin(), p.tags.end());
      fields.insert(fields.end(), r.begin(), r.end());
      fields.push_back(unit_status);
      fields.push_back(message);
      const std::string line = csv_line(fields);
      std::fputs(line.c_str(), f);
      std::fflush(f);
      ur.lines.push_back(line);
    }
    if (!ur.ok)
      err << "unit " << u << " (" << join(integ) << (p.label.empty() ? "" : ", ") << p.label
          << "): " << unit_status << ": " << message << "\n";
    progress.tick(join(integ) + (p.label.empty() ? "" : ", " + p.label));
  }
}

}  // namespace

int run_spec(const RunOptions& opt, std::ostream& out, std::ostream& err) {
  return run_loaded_spec(load_spec_file(opt.spec_file, opt.sets), opt, out, err);
}

int run_loaded_spec(const SpecFile& loaded, const RunOptions& opt, std::ostream& out,
                    std::ostream& err) {
  // Written verbatim into #SBATCH lines of the job scripts: a newline would start a shell
  // command there. Slurm's partition names and time limits need none of the other characters.
  for (const auto& [flag, value] :
       {std::pair<const char*, const std::string*>{"--partition", &opt.partition},
        {"--time", &opt.time_limit}})
    for (const char c : *value)
      require_input(std::isalnum(static_cast<unsigned char>(c)) ||
                        std::string_view("_.,:+-").find(c) != std::string_view::npos,
                    std::string(flag) + ": '" + printable(*value) + "' holds a character a Slurm " +
                        (std::string(flag) == "--time" ? "time limit" : "partition name") +
                        " does not have (allowed: letters, digits and _ . , : + -)");
  const SpecFile spec = with_method_names(loaded);
  const Expansion ex = expand(spec);
  for (const auto& p : ex.points) validate_point(spec, p);
  if (opt.slurm_tasks < 0) throw BadInput("--slurm: expected a number of tasks >= 1");

  const std::string kind = spec.kind;
  const bool unit_per_integrator = study_kind(kind).unit_per_integrator;
  out << spec.file << ": " << kind << ", " << ex.points.size() << " point(s) x "
      << (!unit_per_integrator ? std::string("1 unit (all integrators)")
                               : std::to_string(ex.units_per_point) + " integrator(s)")
      << " = " << ex.units() << " unit(s)\n";
  if (opt.check_only) {
    for (std::size_t i = 0; i < ex.points.size(); ++i)
      out << "  point " << i << ": " << (ex.points[i].label.empty() ? "-" : ex.points[i].label)
          << "\n";
    return 0;
  }
  if (opt.slurm_tasks > 0) {
    write_slurm(opt, spec, ex, out);
    return 0;
  }

  const fs::path dir = opt.out_dir;
  require_output_dir(dir);
  const FolderClaim claim(dir, &err);  // no other run writes here until this one is done
  const fs::path csv = dir / csv_name(kind);
  const std::string hash = spec_hash(spec);
  const std::string header = run_header(study_kind(kind).unit_columns, ex);
  std::map<long, UnitRows> done = kept_units(opt, spec, ex, header, hash, err);
  write_all(csv, header, done);  // the kept units (or the header alone)
  write_run_json(opt, spec, ex, hash);

  std::vector<long> todo;
  long in_shard = 0;
  for (long u = 0; u < ex.units(); ++u) {
    if (u % opt.shard_count != opt.shard_index) continue;
    ++in_shard;
    if (!done.count(u)) todo.push_back(u);
  }
  if (opt.resume)
    out << "resume: " << (in_shard - static_cast<long>(todo.size())) << " of " << in_shard
        << " unit(s) already done\n";
  run_units(spec, ex, todo, csv, dir.string(), done, err);
  write_all(csv, header, done);  // sorted by unit
  if (opt.shard_count == 1 && static_cast<long>(done.size()) == ex.units())
    write_markdown(csv, header, done);

  long failed = 0;
  for (const auto& [u, rows] : done) failed += rows.ok ? 0 : 1;
  out << "wrote " << csv.string() << " (" << done.size() << " unit(s)";
  if (failed) out << ", " << failed << " failed";
  out << ") and " << (dir / "run.json").string() << "\n";
  return failed ? kExitRowsFailed : 0;
}

int merge_shards(const std::string& out_dir, const std::vector<std::string>& dirs,
                 std::ostream& out, std::ostream& err, bool force) {
  if (dirs.empty()) throw BadInput("merge: no shard folders given");
  nlohmann::json first;
  std::string header;
  std::map<long, UnitRows> units;
  for (const auto& d : dirs) {
    const nlohmann::json run = read_json(fs::path(d) / "run.json");
    if (first.is_null()) {
      first = run;
    } else if (run.value("spec_hash", "") != first.value("spec_hash", "")) {
      const std::string diff = run.contains("spec") && first.contains("spec")
                                   ? spec_difference(first["spec"], run["spec"])
                                   : "";
      throw BadInput(
          "merge: " + d + " holds a different spec (hash " + run.value("spec_hash", "?") +
          ") than " + dirs.front() + " (hash " + first.value("spec_hash", "?") + ")" +
          (diff.empty() ? "" : ": " + diff + " (there: " + dirs.front() + ", here: " + d + ")"));
    }
    const CsvContent c = read_run_csv(fs::path(d) / run.value("csv", ""));
    if (c.header.empty()) throw BadInput("merge: " + d + " has no rows file");
    if (header.empty()) header = c.header;
    if (c.header != header) throw BadInput("merge: " + d + " has different columns");
    for (const auto& [u, rows] : c.units) units.emplace(u, rows);
  }
  const fs::path dir = out_dir;
  require_output_dir(dir);
  const FolderClaim claim(dir, &err);  // no other run writes here until this one is done
  const std::string name = first.value("csv", "run.csv");
  // Output safety: an --out folder holding a run of a different spec is refused unless --force.
  check_existing_results(dir, "run.json", {name, fs::path(name).replace_extension(".md").string()},
                         first.value("spec", nlohmann::json()), force, &err);
  write_all(dir / name, header, units);
  const long total = first.value("units", 0L);
  std::vector<std::string> missing;
  for (long u = 0; u < total; ++u)
    if (!units.count(u)) missing.push_back(std::to_string(u));
  long failed = 0;
  for (const auto& [u, rows] : units) failed += rows.ok ? 0 : 1;
  nlohmann::json run = first;
  run["shard"] = "merged";
  run["merged_from"] = dirs;
  run["missing_units"] = missing;
  write_file_atomic(dir / "run.json", run.dump(2) + "\n");
  if (missing.empty()) write_markdown(dir / name, header, units);
  out << "merged " << units.size() << " of " << total << " unit(s) from " << dirs.size()
      << " folder(s) into " << (dir / name).string() << "\n";
  if (!missing.empty()) err << "merge: missing units: " << join(missing) << "\n";
  if (failed) err << "merge: " << failed << " unit(s) failed (unit_status in the CSV)\n";
  return missing.empty() && failed == 0 ? 0 : kExitRowsFailed;
}

}  // namespace stiffbench
