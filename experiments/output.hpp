// File output owned by the experiments layer: tables as CSV and Markdown, JSON metadata, and
// atomic writes (temporary name, then rename) so an interrupted run never leaves a truncated
// table.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace stiffbench {

struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  std::string to_csv() const;
  std::string to_markdown() const;
};

// Full precision (round-trips through text): for values in CSV files.
std::string format_full(double x);
// Short scientific form for Markdown tables and progress lines.
std::string format_short(double x, int digits = 3);
// Fixed-point form with `digits` decimals (observed orders).
std::string format_fixed(double x, int digits = 3);

void write_file_atomic(const std::filesystem::path& path, const std::string& content);

// Creates DIR and checks that a file can be written there, before an experiment runs; BadInput
// naming `flag`, the directory and the reason otherwise (and nothing is left behind).
void require_output_dir(const std::filesystem::path& dir, const std::string& flag = "--out");
// The same for an output file: its folder can be created and written, and FILE is not a folder.
void require_output_file(const std::filesystem::path& file, const std::string& flag = "--out");
// Removes the folders require_output_dir created in this process that are still empty: called
// when a command ends in bad input, so a refused run leaves no trace.
void remove_created_output_dirs();

// Metadata common to every experiment: spec, versions, compiler, flags, git revision, thread
// count, date, command line.
nlohmann::json run_metadata(const std::string& experiment, const nlohmann::json& spec);

// The command line recorded in run metadata: set by cli_main() for the duration of its run
// (cleared again when it returns, so later library calls in the same process record none).
void set_command_line(int argc, char** argv);
void clear_command_line();

}  // namespace stiffbench
