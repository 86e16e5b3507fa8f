#include "experiments/output.hpp"

#include "experiments/catalog.hpp"

#include <omp.h>

#include <Eigen/Core>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>

#include "core/types.hpp"
#include "experiments/build_info.hpp"

namespace stiffbench {

namespace {
std::string g_command_line;
bool g_command_line_set = false;

std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"') out += '"';
    out += ch;
  }
  out += '"';
  return out;
}
}  // namespace

std::string Table::to_csv() const {
  std::ostringstream os;
  for (std::size_t i = 0; i < columns.size(); ++i) os << (i ? "," : "") << csv_escape(columns[i]);
  os << "\n";
  for (const auto& r : rows) {
    for (std::size_t i = 0; i < r.size(); ++i) os << (i ? "," : "") << csv_escape(r[i]);
    os << "\n";
  }
  return os.str();
}

std::string Table::to_markdown() const {
  std::ostringstream os;
  os << "|";
  for (const auto& c : columns) os << " " << c << " |";
  os << "\n|";
  for (std::size_t i = 0; i < columns.size(); ++i) os << "---|";
  os << "\n";
  for (const auto& r : rows) {
    os << "|";
    for (const auto& v : r) os << " " << (v.empty() ? " " : v) << " |";
    os << "\n";
  }
  return os.str();
}

void write_file_atomic(const std::filesystem::path& path, const std::string& content) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  const auto tmp = std::filesystem::path(path.string() + ".tmp");
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
    f << content;
    f.flush();
    if (!f) throw std::runtime_error("error writing " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
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
  const auto probe = dir / ".stiffbench_write_test";
  bool ok = false;
  int error = 0;
  {
    errno = 0;
    std::ofstream f(probe, std::ios::binary | std::ios::trunc);
    ok = f.good();
    error = errno;
  }
  fs::remove(probe, ec);
  if (!ok) {
    const std::string reason = error ? std::strerror(error) : "cannot create a file";
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

nlohmann::json run_metadata(const std::string& experiment, const nlohmann::json& spec) {
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
  j["threads"] = omp_get_max_threads();
  j["date"] = date;
  // A program calling the studies directly has no command line: say so rather than record "".
  if (g_command_line_set) {
    j["caller"] = "cli";
    j["command_line"] = g_command_line;
  } else {
    j["caller"] = "library";
    j["command_line"] = nullptr;
  }
  // What the model is, also for one registered from outside the library (register_model).
  if (spec.is_object() && spec.contains("model") && spec["model"].is_string()) {
    if (const auto* e = model_registry().find(spec["model"].get<std::string>())) {
      j["model"] = {{"name", e->info.name},
                    {"description", e->info.description},
                    {"source", e->info.source},
                    {"built_in", e->built_in}};
    }
  }
  return j;
}

}  // namespace stiffbench
