#include "experiments/output.hpp"

#include "experiments/catalog.hpp"

#include <omp.h>

#include <Eigen/Core>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
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

std::string format_full(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  // Shortest representation that round-trips.
  const auto res = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, res.ptr);
}

std::string format_short(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits, x);
  return buf;
}

std::string format_fixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
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

void require_output_dir(const std::filesystem::path& dir, const std::string& flag) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const auto probe = dir / ".stiffbench_write_test";
  {
    std::ofstream f(probe, std::ios::binary | std::ios::trunc);
    require_input(!ec && f.good(), flag + " " + dir.string() + ": cannot create or write there" +
                                       (ec ? " (" + ec.message() + ")" : std::string()));
  }
  std::filesystem::remove(probe, ec);
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
