// The energy command on the real binary: it writes its tables, and refuses a model without an
// energy invariant with exit 2 and one message naming it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "tests/cli_support.hpp"

namespace stiffbench {
namespace {

using stiffbench::testing_support::CliOutcome;
using stiffbench::testing_support::run_cli;

TEST(EnergyCli, WritesTablesAndRejectsModelsWithoutEnergy) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("stiffbench_energy_cli_" + std::to_string(::getpid()));
  const CliOutcome ok = run_cli(
      "energy --model kepler --param e=0.5 --integrators rk4,velocity_verlet --h 0.05 "
      "--t-end 31.4 --samples 20 --out " +
      dir.string());
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.out.find("velocity_verlet"), std::string::npos) << ok.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "energy.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "energy_summary.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "energy.json"));
  std::filesystem::remove_all(dir);

  const CliOutcome bad =
      run_cli("energy --model robertson --integrators rk4 --h 0.1 --t-end 1 --out " + dir.string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("robertson"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace stiffbench
