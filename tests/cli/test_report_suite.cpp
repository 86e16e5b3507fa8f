// `stiffbench report SUITE`: a user's folder of spec files, one section each, and the identity
// between a section and `stiffbench run` on its spec file (experiments/commands/report.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/build_info.hpp"
#include "tests/cli_support.hpp"

namespace {

namespace fs = std::filesystem;
using stiffbench::testing_support::fresh_dir;
using stiffbench::testing_support::run_cli;
using stiffbench::testing_support::shell_quote;
using stiffbench::testing_support::slurp;

const fs::path kSource = STIFFBENCH_SOURCE_DIR;

// A CSV without quoted fields as a header and rows of fields.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};
std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  std::string x;
  while (std::getline(ss, x, ',')) f.push_back(x);
  if (!line.empty() && line.back() == ',') f.push_back("");
  return f;
}
Csv read_csv(const fs::path& p) {
  Csv c;
  std::stringstream ss(slurp(p));
  std::string line;
  std::getline(ss, line);
  c.header = split(line);
  while (std::getline(ss, line))
    if (!line.empty()) c.rows.push_back(split(line));
  return c;
}
// The rows restricted to `columns` (by name), in order.
std::vector<std::vector<std::string>> project(const Csv& c,
                                              const std::vector<std::string>& columns) {
  std::vector<std::size_t> idx;
  for (const auto& col : columns)
    for (std::size_t i = 0; i < c.header.size(); ++i)
      if (c.header[i] == col) idx.push_back(i);
  std::vector<std::vector<std::string>> out;
  for (const auto& r : c.rows) {
    std::vector<std::string> s;
    for (auto i : idx) s.push_back(i < r.size() ? r[i] : "");
    out.push_back(s);
  }
  return out;
}
// The section's columns except the timing ones (wall_s, wall_s_*, and repeats, which depends on
// the measured times): `run` must give the same values.
void expect_same_rows(const fs::path& section_csv, const fs::path& run_csv) {
  const Csv sec = read_csv(section_csv), run = read_csv(run_csv);
  std::vector<std::string> cols;
  for (const auto& c : sec.header)
    if (c != "wall_s" && c.rfind("wall_s_", 0) != 0 && c != "repeats") cols.push_back(c);
  ASSERT_FALSE(sec.rows.empty()) << section_csv;
  EXPECT_EQ(project(sec, cols), project(run, cols)) << section_csv << " vs " << run_csv;
}

std::string value(const Csv& c, const std::string& integrator, const std::string& column) {
  const auto rows = project(c, {"integrator", column});
  for (const auto& r : rows)
    if (r[0] == integrator) return r[1];
  return "";
}

}  // namespace

// rk4's observed order tends to 4 on the oscillator and heun's to 2 (0.2 is the tolerance of the
// report's own "within 0.2" column). rk4's stability polynomial R = 1 + z + z^2/2 + z^3/6 +
// z^4/24 has |R(iy)|^2 = 1 - y^6/72 + y^8/576, so the imaginary-axis limit is 2*sqrt(2) exactly,
// and R(x) = 1 on the negative axis at the real root of x^3 + 4x^2 + 12x + 24 = 0,
// x = -2.785293563.
TEST(ReportSuite, UserFolderRunsEachSpecAsASection) {
  const fs::path dir = fresh_dir("suite", "user");
  fs::create_directories(dir / "suite");
  std::ofstream(dir / "suite" / "01_osc.toml")
      << "kind = \"convergence\"\ntitle = \"Oscillator orders\"\nnote = \"Slopes.\"\n"
         "model = \"harmonic_oscillator\"\nintegrators = [\"rk4\", \"heun\"]\n"
         "t_end = 1.0\nh = 0.1\nlevels = 3\n\n[quick]\nlevels = 2\n";
  std::ofstream(dir / "suite" / "02_regions.toml")
      << "kind = \"region\"\ntitle = \"Regions\"\nnote = \"Boundaries.\"\n"
         "integrators = [\"rk4\", \"heun\"]\nresolution = 60\n";
  const auto r = run_cli("report " + shell_quote((dir / "suite").string()) + " --out " +
                         shell_quote((dir / "out").string()));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string md = slurp(dir / "out" / "REPORT.md");
  EXPECT_NE(md.find("## Oscillator orders"), std::string::npos) << md;
  EXPECT_NE(md.find("## Regions"), std::string::npos) << md;
  EXPECT_LT(md.find("## Oscillator orders"), md.find("## Regions"));  // file-name order

  const Csv conv = read_csv(dir / "out" / "osc" / "convergence.csv");
  ASSERT_EQ(conv.rows.size(), 6u);
  const auto orders = project(conv, {"integrator", "observed_order"});
  ASSERT_EQ(orders[2][0], "rk4");
  ASSERT_EQ(orders[5][0], "heun");
  EXPECT_NEAR(std::stod(orders[2][1]), 4.0, 0.2);  // rk4, finest pair
  EXPECT_NEAR(std::stod(orders[5][1]), 2.0, 0.2);  // heun
  const Csv limits = read_csv(dir / "out" / "regions" / "region_limits.csv");
  EXPECT_NEAR(std::stod(value(limits, "rk4", "imaginary_axis_limit")), 2.0 * std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(std::stod(value(limits, "rk4", "real_axis_limit")), -2.785293563, 1e-6);

  // `run` on a section's spec gives the section's rows.
  const auto run = run_cli("run " + shell_quote((dir / "suite" / "01_osc.toml").string()) +
                           " --out " + shell_quote((dir / "run").string()));
  ASSERT_EQ(run.code, 0) << run.err;
  expect_same_rows(dir / "out" / "osc" / "convergence.csv", dir / "run" / "convergence.csv");

  // --quick applies [quick]: two levels.
  const auto quick = run_cli("report " + shell_quote((dir / "suite").string()) + " --quick --out " +
                             shell_quote((dir / "quick").string()));
  ASSERT_EQ(quick.code, 0) << quick.err;
  EXPECT_EQ(read_csv(dir / "quick" / "osc" / "convergence.csv").rows.size(), 4u);
  fs::remove_all(dir);
}

// The built-in suite's pendulum section (36 methods, reference rk4 at a 16 times finer step) as a
// one-file suite with the report's --quick settings, and `stiffbench run` on the same file with
// the same override: equal rows (wall times aside).
TEST(ReportSuite, PendulumSectionEqualsRunOnItsSpec) {
  const fs::path dir = fresh_dir("suite", "pendulum");
  const std::string spec = (kSource / "suites/report/04_pendulum.toml").string();
  const auto r = run_cli("report " + shell_quote(spec) + " --quick --out " +
                         shell_quote((dir / "report").string()));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto run = run_cli("run " + shell_quote(spec) + " --set levels=4 --out " +
                           shell_quote((dir / "run").string()));
  ASSERT_EQ(run.code, 0) << run.err;
  const Csv sec = read_csv(dir / "report" / "pendulum" / "convergence.csv");
  EXPECT_EQ(sec.rows.size(), 36u * 4u);
  expect_same_rows(dir / "report" / "pendulum" / "convergence.csv",
                   dir / "run" / "convergence.csv");
  fs::remove_all(dir);
}

// --html: DIR/report.html holds both sections (titles escaped), one inline SVG per plotted
// section (the region study draws one; the plot needs gnuplot, so the count is the number of
// SVG files written), the links to each section's files and the run metadata.
TEST(ReportSuite, HtmlPageHoldsEverySection) {
  const fs::path dir = fresh_dir("suite", "html");
  fs::create_directories(dir / "suite");
  std::ofstream(dir / "suite" / "01_osc.toml")
      << "kind = \"convergence\"\ntitle = \"Oscillator <k & m>\"\nnote = \"Slopes.\"\n"
         "model = \"harmonic_oscillator\"\nintegrators = [\"rk4\", \"heun\"]\n"
         "t_end = 1.0\nh = 0.1\nlevels = 2\n";
  std::ofstream(dir / "suite" / "02_regions.toml")
      << "kind = \"region\"\ntitle = \"Regions\"\nintegrators = [\"rk4\"]\nresolution = 40\n";
  const auto r = run_cli("report " + shell_quote((dir / "suite").string()) + " --html --out " +
                         shell_quote((dir / "out").string()));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("report.html"), std::string::npos) << r.out;
  const std::string page = slurp(dir / "out" / "report.html");
  EXPECT_NE(page.find("<h2>Oscillator &lt;k &amp; m&gt;</h2>"), std::string::npos);
  EXPECT_NE(page.find("<section class=\"report-section\" id=\"sec-regions\">\n<h2>Regions</h2>"),
            std::string::npos);
  std::size_t svgs = 0, plots = 0;
  for (const char* s : {"osc/convergence.svg", "regions/region.svg"})
    svgs += fs::exists(dir / "out" / s) ? 1 : 0;
  for (auto p = page.find("<figure class=\"plot\"><svg"); p != std::string::npos;
       p = page.find("<figure class=\"plot\"><svg", p + 1))
    ++plots;
  EXPECT_EQ(plots, svgs);
  EXPECT_NE(page.find("<a href=\"osc/convergence.csv\">convergence.csv</a>"), std::string::npos);
  EXPECT_NE(page.find("<a href=\"regions/region.json\">region.json</a>"), std::string::npos);
  EXPECT_NE(page.find("<th scope=\"row\">stiffbench_version</th><td>" STIFFBENCH_VERSION "</td>"),
            std::string::npos);
  EXPECT_NE(page.find("<th scope=\"row\">suite</th><td>full, user suite of 2 spec files</td>"),
            std::string::npos);
  // The note opens the section's text once (not repeated as a separate paragraph).
  EXPECT_NE(page.find("<p>Slopes. Reference: exact."), std::string::npos);
  // Without --html no page is written.
  const auto plain = run_cli("report " + shell_quote((dir / "suite").string()) + " --out " +
                             shell_quote((dir / "plain").string()));
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_FALSE(fs::exists(dir / "plain" / "report.html"));
  fs::remove_all(dir);
}

TEST(ReportSuite, BadSuitesAreRefusedBeforeAnythingRuns) {
  const fs::path dir = fresh_dir("suite", "bad");
  fs::create_directories(dir / "empty");
  auto r = run_cli("report " + shell_quote((dir / "empty").string()) + " --out " +
                   shell_quote((dir / "out").string()));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("holds no spec file"), std::string::npos) << r.err;
  fs::create_directories(dir / "sweep");
  std::ofstream(dir / "sweep" / "a.toml")
      << "kind = \"convergence\"\nmodel = \"harmonic_oscillator\"\nintegrators = [\"rk4\"]\n"
         "t_end = 1.0\nlevels = [3, 4]\n";
  r = run_cli("report " + shell_quote((dir / "sweep").string()) + " --out " +
              shell_quote((dir / "out").string()));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("a report section is one study, not a sweep"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));  // nothing written
  fs::remove_all(dir);
}

// The self-contained page loads nothing from outside: an image with a remote address in a
// section's note is written as a link to it (no <img> with that address; a relative image would
// stay an image). scripts/check-html.sh checks the same in Chromium on the CI's report.
TEST(ReportSuite, ARemoteImageInANoteIsALinkNotALoad) {
  const fs::path dir = fresh_dir("suite", "remote_image");
  fs::create_directories(dir / "suite");
  std::ofstream(dir / "suite" / "01_osc.toml")
      << "kind = \"convergence\"\nmodel = \"harmonic_oscillator\"\nintegrators = [\"rk4\"]\n"
         "t_end = 1.0\nh = 0.1\nlevels = 3\n"
         "note = \"See ![logo](https://example.org/logo.png) and ![rel](osc/convergence.png).\"\n";
  const auto r = run_cli("report " + shell_quote((dir / "suite").string()) + " --html --out " +
                         shell_quote((dir / "out").string()));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string page = stiffbench::testing_support::slurp(dir / "out" / "report.html");
  EXPECT_EQ(page.find("src=\"https://example.org"), std::string::npos);
  EXPECT_NE(page.find("<a href=\"https://example.org/logo.png\">logo (remote image)</a>"),
            std::string::npos);
  EXPECT_NE(page.find("<img src=\"osc/convergence.png\""), std::string::npos);
  fs::remove_all(dir);
}
