// The gnuplot scripts compiled into the library (cmake/embed_files.cmake), which a user program
// linking an installed stiffbench draws with when no plots/ folder is found: the embedded texts
// must equal the files in plots/ byte for byte (checked against the files themselves, read
// here independently), and a plot drawn from them alone must produce a PNG.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "experiments/build_info.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {
// Defined in the generated embedded_plots.cpp of the experiments library.
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_plot_scripts();
}  // namespace stiffbench

namespace fs = std::filesystem;
using namespace stiffbench;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST(PlotScripts, EmbeddedTextsEqualTheFilesInPlots) {
  const fs::path plots = fs::path(STIFFBENCH_SOURCE_DIR) / "plots";
  std::set<std::string> on_disk;
  for (const auto& e : fs::directory_iterator(plots))
    if (e.path().extension() == ".gp") on_disk.insert(e.path().filename().string());
  ASSERT_FALSE(on_disk.empty());

  std::set<std::string> embedded;
  for (const auto& [name, text] : embedded_plot_scripts()) {
    embedded.insert(std::string(name));
    ASSERT_TRUE(on_disk.count(std::string(name))) << name << " is embedded but not in plots/";
    EXPECT_EQ(std::string(text), read_file(plots / std::string(name))) << name;
  }
  EXPECT_EQ(embedded, on_disk);
}

// A program with no plots/ folder of its own: STIFFBENCH_PLOTS_DIR points to a folder that
// holds only what the library embeds, and the convergence plot of a two-method table is drawn.
TEST(PlotScripts, EmbeddedScriptsAloneDrawAConvergencePng) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot";
  const fs::path dir =
      fs::temp_directory_path() / ("sb-embedded-plots-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "scripts");
  for (const auto& [name, text] : embedded_plot_scripts())
    std::ofstream(dir / "scripts" / std::string(name), std::ios::binary) << text;

  // Errors of a first- and a second-order method at h = 0.1, 0.05, 0.025 (C h^p with C = 1).
  const fs::path csv = dir / "convergence.csv";
  {
    std::ofstream out(csv);
    out << "model,integrator,order,h,steps,error,observed_order,f_evals,jac_evals,lin_solves,"
           "wall_s,status\n";
    for (const auto& [method, p] : {std::pair<std::string, int>{"euler", 1}, {"heun", 2}}) {
      double h = 0.1;
      for (int k = 0; k < 3; ++k, h /= 2) {
        const double err = p == 1 ? h : h * h;
        out << "harmonic_oscillator," << method << "," << p << "," << h << "," << (10 << k) << ","
            << err << "," << (k == 0 ? "" : std::to_string(p)) << ",0,0,0,0,ok\n";
      }
    }
  }
  ASSERT_EQ(::setenv("STIFFBENCH_PLOTS_DIR", (dir / "scripts").c_str(), 1), 0);
  EXPECT_EQ(plots_dir(), dir / "scripts");
  std::ostringstream err;
  const bool ok = plot_convergence(csv, "embedded", false, PlotOptions{}, err);
  ::unsetenv("STIFFBENCH_PLOTS_DIR");
  EXPECT_TRUE(ok) << err.str();
  EXPECT_GT(fs::file_size(dir / "convergence.png"), 1000u) << err.str();
  fs::remove_all(dir);
}

// The panels take their families from the caller (output/ looks nothing up): an additive pair's
// table alone ("imexpair:explicit") goes with the pair; an unknown name, or no lookup at all,
// goes to "other".
TEST(PlotPanels, FamiliesComeFromTheCaller) {
  const FamilyOf family = [](const std::string& name) -> std::string {
    if (name == "a") return "explicit";
    if (name == "imexpair") return "imex";
    if (name == "b") return "implicit";
    return "";
  };
  const std::vector<std::string> names = {"b", "imexpair:explicit", "a", "unknown"};
  const std::vector<PlotPanel> panels = family_panels(names, family);
  ASSERT_EQ(panels.size(), 4u);
  EXPECT_EQ(panels[0].methods, std::vector<std::string>{"a"});
  EXPECT_EQ(panels[1].methods, std::vector<std::string>{"b"});
  EXPECT_EQ(panels[2].methods, std::vector<std::string>{"imexpair:explicit"});
  EXPECT_EQ(panels[3].title, "other");
  EXPECT_EQ(panels[3].methods, std::vector<std::string>{"unknown"});
  const std::vector<PlotPanel> none = family_panels(names, nullptr);
  ASSERT_EQ(none.size(), 1u);
  EXPECT_EQ(none[0].methods, names);
}
