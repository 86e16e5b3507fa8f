#include "experiments/output/csv.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace stiffbench {

std::vector<std::string> parse_csv_line(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

std::vector<std::string> csv_column_values_in(const std::string& text, const std::string& column) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line)) return {};
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const auto header = parse_csv_line(line);
  const auto it = std::find(header.begin(), header.end(), column);
  if (it == header.end()) return {};
  const auto col = static_cast<std::size_t>(it - header.begin());
  std::vector<std::string> values;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto cells = parse_csv_line(line);
    if (col >= cells.size()) continue;
    if (std::find(values.begin(), values.end(), cells[col]) == values.end())
      values.push_back(cells[col]);
  }
  return values;
}

CsvContent parse_run_csv(const std::string& text) {
  CsvContent c;
  std::size_t pos = 0;
  std::vector<std::string> columns;
  std::size_t status_col = 0;
  bool have_header = false;
  std::map<long, std::pair<long, UnitRows>> partial;  // unit -> (expected rows, rows)
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) break;  // torn last line
    const std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (!have_header) {
      have_header = true;
      c.header = line + "\n";
      columns = parse_csv_line(line);
      status_col = static_cast<std::size_t>(
          std::find(columns.begin(), columns.end(), "unit_status") - columns.begin());
      continue;
    }
    const auto f = parse_csv_line(line);
    if (f.size() != columns.size() || columns.size() < 2) {
      ++c.dropped_rows;
      continue;
    }
    try {
      const long unit = std::stol(f[0]);
      const long expected = std::stol(f[1]);
      if (unit < 0 || expected < 1) throw std::invalid_argument("unit or unit_rows out of range");
      auto& [want, rows] = partial[unit];
      if (!rows.lines.empty() && want != expected) want = -1;  // rows disagree: not a unit
      if (rows.lines.empty()) want = expected;
      rows.lines.push_back(line + "\n");
      if (status_col < f.size() && f[status_col] != "ok") rows.ok = false;
    } catch (const std::exception&) {
      ++c.dropped_rows;
    }
  }
  for (auto& [unit, er] : partial) {
    // Complete: exactly unit_rows rows, all distinct (a duplicated row standing in for a
    // missing one is not a complete unit).
    std::vector<std::string> sorted = er.second.lines;
    std::sort(sorted.begin(), sorted.end());
    const bool distinct = std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
    if (distinct && static_cast<long>(er.second.lines.size()) == er.first)
      c.units[unit] = std::move(er.second);
    else
      c.dropped_rows += static_cast<long>(er.second.lines.size());
  }
  return c;
}

}  // namespace stiffbench
