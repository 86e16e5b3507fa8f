#include "core/solve_stats.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace stiffbench {

std::string to_string(Status s) {
  switch (s) {
    case Status::ok:
      return "ok";
    case Status::unstable:
      return "unstable";
    case Status::newton_failed:
      return "newton_failed";
    case Status::solver_error:
      return "solver_error";
    case Status::error:
      return "error";
    case Status::timeout:
      return "timeout";
    case Status::step_size_too_small:
      return "step_size_too_small";
    case Status::invalid_state:
      return "invalid_state";
  }
  return "?";
}

std::vector<std::string> SolveStats::counter_names() {
  return {"newton_iters",  "newton_conv_failures", "error_test_failures",
          "linear_setups", "linear_iters",         "fe_evals",
          "fi_evals"};
}

std::string SolveStats::count_text(long v) { return v < 0 ? std::string() : std::to_string(v); }

std::string SolveStats::count_shown(const std::string& text) {
  return text.empty() ? "not reported" : text;
}

std::vector<std::string> SolveStats::counter_values() const {
  return {count_text(newton_iters),
          std::to_string(newton_conv_failures),
          std::to_string(error_test_failures),
          count_text(linear_setups),
          std::to_string(linear_iters),
          std::to_string(fe_evals),
          std::to_string(fi_evals)};
}

std::vector<std::string> SolveStats::field_names() {
  return {"status",
          "steps",
          "error_test_failures",
          "f_evals",
          "fe_evals",
          "fi_evals",
          "jac_evals",
          "linear_setups",
          "lin_solves",
          "newton_iters",
          "newton_conv_failures",
          "linear_iters",
          "wall_s"};
}

std::vector<std::string> SolveStats::field_values() const {
  std::ostringstream wall;
  wall << std::setprecision(6) << wall_s;
  return {to_string(status),
          std::to_string(steps),
          std::to_string(error_test_failures),
          std::to_string(f_evals),
          std::to_string(fe_evals),
          std::to_string(fi_evals),
          std::to_string(jac_evals),
          count_text(linear_setups),
          count_text(lin_solves),
          count_text(newton_iters),
          std::to_string(newton_conv_failures),
          std::to_string(linear_iters),
          wall.str()};
}

void print_stats_table(std::ostream& os, const SolveStats& s) {
  const auto names = SolveStats::field_names();
  const auto values = s.field_values();
  // The longest name (newton_conv_failures) and two spaces.
  std::size_t w = 0;
  for (const auto& n : names) w = std::max(w, n.size() + 2);
  const auto width = static_cast<int>(w);
  for (std::size_t i = 0; i < names.size(); ++i)
    os << "  " << std::left << std::setw(width) << names[i] << std::right
       << SolveStats::count_shown(values[i]) << "\n";
  if (s.library_f_evals >= 0)
    os << "  " << std::left << std::setw(width) << "library_f_evals" << std::right
       << s.library_f_evals << "\n";
  if (!s.message.empty())
    os << "  " << std::left << std::setw(width) << "message" << s.message << "\n";
  if (!s.library_report.empty()) os << "\nlibrary statistics:\n" << s.library_report;
}

void print_stats_csv_header(std::ostream& os) {
  const auto names = SolveStats::field_names();
  for (std::size_t i = 0; i < names.size(); ++i) os << (i ? "," : "") << names[i];
  os << "\n";
}

void print_stats_csv_row(std::ostream& os, const SolveStats& s) {
  const auto values = s.field_values();
  for (std::size_t i = 0; i < values.size(); ++i) os << (i ? "," : "") << values[i];
  os << "\n";
}

}  // namespace stiffbench
