// Replays the fuzz targets (fuzz/targets.hpp) on their seed corpus and on every input a fuzz
// run ever found (fuzz/regressions/TARGET/) in the normal build, so a fixed crash
// stays fixed without clang. Each input must be accepted or refused with BadInput; the targets
// throw std::logic_error on a broken invariant, which fails here.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "experiments/build_info.hpp"
#include "fuzz/targets.hpp"

namespace fs = std::filesystem;

namespace {

int replay(const std::string& target, const std::function<void(std::string_view)>& one) {
  int n = 0;
  for (const char* set : {"corpus", "regressions"}) {
    const fs::path dir = fs::path(STIFFBENCH_SOURCE_DIR) / "fuzz" / set / target;
    if (!fs::exists(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir)) {
      std::ifstream in(e.path(), std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      EXPECT_NO_THROW(one(ss.str())) << e.path();
      ++n;
    }
  }
  return n;
}

TEST(FuzzRegressions, Params) { EXPECT_GT(replay("params", stiffbench::fuzz::params_one), 3); }
TEST(FuzzRegressions, SpecFile) {
  EXPECT_GT(replay("spec_file", stiffbench::fuzz::spec_file_one), 3);
}
TEST(FuzzRegressions, Csv) { EXPECT_GT(replay("csv", stiffbench::fuzz::csv_one), 3); }
TEST(FuzzRegressions, MethodFile) {
  EXPECT_GT(replay("method_file", stiffbench::fuzz::method_file_one), 3);
}

// The targets' own checks work: an invariant violation is reported, not swallowed.
TEST(FuzzRegressions, TargetsReportBrokenInvariants) {
  EXPECT_THROW(stiffbench::fuzz::fail("x"), std::logic_error);
}

}  // namespace
