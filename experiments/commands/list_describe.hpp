// The subcommands of `stiffbench`, callable from main() and from tests.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "experiments/commands/solve.hpp"
#include "experiments/framework/spec_file.hpp"
#include "experiments/studies/convergence.hpp"

namespace stiffbench {

void cmd_list(const std::string& what, std::ostream& out);

// The commands that are not studies (the studies come from their registry, study_kinds()). The
// summary is also the command's --help description (cli/), so each is written once here; `list
// experiments` shows the solve command first, then the studies, then the others.
struct CommandEntry {
  std::string name;
  std::string writes;   // the files it writes
  std::string summary;  // one paragraph: what it does
};
const std::vector<CommandEntry>& command_entries();
// The entry of `name` (std::logic_error for a name that is not a command: a programming error).
const CommandEntry& command_entry(const std::string& name);
void cmd_describe(const std::string& name, std::ostream& out);

struct ReportOptions {
  std::string out_dir = "results";
  bool quick = false;
  bool svg = false;
  bool html = false;  // also write DIR/report.html (experiments/output/html.hpp; implies SVG plots)
  bool force = false;  // --force: replace a report of another suite in out_dir
  // Spec files and folders of spec files (each folder's *.toml in name order), one section per
  // spec; empty: the built-in suite (suites/report/, compiled in).
  std::vector<std::string> suite;
};

// One section of a report: its spec file (title, note; [quick] applied for --quick) and its
// folder name (the file's stem without a leading "NN_").
struct ReportSection {
  std::string name;
  SpecFile spec;
};
// The spec files of a suite (see ReportOptions::suite).
std::vector<std::string> report_suite_files(const std::vector<std::string>& suite);
// Loads and checks every section (names, parameters, options) before anything runs.
std::vector<ReportSection> load_report_suite(const std::vector<std::string>& suite, bool quick);

// The spec `report` records in DIR/report.json ({"suite": "quick" | "full"}, plus the canonical
// form of each spec file of a user suite) and compares with check_existing_results before it
// runs (BadInput for a report of another suite in DIR unless force_output(); --svg and --html are
// not part of it).
nlohmann::json report_spec(const ReportOptions& opt);
void cmd_report(const ReportOptions& opt, std::ostream& out, std::ostream& err);

}  // namespace stiffbench
