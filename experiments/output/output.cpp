#include "experiments/output/output.hpp"

#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <map>
#include <ostream>
#include <sstream>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "core/types.hpp"
#include "experiments/build_info.hpp"
#include "integrators/reference/gsl.hpp"
#include "integrators/reference/sundials.hpp"

namespace stiffbench {

namespace {
std::string g_command_line;
bool g_command_line_set = false;

}  // namespace

std::string csv_field(const std::string& s) {
  std::string f = s;
  std::replace(f.begin(), f.end(), '\n', ' ');
  std::replace(f.begin(), f.end(), '\r', ' ');
  if (f.find_first_of(",\"") == std::string::npos) return f;
  std::string q = "\"";
  for (char c : f) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + csv_field(fields[i]);
  return line + "\n";
}

std::uint64_t fnv1a64(std::string_view s, std::uint64_t h) {
  for (const unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string hex16(std::uint64_t x) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(x));
  return buf;
}

std::optional<double> least_squares_slope(const std::vector<double>& x,
                                          const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 2) return std::nullopt;
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < n; ++k) {
    mx += x[k];
    my += y[k];
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < n; ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  if (!(sxx > 0)) return std::nullopt;
  return sxy / sxx;
}

std::string Table::to_csv() const {
  std::string out = csv_line(columns);
  for (const auto& r : rows) out += csv_line(r);
  return out;
}

std::string markdown_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    if (ch == '|')
      out += "\\|";
    else
      out += ch == '\n' || ch == '\r' ? ' ' : ch;
  }
  return out;
}

namespace {

std::string markdown_cell(const std::string& v) { return v.empty() ? " " : markdown_escape(v); }

}  // namespace

std::string Table::to_markdown() const {
  std::ostringstream os;
  os << "|";
  for (const auto& c : columns) os << " " << markdown_cell(c) << " |";
  os << "\n|";
  for (std::size_t i = 0; i < columns.size(); ++i) os << "---|";
  os << "\n";
  for (const auto& r : rows) {
    os << "|";
    for (const auto& v : r) os << " " << markdown_cell(v) << " |";
    os << "\n";
  }
  return os.str();
}

namespace {
// The process's umask (read by setting it and setting it back; no other thread creates files
// while an output file is being opened).
mode_t current_umask() {
  const mode_t m = ::umask(022);
  ::umask(m);
  return m;
}
}  // namespace

std::filesystem::path create_exclusive_file(const std::filesystem::path& dir,
                                            const std::string& prefix) {
  // mkostemp: a name no other process can predict, created with O_CREAT | O_EXCL (never through
  // an existing file or symlink), mode 0600 until the caller's umask-respecting rename.
  std::string name =
      (dir.empty() ? std::filesystem::path(".") : dir).string() + "/" + prefix + "XXXXXX";
  const int fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd < 0)
    throw std::runtime_error("cannot create a file in " + dir.string() + ": " +
                             std::strerror(errno));
  ::fchmod(fd, 0666 & ~current_umask());
  ::close(fd);
  return name;
}

AtomicFileStream::AtomicFileStream(std::filesystem::path path) : path_(std::move(path)) {
  namespace fs = std::filesystem;
  if (path_.has_parent_path()) fs::create_directories(path_.parent_path());
  // Hidden, with an unpredictable suffix, created exclusively (create_exclusive_file): it cannot
  // collide with a user's file or another process's temporary, nor be a planted symlink.
  try {
    tmp_ = create_exclusive_file(path_.parent_path(), "." + path_.filename().string() + ".tmp.");
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("cannot write " + path_.string() + " (" + e.what() + ")");
  }
  file_.open(tmp_, std::ios::binary | std::ios::out);
  if (!file_)
    throw std::runtime_error("cannot write " + path_.string() + " (temporary " + tmp_.string() +
                             ": " + std::strerror(errno) + ")");
}

AtomicFileStream::~AtomicFileStream() {
  if (committed_) return;
  file_.close();
  std::error_code ignore;
  std::filesystem::remove(tmp_, ignore);
}

void AtomicFileStream::commit() {
  errno = 0;
  file_.flush();
  const int flush_error = errno;
  file_.close();
  if (!file_) {
    int e = errno ? errno : flush_error;
    // A stream does not keep errno; a full file system is the usual cause.
    struct statvfs info {};
    if (e == 0 &&
        ::statvfs(tmp_.parent_path().empty() ? "." : tmp_.parent_path().c_str(), &info) == 0 &&
        info.f_bavail == 0)
      e = ENOSPC;
    throw std::runtime_error("error writing " + path_.string() + " (temporary " + tmp_.string() +
                             "): " + (e ? std::strerror(e) : "the stream failed"));
  }
  std::filesystem::rename(tmp_, path_);
  committed_ = true;
}

void write_file_atomic(const std::filesystem::path& path, const std::string& content) {
  namespace fs = std::filesystem;
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  fs::path tmp;
  try {
    tmp = create_exclusive_file(path.parent_path(), "." + path.filename().string() + ".tmp.");
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("cannot write " + path.string() + " (" + e.what() + ")");
  }
  // Written with write(2), so a failure carries the system's reason (errno), e.g. ENOSPC.
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CLOEXEC | O_NOFOLLOW);
  int error = fd < 0 ? errno : 0;
  for (std::size_t done = 0; fd >= 0 && error == 0 && done < content.size();) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno != EINTR) error = errno;
    if (n > 0) done += static_cast<std::size_t>(n);
  }
  if (fd >= 0 && ::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw std::runtime_error("error writing " + path.string() + ": " + std::strerror(error));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw std::runtime_error("cannot write " + path.string() + ": " + ec.message());
  }
}

namespace {
// Folders require_output_dir created in this process (outermost first), so a run refused as bad
// input afterwards leaves nothing behind (remove_created_output_dirs).
std::vector<std::filesystem::path> g_created_dirs;
}  // namespace

void require_output_dir(const std::filesystem::path& dir, const std::string& flag) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // The folders that do not exist yet, outermost first: removed again if the probe fails.
  std::vector<fs::path> missing;
  for (fs::path p = dir; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing.insert(missing.begin(), p);
    if (p == p.parent_path()) break;
  }
  for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
    // A file where a folder is needed.
    if (fs::exists(p, ec) && !fs::is_directory(p, ec))
      throw BadInput(flag + " " + dir.string() + ": cannot create or write there (" + p.string() +
                     " is a file, not a folder)");
    if (p == p.parent_path()) break;
  }
  ec.clear();
  fs::create_directories(dir, ec);
  auto undo = [&] {
    std::error_code ignore;
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) fs::remove(*it, ignore);
  };
  if (ec) {
    undo();
    throw BadInput(flag + " " + dir.string() + ": cannot create the folder (" + ec.message() + ")");
  }
  // The probe is created exclusively under an unpredictable name: a symlink planted in the
  // folder is never opened, so its target is never touched.
  bool ok = false;
  std::string reason = "cannot create a file";
  try {
    fs::remove(create_exclusive_file(dir, ".stiffbench_write_test."), ec);
    ok = true;
  } catch (const std::runtime_error& e) {
    reason = e.what();
  }
  if (!ok) {
    undo();
    throw BadInput(flag + " " + dir.string() + ": cannot write there (" + reason + ")");
  }
  for (const auto& p : missing) g_created_dirs.push_back(p);
}

void require_output_file(const std::filesystem::path& file, const std::string& flag) {
  namespace fs = std::filesystem;
  std::error_code ec;
  require_input(!file.empty() && file.filename() != "." && file.filename() != "..",
                flag + " '" + file.string() + "': a folder, not a file name");
  if (fs::is_directory(file, ec))
    throw BadInput(flag + " " + file.string() + ": is a folder; give a file name");
  const fs::path parent = file.has_parent_path() ? file.parent_path() : fs::path(".");
  try {
    require_output_dir(parent, flag);
  } catch (const BadInput& e) {
    // Name the file the user gave, with the folder's reason.
    std::string msg = e.what();
    const std::string head = flag + " " + parent.string() + ": ";
    if (msg.rfind(head, 0) == 0) msg = msg.substr(head.size());
    throw BadInput(flag + " " + file.string() + ": " + msg);
  }
}

void remove_created_output_dirs() {
  std::error_code ec;
  // Innermost first; fs::remove leaves a folder that is not empty.
  for (auto it = g_created_dirs.rbegin(); it != g_created_dirs.rend(); ++it)
    std::filesystem::remove(*it, ec);
  g_created_dirs.clear();
}

namespace {
bool g_force_output = false;

std::string shown(const nlohmann::json& v) { return v.dump(); }

// The differences of two JSON values below `path` (none when equal), in key order, each as
// "KEY = A there, B here" ("(absent)" for a missing key).
void collect_differences(const nlohmann::json& a, const nlohmann::json& b, const std::string& path,
                         std::vector<std::string>& out) {
  if (a == b) return;
  const std::string key = path.empty() ? "spec" : path;
  if (a.is_object() && b.is_object()) {
    std::vector<std::string> keys;  // sorted union (nlohmann objects iterate in key order)
    for (const auto& [k, v] : a.items()) keys.push_back(k);
    for (const auto& [k, v] : b.items())
      if (!a.contains(k)) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    for (const auto& k : keys) {
      const std::string sub = path.empty() ? k : path + "." + k;
      if (!a.contains(k))
        out.push_back(sub + " = (absent) there, " + shown(b[k]) + " here");
      else if (!b.contains(k))
        out.push_back(sub + " = " + shown(a[k]) + " there, (absent) here");
      else
        collect_differences(a[k], b[k], sub, out);
    }
    return;
  }
  out.push_back(key + " = " + shown(a) + " there, " + shown(b) + " here");
}

// The method files a spec record names, at any depth (a profile's record holds its problems'
// specs): method name -> (file, content hash).
using MethodFiles = std::map<std::string, std::pair<std::string, std::string>>;
void gather_method_files(const nlohmann::json& j, MethodFiles& out) {
  if (j.is_array())
    for (const auto& x : j) gather_method_files(x, out);
  if (!j.is_object()) return;
  for (const auto& [k, v] : j.items()) {
    if (k == "method_files" && v.is_object()) {
      for (const auto& [name, rec] : v.items())
        if (rec.is_object())
          out[name] = {rec.value("file", std::string()), rec.value("fnv1a64", std::string())};
    } else {
      gather_method_files(v, out);
    }
  }
}

// `j` with every "method_files" object reduced to {name: content hash} (keep = true) or removed.
void reduce_method_files(nlohmann::json& j, bool keep) {
  if (j.is_array())
    for (auto& x : j) reduce_method_files(x, keep);
  if (!j.is_object()) return;
  if (j.contains("method_files") && j["method_files"].is_object()) {
    if (!keep) {
      j.erase("method_files");
    } else {
      nlohmann::json h = nlohmann::json::object();
      for (const auto& [name, rec] : j["method_files"].items())
        h[name] = rec.is_object() ? rec.value("fnv1a64", std::string()) : std::string();
      j["method_files"] = h;
    }
  }
  for (auto& item : j.items())
    if (item.key() != "method_files") reduce_method_files(item.value(), keep);
}
}  // namespace

nlohmann::json spec_identity(const nlohmann::json& spec) {
  nlohmann::json id = spec;
  reduce_method_files(id, true);
  return id;
}

std::vector<std::string> spec_differences(const nlohmann::json& recorded,
                                          const nlohmann::json& requested) {
  // Through text, as the record was written: NaN becomes null, integers and reals compare alike.
  nlohmann::json a = nlohmann::json::parse(recorded.dump());
  nlohmann::json b = nlohmann::json::parse(requested.dump());
  std::vector<std::string> out;
  // The method files first, by name and file: "method file F (method 'm') changed".
  MethodFiles fa, fb;
  gather_method_files(a, fa);
  gather_method_files(b, fb);
  for (const auto& [name, here] : fb) {
    const std::string what = "method file " + here.first + " (method '" + name + "')";
    if (const auto it = fa.find(name); it == fa.end())
      out.push_back(what + ": not read from a method file there");
    else if (it->second.second != here.second)
      out.push_back(what + " changed since that run: content hash " + it->second.second +
                    " there, " + here.second + " here");
  }
  for (const auto& [name, there] : fa)
    if (!fb.count(name))
      out.push_back("method '" + name + "': read from the method file " + there.first +
                    " there, not from a method file here");
  reduce_method_files(a, false);
  reduce_method_files(b, false);
  collect_differences(a, b, "", out);
  return out;
}

void set_force_output(bool force) { g_force_output = force; }
bool force_output() { return g_force_output; }

std::string spec_difference(const nlohmann::json& recorded, const nlohmann::json& requested) {
  const std::vector<std::string> d = spec_differences(recorded, requested);
  constexpr std::size_t kShown = 4;
  std::string text;
  for (std::size_t i = 0; i < d.size() && i < kShown; ++i) text += (i ? "; " : "") + d[i];
  if (d.size() > kShown) text += "; and " + std::to_string(d.size() - kShown) + " more";
  return text;
}

bool check_existing_results(const std::filesystem::path& dir, const std::string& record,
                            const std::vector<std::string>& results, const nlohmann::json& spec,
                            bool force, std::ostream* note, const std::string& flag) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path rec = dir / record;
  const std::string advice = "; choose another " + flag + " or pass --force to replace them";
  std::string problem;  // why the results cannot be replaced silently; empty: same spec
  fs::path culprit = rec;
  if (fs::exists(rec, ec)) {
    std::ifstream in(rec, std::ios::binary);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(in);
    } catch (const std::exception&) {
      j = nlohmann::json();
      problem = "holds results we cannot identify: " + rec.string() + " is not valid JSON";
    }
    if (problem.empty() && (!j.is_object() || !j.contains("spec")))
      problem = "holds results we cannot identify: " + rec.string() + " records no \"spec\"";
    if (problem.empty()) {
      const std::string d = spec_difference(j["spec"], spec);
      if (!d.empty())
        problem = "holds results of a different spec (" + rec.string() + ": " + d + ")";
    }
  } else {
    bool any = false;
    for (const auto& r : results)
      if (fs::exists(dir / r, ec)) {
        culprit = dir / r;
        any = true;
        break;
      }
    if (!any) return false;
    problem = "holds results we cannot identify: " + culprit.string() + " exists but " +
              rec.string() + " (the record of their spec) does not";
  }
  if (problem.empty()) {
    if (note)
      *note << "note: " << flag << " " << dir.string() << " holds results of the same spec ("
            << rec.string() << "): recomputing and replacing them\n";
    return true;
  }
  if (!force) throw BadInput(flag + " " + dir.string() + " " + problem + advice);
  if (note)
    *note << "note: " << flag << " " << dir.string() << " " << problem
          << ": replacing them (--force)\n";
  return true;
}

bool check_study_output(const std::filesystem::path& dir, const std::string& name,
                        const nlohmann::json& spec, bool force, std::ostream* note,
                        const std::vector<std::string>& extra) {
  std::vector<std::string> results = {name + ".csv", name + ".md", name + ".png", name + ".svg"};
  results.insert(results.end(), extra.begin(), extra.end());
  return check_existing_results(dir, name + ".json", results, spec, force, note);
}

std::string failed_runs_markdown(const std::vector<RunNote>& runs) {
  std::ostringstream os;
  for (const RunNote& r : runs) {
    if (r.stats->status == Status::ok) continue;
    if (os.tellp() == 0) os << "\nRuns that did not end with status ok:\n\n";
    os << "- " << r.what << ": " << to_string(r.stats->status);
    if (!r.stats->message.empty()) os << ": " << r.stats->message;
    os << "\n";
  }
  return os.str();
}

void set_command_line(int argc, char** argv) {
  g_command_line_set = true;
  g_command_line.clear();
  for (int i = 0; i < argc; ++i) {
    if (i) g_command_line += ' ';
    g_command_line += argv[i];
  }
}

void clear_command_line() {
  g_command_line_set = false;
  g_command_line.clear();
}

std::string cpu_model() {
  // Read once: the processor does not change while the program runs.
  static const std::string model = [] {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
      if (line.rfind("model name", 0) != 0) continue;
      const auto colon = line.find(':');
      if (colon == std::string::npos) continue;
      const auto start = line.find_first_not_of(" \t", colon + 1);
      return start == std::string::npos ? std::string("unknown") : line.substr(start);
    }
    return std::string("unknown");
  }();
  return model;
}

nlohmann::json run_metadata(const std::string& experiment, const nlohmann::json& spec,
                            const std::optional<ModelRecord>& model) {
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &tm);
  nlohmann::json j;
  j["experiment"] = experiment;
  j["spec"] = spec;
  j["stiffbench_version"] = STIFFBENCH_VERSION;
  j["git_revision"] = git_revision();
  j["compiler"] = std::string("g++ ") + __VERSION__;
  j["build_type"] = STIFFBENCH_BUILD_TYPE;
  j["flags"] = STIFFBENCH_CXX_FLAGS;
  j["eigen_version"] = std::to_string(EIGEN_WORLD_VERSION) + "." +
                       std::to_string(EIGEN_MAJOR_VERSION) + "." +
                       std::to_string(EIGEN_MINOR_VERSION);
  j["sundials_version"] = sundials_library_version();
  j["gsl_version"] = gsl_library_version();
  j["cpu_model"] = cpu_model();
  j["threads"] = omp_get_max_threads();
  // The seed of the study's random numbers (shuffled run order, bootstrap, perturbations); null
  // for a study that draws none.
  j["seed"] = spec.is_object() && spec.contains("seed") ? spec["seed"] : nlohmann::json(nullptr);
  j["date"] = date;
  // A program calling the studies directly has no command line: say so rather than record "".
  if (g_command_line_set) {
    j["caller"] = "cli";
    j["command_line"] = g_command_line;
  } else {
    j["caller"] = "library";
    j["command_line"] = nullptr;
  }
  if (model)
    j["model"] = {{"name", model->name},
                  {"description", model->description},
                  {"source", model->source},
                  {"built_in", model->built_in}};
  return j;
}

FolderClaim::FolderClaim(const std::filesystem::path& dir, std::ostream* note,
                         const std::string& flag)
    : lock_(dir / ".stiffbench.lock") {
  namespace fs = std::filesystem;
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &tm);
  const std::string text = "pid " + std::to_string(static_cast<long>(::getpid())) + "\nstarted " +
                           date + "\ncommand " +
                           (g_command_line_set ? printable(g_command_line) : "(library)") + "\n";
  for (int attempt = 0; attempt < 2; ++attempt) {
    const int fd =
        ::open(lock_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd >= 0) {
      const ssize_t n = ::write(fd, text.data(), text.size());
      ::close(fd);
      if (n == static_cast<ssize_t>(text.size())) return;
      std::error_code ignore;
      fs::remove(lock_, ignore);
      throw std::runtime_error("cannot write " + lock_.string());
    }
    if (errno != EEXIST)
      throw BadInput(flag + " " + dir.string() + ": cannot claim the folder (" + lock_.string() +
                     ": " + std::strerror(errno) + ")");
    // Held: by a live process (refused), or left by one that is gone (taken over).
    std::ifstream in(lock_, std::ios::binary);
    std::string held{std::istreambuf_iterator<char>(in), {}};
    long pid = 0;
    if (held.rfind("pid ", 0) == 0) pid = std::strtol(held.c_str() + 4, nullptr, 10);
    if (pid == static_cast<long>(::getpid())) {  // this process already holds it (a command
      lock_.clear();                             // running a study in its own folder): nested
      return;
    }
    const bool alive = pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM);
    std::string who;  // "pid N; started T; command C"
    std::istringstream lines(held);
    for (std::string line; std::getline(lines, line);) who += (who.empty() ? "" : "; ") + line;
    if (alive || attempt > 0)
      throw BadInput(flag + " " + dir.string() + " is being written by another run (" +
                     printable(who.substr(0, 300)) + " in " + lock_.string() +
                     "); wait for it or choose another " + flag);
    if (note)
      *note << "note: " << lock_.string() << " was left by a run that is gone (" << printable(who)
            << "); taking the folder over\n";
    std::error_code ignore;
    fs::remove(lock_, ignore);
  }
}

FolderClaim::~FolderClaim() {
  if (lock_.empty()) return;
  std::error_code ignore;
  std::filesystem::remove(lock_, ignore);
}

}  // namespace stiffbench
