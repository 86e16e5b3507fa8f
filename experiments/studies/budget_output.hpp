// The budget study's tables, files and plot (the public ones are declared in budget.hpp).
// Private to the study.
#pragma once

#include <string>
#include <vector>

#include "experiments/output/output.hpp"
#include "experiments/studies/budget.hpp"

namespace stiffbench::budget_internal {

// The integrator parameters the grid sets (a method's own, found by key in its declaration),
// which are also columns of budget.csv.
inline constexpr const char* kIterationsKey = "iterations";
inline constexpr const char* kSubstepsKey = "substeps";

// The table of budget.md and of the summary printed after `stiffbench budget`: the columns of
// the model's error measure only.
Table budget_markdown_table(const BudgetResult& r);
// Per method: the best configuration at the frame budget, or why there is none.
std::string best_markdown(const BudgetResult& r, const std::vector<std::string>& integrators);
// One line per equal-total family: does the error fall with every step up in substeps?
std::string families_markdown(const BudgetResult& r);

}  // namespace stiffbench::budget_internal
