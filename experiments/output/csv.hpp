// Reading the CSV files the experiments write, for `plot` (the values of one column) and for
// `run --resume` / `merge` (the rows of a run, grouped by unit). Pure text in, values out: no
// files and no other part of the library, so the fuzz targets (fuzz/) link only this.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace stiffbench {

// The fields of one CSV line: commas separate, double quotes quote ("" is a quote inside).
std::vector<std::string> parse_csv_line(const std::string& line);

// The distinct values of `column` in CSV text, in order of first appearance (empty when the
// column is missing).
std::vector<std::string> csv_column_values_in(const std::string& text, const std::string& column);

// The rows of one unit of a run CSV (experiments/commands/run.hpp).
struct UnitRows {
  std::vector<std::string> lines;  // complete lines with '\n'
  bool ok = true;                  // every row's unit_status is ok
};

// A run CSV: the header line and the complete units (exactly `unit_rows` distinct rows, all
// giving the same `unit_rows`); a torn last line (no newline), lines with the wrong number of
// fields, incomplete units and units with a duplicated row are dropped.
struct CsvContent {
  std::string header;
  std::map<long, UnitRows> units;
  long dropped_rows = 0;
};
CsvContent parse_run_csv(const std::string& text);

}  // namespace stiffbench
