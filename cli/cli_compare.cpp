// `stiffbench compare OLD NEW` (experiments/commands/compare.hpp).
#include <iostream>
#include <memory>
#include <string>

#include "cli/cli.hpp"
#include "experiments/commands/compare.hpp"
#include "experiments/commands/list_describe.hpp"

namespace stiffbench {

void add_compare_command(CLI::App& app) {
  struct State {
    std::string old_dir, new_dir, out_dir = "compare";
    CompareOptions opt;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand("compare", command_entry("compare").summary);
  cmd->footer(
      "Files are matched by their path relative to OLD and NEW. Run records (*.json): spec, "
      "versions (stiffbench, Eigen, SUNDIALS, GSL), git revision, compiler, flags, CPU model, "
      "thread count and seed. Rows of each CSV are matched by their key columns (model, "
      "integrator, h, setting, ...); counters and text must be equal, other numbers agree within "
      "--rtol/--atol; timing columns are reported, not compared. Wall time: faster/slower when "
      "the bootstrap 95% intervals of the medians are disjoint and each side has at least 4 "
      "runs, else not resolved. Prints the Markdown summary. Exit 0 same results, 1 a row "
      "differs or a file or row is on one side only (the changed rows are named on stderr), 2 "
      "bad input. See docs/commands/compare.md.");
  cmd->add_option("old", st->old_dir, "output folder of the first run")->required();
  cmd->add_option("new", st->new_dir, "output folder of the second run")->required();
  cmd->add_option("--rtol", st->opt.rtol,
                  "relative tolerance on real numbers: |new - old| <= rtol*max(|old|, |new|) + "
                  "atol (counters and text are compared exactly)")
      ->capture_default_str();
  cmd->add_option("--atol", st->opt.atol, "absolute tolerance on real numbers")
      ->capture_default_str();
  cmd->add_option("--out", st->out_dir,
                  "output directory of compare.{md,csv,json} (not inside OLD or NEW)")
      ->capture_default_str();
  cmd->add_flag_function(
      "--force", [](std::int64_t) { set_force_output(true); },
      "replace a comparison of other folders or tolerances in --out (default: refuse it)");
  cmd->callback([st]() {
    const CompareResult r =
        compare_study(st->old_dir, st->new_dir, st->opt, st->out_dir, &std::cerr);
    std::cout << compare_markdown(r);
    if (r.same()) return;
    std::cerr << "stiffbench: compare: " << r.changed_rows() << " row"
              << (r.changed_rows() == 1 ? "" : "s") << " differ";
    if (r.files_on_one_side()) std::cerr << ", " << r.files_on_one_side() << " file(s) on one side";
    std::cerr << " (details in " << st->out_dir << "/compare.md)\n";
    long named = 0;
    for (const auto& f : r.files)
      if (f.presence != FileComparison::Presence::both && named++ < 20)
        std::cerr << "  " << f.file << ": file only in "
                  << (f.presence == FileComparison::Presence::old_only ? "OLD" : "NEW") << "\n";
    for (const auto& row : r.rows)
      if (row.changed && named++ < 20) {
        std::cerr << "  " << row.file << ": " << row.key << ": ";
        for (std::size_t k = 0; k < row.differences.size(); ++k)
          std::cerr << (k ? "; " : "") << row.differences[k];
        std::cerr << "\n";
      }
    if (named > 20) std::cerr << "  (" << named - 20 << " more in compare.csv)\n";
    set_command_exit_code(1);
  });
}

}  // namespace stiffbench
