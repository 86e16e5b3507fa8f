// `stiffbench describe` on a mass-spring model (the real binary) lists every registered
// parameter with its type and default.
#include <gtest/gtest.h>

#include <string>

#include "core/params.hpp"
#include "experiments/framework/catalog.hpp"
#include "tests/cli_support.hpp"

namespace stiffbench {
namespace {

TEST(MassSpringCli, DescribeClothListsEveryParameterWithItsDefault) {
  const testing_support::CliOutcome o = testing_support::run_cli("describe cloth");
  EXPECT_EQ(o.code, 0) << o.err;
  for (const ParamSpec& p : model_registry().at("cloth").params)
    EXPECT_NE(o.out.find("| " + p.key + " | " + to_string(p.type) + " | " + p.default_value + " |"),
              std::string::npos)
        << p.key << "\n"
        << o.out;
}

}  // namespace
}  // namespace stiffbench
