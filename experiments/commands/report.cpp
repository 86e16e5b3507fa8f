// `stiffbench report [SUITE...]`: a suite of spec files, one section each, run through the study
// framework into one folder per section and DIR/REPORT.md linking every table and plot.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "experiments/build_info.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/commands/run.hpp"
#include "experiments/framework/spec_file.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/html.hpp"

namespace stiffbench {

// suites/report/*.toml, compiled in (cmake/embed_files.cmake).
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_report_suite();

namespace fs = std::filesystem;

namespace {

// "03_kepler_e05.toml" -> "kepler_e05": the section's folder.
std::string section_name(const std::string& file) {
  std::string stem = fs::path(file).stem().string();
  std::size_t i = 0;
  while (i < stem.size() && std::isdigit(static_cast<unsigned char>(stem[i]))) ++i;
  if (i > 0 && i < stem.size() && stem[i] == '_') stem = stem.substr(i + 1);
  return stem;
}

constexpr const char* kBuiltInSuite = "suites/report/";

// A section's run metadata (DIR/NAME/STEM.json) as rows for the HTML page; none when unreadable.
HtmlMetadata section_metadata(const fs::path& json_file) {
  std::ifstream in(json_file);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() ? HtmlMetadata{} : html_metadata(j);
}

// DIR/report.html (--html): the page's metadata is the report's own (report.json), its
// introduction the paragraphs of REPORT.md before the first section.
void write_report_html(const fs::path& out_dir, const nlohmann::json& report_json,
                       const std::string& intro, const std::vector<HtmlSection>& sections,
                       std::ostream& out) {
  HtmlMetadata meta;
  const nlohmann::json& spec = report_json["spec"];
  meta.emplace_back(
      "suite",
      spec.value("suite", "") +
          (spec.contains("spec_files")
               ? ", user suite of " + std::to_string(spec["spec_files"].size()) + " spec files"
               : ", built-in suite"));
  meta.emplace_back("sections", std::to_string(sections.size()));
  const HtmlMetadata all = html_metadata(report_json);
  for (const std::string key : {"stiffbench_version", "git_revision", "compiler", "build_type",
                                "flags", "eigen_version", "threads", "date", "command_line"})
    for (const auto& [k, v] : all)
      if (k == key) meta.emplace_back(k, v);
  const fs::path page = out_dir / "report.html";
  write_html_page(page, "stiffbench report", meta, sections,
                  "[REPORT.md](REPORT.md) · [report.json](report.json)\n\n" + intro);
  out << "wrote " << page.string() << "\n";
}

}  // namespace

std::vector<std::string> report_suite_files(const std::vector<std::string>& suite) {
  std::vector<std::string> files;
  if (suite.empty()) {
    for (const auto& [name, text] : embedded_report_suite())
      files.push_back(kBuiltInSuite + std::string(name));
    return files;
  }
  for (const auto& item : suite) {
    std::error_code ec;
    if (fs::is_directory(item, ec)) {
      std::vector<std::string> in_dir;
      for (const auto& e : fs::directory_iterator(item))
        if (e.is_regular_file() && e.path().extension() == ".toml")
          in_dir.push_back(e.path().string());
      std::sort(in_dir.begin(), in_dir.end());
      require_input(!in_dir.empty(), "report: folder " + item + " holds no spec file (*.toml)");
      files.insert(files.end(), in_dir.begin(), in_dir.end());
    } else {
      require_input(fs::is_regular_file(item, ec),
                    "report: " + item + " is neither a spec file nor a folder of spec files");
      files.push_back(item);
    }
  }
  return files;
}

std::vector<ReportSection> load_report_suite(const std::vector<std::string>& suite, bool quick) {
  std::vector<ReportSection> sections;
  auto built_in_spec = [](const std::string& file) {
    for (const auto& [name, text] : embedded_report_suite())
      if (kBuiltInSuite + std::string(name) == file)
        return parse_spec_text(std::string(text), file, {});
    throw std::logic_error("no built-in spec " + file);
  };
  for (const auto& file : report_suite_files(suite)) {
    ReportSection s;
    s.spec = suite.empty() ? built_in_spec(file) : load_spec_file(file, {});
    if (quick) apply_quick(s.spec);
    if (s.spec.skip) continue;
    s.name = section_name(file);
    for (const auto& other : sections)
      require_input(other.name != s.name, "report: two sections named '" + s.name + "' (" +
                                              other.spec.file + ", " + file + ")");
    if (s.spec.title.empty()) s.spec.title = s.name;
    make_spec_job(s.spec, "");  // every section is checked before the first one runs
    sections.push_back(std::move(s));
  }
  return sections;
}

nlohmann::json report_spec(const ReportOptions& opt) {
  nlohmann::json j = {{"suite", opt.quick ? "quick" : "full"}};
  if (!opt.suite.empty()) {
    nlohmann::json files = nlohmann::json::array();
    for (const auto& f : report_suite_files(opt.suite))
      files.push_back(spec_record(load_spec_file(f, {})));  // with its method files
    j["spec_files"] = files;
  }
  return j;
}

void cmd_report(const ReportOptions& opt, std::ostream& out, std::ostream& err) {
  const std::vector<ReportSection> sections = load_report_suite(opt.suite, opt.quick);
  require_output_dir(opt.out_dir);
  const FolderClaim claim(opt.out_dir, &err);  // no other run writes here until this one is done
  // Output safety: DIR/report.json records the suite; a folder holding a report of another
  // suite is refused unless --force. Plot formats (--svg) are not part of it, as for the
  // studies. Written before the suite runs, so an interrupted report is identified too.
  const nlohmann::json spec = report_spec(opt);
  check_existing_results(opt.out_dir, "report.json", {"REPORT.md", "report.html"}, spec, opt.force,
                         &err);
  const nlohmann::json report_json = run_metadata("report", spec);
  write_file_atomic(fs::path(opt.out_dir) / "report.json", report_json.dump(2) + "\n");
  std::ostringstream intro;
  intro << "stiffbench " << STIFFBENCH_VERSION << ", revision " << git_revision() << ", "
        << (opt.suite.empty() ? "" : "user suite, ") << (opt.quick ? "quick" : "full")
        << " settings. Each section links its full-precision CSV, Markdown table and JSON metadata "
           "(spec, versions, compiler, flags, date); its spec file reproduces it with `stiffbench "
           "run`.\n\n";
  intro << "Errors are max-norms against the exact solution or the named reference; 'observed "
           "order' is log(e_k/e_{k+1})/log(h_k/h_{k+1}) between consecutive step sizes. A "
           "convergence section's order is a least-squares fit over its asymptotic window "
           "(consecutive levels above the round-off floor and the reference's accuracy whose "
           "observed orders agree), shown with its standard error and h range; rows at a floor "
           "have status `floor`.\n\n";
  std::ostringstream md;
  md << "# stiffbench report\n\n" << intro.str();
  std::vector<HtmlSection> html;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const ReportSection& s = sections[i];
    err << "== [" << i + 1 << "/" << sections.size() << "] " << s.name << "\n";
    const StudyKind& kind = study_kind(s.spec.kind);
    auto job = make_spec_job(s.spec, "");
    job->run(&err);
    const fs::path dir = fs::path(opt.out_dir) / s.name;
    PlotOptions plot;
    plot.svg = opt.svg || opt.html;
    plot.family = registered_family;
    const bool plotted = job->write(dir, s.spec.title, plot, err);
    md << "## " << s.spec.title << "\n\n";
    std::vector<std::string> files = {kind.stem + ".csv"};
    files.insert(files.end(), kind.extra_files.begin(), kind.extra_files.end());
    files.push_back(kind.stem + ".md");
    files.push_back(kind.stem + ".json");
    for (std::size_t f = 0; f < files.size(); ++f)
      md << (f ? " · " : "") << "[" << files[f] << "](" << s.name << "/" << files[f] << ")";
    md << "\n\n";
    if (plotted) md << "![" << s.spec.title << "](" << s.name << "/" << kind.stem << ".png)\n\n";
    const std::string text = job->report_markdown(s.spec.note);
    md << text;
    if (!opt.html) continue;
    // The note opens the section's text (report_markdown), so it is not repeated.
    HtmlSection h{s.name, s.spec.title, "", text, {}, dir / (kind.stem + ".csv"), 300, {}, {}};
    if (plotted) h.svgs.push_back(dir / (kind.stem + ".svg"));
    for (const auto& f : files) h.links.push_back({f, s.name + "/" + f});
    h.metadata = section_metadata(dir / (kind.stem + ".json"));
    html.push_back(std::move(h));
  }
  write_file_atomic(fs::path(opt.out_dir) / "REPORT.md", md.str());
  out << "wrote " << (fs::path(opt.out_dir) / "REPORT.md").string() << "\n";
  if (opt.html) write_report_html(opt.out_dir, report_json, intro.str(), html, out);
}

}  // namespace stiffbench
