// `stiffbench run SPEC.toml` and `stiffbench merge` (experiments/commands/run.hpp).
#include <cstdlib>
#include <iostream>
#include <memory>

#include "cli/cli.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/commands/run.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

void add_run_commands(CLI::App& app) {
  struct State {
    RunOptions opt;
    std::string shard;
    std::string merge_out = "results";
    std::vector<std::string> merge_dirs;
  };
  auto st = std::make_shared<State>();
  auto* run = app.add_subcommand("run", command_entry("run").summary);
  run->add_option("spec", st->opt.spec_file, "spec file (suites/*.toml)")->required();
  run->add_option("--set", st->opt.sets,
                  "override a spec key: KEY=VALUE in TOML syntax, e.g. t_end=2, "
                  "params.n=[8,16], reference=rk4 (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  run->add_option("--out", st->opt.out_dir, "output directory")->capture_default_str();
  run->add_flag("--resume", st->opt.resume,
                "keep the complete units already in OUT/<kind>.csv and run the others (a "
                "folder holding units of this spec is refused without --resume or --force; "
                "--force starts over)");
  run->add_option("--shard", st->shard,
                  "I/N: run only the units whose index mod N is I (join with `stiffbench merge`)");
  run->add_flag("--check", st->opt.check_only,
                "validate the spec and print the sweep points; run nothing");
  run->add_option("--slurm", st->opt.slurm_tasks,
                  "N: write OUT/slurm/{array.sbatch,merge.sbatch,submit.sh} for a Slurm job "
                  "array of N shards plus a dependent merge job; submits nothing");
  run->add_option("--partition", st->opt.partition, "Slurm partition (with --slurm)");
  run->add_option("--time", st->opt.time_limit, "Slurm time limit, e.g. 01:00:00 (with --slurm)");
  run->callback([st]() {
    if (!st->shard.empty()) parse_shard(st->shard, st->opt.shard_index, st->opt.shard_count);
    st->opt.force = force_output();
    const int code = run_spec(st->opt, std::cout, std::cerr);
    if (code != 0) {
      std::cout.flush();
      std::exit(code);
    }
  });

  auto* merge = app.add_subcommand("merge", command_entry("merge").summary);
  merge->add_option("--out", st->merge_out, "output directory")->required();
  merge->add_option("dirs", st->merge_dirs, "shard folders")->required();
  merge->callback([st]() {
    const int code =
        merge_shards(st->merge_out, st->merge_dirs, std::cout, std::cerr, force_output());
    if (code != 0) {
      std::cout.flush();
      std::exit(code);
    }
  });
}

}  // namespace stiffbench
