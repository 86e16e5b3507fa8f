#include "experiments/output/plotting.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <ostream>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/integrator.hpp"
#include "core/params.hpp"
#include "experiments/build_info.hpp"
#include "experiments/output/csv.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

namespace fs = std::filesystem;

std::vector<PlotPanel> family_panels(const std::vector<std::string>& integrators,
                                     const FamilyOf& family) {
  const std::vector<std::pair<std::string, std::string>> order = {
      {"explicit", "explicit Runge-Kutta"},
      {"symplectic", "symplectic"},
      {"implicit", "implicit"},
      {"imex", "implicit-explicit (IMEX)"},
      {"graphics", "graphics (spring solvers)"},
      {"splitting", "splitting schemes"},
      {to_string(Family::reference), "library references"},
      {"other", "other"}};
  auto family_of = [&family](const std::string& name) {
    std::string f = family ? family(name) : "";
    // An additive pair's table analysed alone ("ark324l2sa:explicit") goes with the pair.
    if (f.empty() && family && name.find(':') != std::string::npos)
      f = family(name.substr(0, name.find(':')));
    return f.empty() ? std::string("other") : f;
  };
  std::vector<std::string> families;
  for (const auto& name : integrators) families.push_back(family_of(name));
  std::vector<PlotPanel> panels;
  for (const auto& [panel_family, title] : order) {
    PlotPanel p{title, {}};
    for (std::size_t i = 0; i < integrators.size(); ++i)
      if (families[i] == panel_family) p.methods.push_back(integrators[i]);
    if (!p.methods.empty()) panels.push_back(std::move(p));
  }
  return panels;
}

// The scripts compiled into the library (generated from plots/*.gp by cmake/embed_files.cmake).
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_plot_scripts();

namespace {

// Writes the embedded scripts once per process into a private temporary folder and returns it.
fs::path embedded_plots_dir() {
  static const fs::path dir = [] {
    // mkdtemp: a new folder (mode 0700) under a name no other process can predict, so no file
    // planted in /tmp is ever written through.
    std::string folder = (fs::temp_directory_path() / "stiffbench-plots-XXXXXX").string();
    if (!::mkdtemp(folder.data()))
      throw std::runtime_error("cannot create a folder for the plot scripts in " +
                               fs::temp_directory_path().string() + ": " + std::strerror(errno));
    const fs::path d = folder;
    for (const auto& [name, text] : embedded_plot_scripts()) {
      std::ofstream out(d / std::string(name), std::ios::binary);
      out.write(text.data(), static_cast<std::streamsize>(text.size()));
    }
    return d;
  }();
  static const struct Cleanup {
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup;
  return dir;
}

}  // namespace

// In order: $STIFFBENCH_PLOTS_DIR; <exe>/../share/stiffbench/plots (the installed or built
// stiffbench binary); the source tree's plots/ of this build; else the copies compiled into the
// library (a user's program linking an installed stiffbench), written to a temporary folder.
fs::path plots_dir() {
  if (const char* env = std::getenv("STIFFBENCH_PLOTS_DIR"); env && *env) return fs::path(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = exe.parent_path().parent_path() / "share" / "stiffbench" / "plots";
    if (fs::exists(beside / "common.gp", ec)) return beside;
  }
  const fs::path source = fs::path(STIFFBENCH_SOURCE_DIR) / "plots";
  if (fs::exists(source / "common.gp", ec)) return source;
  return embedded_plots_dir();
}

namespace {

// A value as a gnuplot single-quoted string: a single quote is doubled, every other character is
// taken literally by gnuplot (no shell is involved: run_gnuplot passes arguments directly), and
// a control character becomes a space (a newline would end the -e command).
std::string gnuplot_quote(const std::string& value) {
  std::string quoted = "'";
  for (char ch : value) {
    if (ch == '\'') quoted += '\'';
    quoted += static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f ? ' ' : ch;
  }
  return quoted + "'";
}

// Runs `gnuplot ARGS...` without a shell, stdout to /dev/null, its stderr collected into
// `messages`; returns its exit status (127 when it could not be started).
int run_gnuplot(const std::vector<std::string>& args, std::string& messages) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    messages = std::string("cannot create a pipe: ") + std::strerror(errno);
    return 127;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  std::vector<char*> argv;
  std::vector<std::string> all = {"gnuplot"};
  all.insert(all.end(), args.begin(), args.end());
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = ::posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (spawned != 0) {
    ::close(fds[0]);
    messages = std::string("cannot start gnuplot: ") + std::strerror(spawned);
    return 127;
  }
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n > 0) {
      if (messages.size() < (1u << 20)) messages.append(buf, static_cast<std::size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status)
                           : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

// Why the plot file PATH (of format EXT) is not complete, or "" when it is: empty, a PNG without
// its IEND chunk, an SVG without its closing tag (a full disk or a killed gnuplot leaves these).
std::string incomplete_plot(const fs::path& path, const std::string& ext) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), {}};
  if (bytes.empty()) return "gnuplot wrote an empty file";
  if (ext == "png") {
    static const std::string iend("\x00\x00\x00\x00IEND\xae\x42\x60\x82", 12);
    if (bytes.size() < iend.size() || bytes.compare(bytes.size() - iend.size(), iend.size(), iend))
      return "the PNG has no end chunk (IEND): truncated";
  } else if (ext == "svg" && bytes.find("</svg>") == std::string::npos) {
    return "the SVG has no closing </svg>: truncated";
  }
  return "";
}

std::atomic<long> g_failed_plots{0};

std::string join_spaces(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : " ") + x;
  return s;
}

}  // namespace

std::vector<std::string> csv_column_values(const fs::path& csv, const std::string& column) {
  std::ifstream in(csv, std::ios::binary);
  if (!in) return {};
  std::stringstream text;
  text << in.rdbuf();
  return csv_column_values_in(text.str(), column);
}

bool run_plot(const std::string& script, const fs::path& out_stem, const PlotVars& vars,
              const std::vector<PlotPanel>& panels, const PlotOptions& opt, std::ostream& err) {
  static bool warned = false;
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    if (!warned) err << "warning: gnuplot not found: tables written, plots skipped\n";
    warned = true;
    return false;
  }
  const fs::path dir = plots_dir();
  PlotVars all = vars;
  all.emplace_back("plotdir", dir.string());
  all.emplace_back("npanels", std::to_string(panels.size()));
  for (std::size_t k = 0; k < panels.size(); ++k) {
    all.emplace_back("ptitle" + std::to_string(k + 1), panels[k].title);
    all.emplace_back("pmethods" + std::to_string(k + 1), join_spaces(panels[k].methods));
  }
  std::vector<std::pair<std::string, std::string>> outputs = {{"png", "png"}};
  if (opt.svg) outputs.emplace_back("svg", "svg");
  bool ok = true;
  for (const auto& [term, ext] : outputs) {
    const fs::path final_path = out_stem.string() + "." + ext;
    // gnuplot writes a temporary created exclusively beside the plot; it is renamed over the
    // plot only once it is complete, so a failed or truncated plot never has the final name.
    fs::path tmp;
    try {
      tmp = create_exclusive_file(final_path.parent_path(),
                                  "." + final_path.filename().string() + ".tmp.");
    } catch (const std::runtime_error& e) {
      err << "warning: plot " << final_path.string() << " not written: " << e.what() << "\n";
      ok = false;
      continue;
    }
    PlotVars with_out = all;
    with_out.emplace_back("outfile", tmp.string());
    with_out.emplace_back("term", term);
    std::string defs;
    for (const auto& [name, value] : with_out) defs += name + "=" + gnuplot_quote(value) + "; ";
    // gnuplot's own warnings (e.g. a method without finite points) come through a pipe and are
    // shown only when the plot fails.
    std::string messages;
    const int status = run_gnuplot({"-e", defs, (dir / script).string()}, messages);
    std::string problem = status != 0 ? "gnuplot exited with status " + std::to_string(status)
                                      : incomplete_plot(tmp, ext);
    // gnuplot does not report a failed write; a full file system is the usual cause.
    struct statvfs fs_info {};
    if (!problem.empty() && ::statvfs(tmp.parent_path().c_str(), &fs_info) == 0 &&
        static_cast<unsigned long long>(fs_info.f_bavail) * fs_info.f_frsize < (64u << 10))
      problem +=
          " (" + std::string(std::strerror(ENOSPC)) + ": " +
          std::to_string(static_cast<unsigned long long>(fs_info.f_bavail) * fs_info.f_frsize) +
          " bytes free there)";
    std::error_code ec;
    if (problem.empty()) {
      fs::rename(tmp, final_path, ec);
      if (ec) problem = "cannot rename the finished plot into place: " + ec.message();
    }
    if (!problem.empty()) {
      fs::remove(tmp, ec);
      err << "warning: plot " << final_path.string() << " not written: " << problem << "\n";
      if (!messages.empty()) err << messages << (messages.back() == '\n' ? "" : "\n");
      ok = false;
    }
  }
  if (!ok) ++g_failed_plots;
  return ok;
}

long failed_plot_count() { return g_failed_plots.load(); }

bool plot_convergence(const fs::path& csv, const std::string& title, bool local,
                      const PlotOptions& opt, std::ostream& err) {
  fs::path stem = csv;
  stem.replace_extension();
  return run_plot("convergence.gp", stem,
                  {{"csvfile", csv.string()},
                   {"ttl", title},
                   {"ycolumn", local ? "5" : "6"},
                   {"slope_offset", local ? "1" : "0"},
                   {"ylab", local ? "local error (max-norm)" : "global error at t_end (max-norm)"}},
                  family_panels(csv_column_values(csv, "integrator"), opt.family), opt, err);
}

bool plot_work_precision(const fs::path& csv, const std::string& title, const PlotOptions& opt,
                         std::ostream& err) {
  fs::path stem = csv;
  stem.replace_extension();
  // Work-precision compares methods across families (hand-written against library methods on
  // one tolerance ladder), so a study of a few methods gets one panel on common axes; larger
  // studies are split by family to stay readable.
  const std::vector<std::string> methods = csv_column_values(csv, "integrator");
  std::vector<PlotPanel> panels = family_panels(methods, opt.family);
  if (methods.size() <= 8) panels = {PlotPanel{"all methods", methods}};
  // The `flag` column, 1-based for gnuplot (0: a CSV written before it existed): rows marked
  // reference_floor are drawn hollow.
  std::string flagcol = "0";
  std::ifstream in(csv);
  std::string header;
  if (std::getline(in, header)) {
    const std::vector<std::string> cols = parse_csv_line(header);
    const auto it = std::find(cols.begin(), cols.end(), "flag");
    if (it != cols.end()) flagcol = std::to_string(it - cols.begin() + 1);
  }
  return run_plot("work_precision.gp", stem,
                  {{"csvfile", csv.string()}, {"ttl", title}, {"flagcol", flagcol}}, panels, opt,
                  err);
}

}  // namespace stiffbench
