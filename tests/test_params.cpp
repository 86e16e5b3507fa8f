// Params and the registries: unknown or unused keys are errors naming the key.
#include <gtest/gtest.h>

#include "experiments/catalog.hpp"

namespace stiffbench {
namespace {

TEST(Params, ParsesAssignmentsAndRejectsMalformedOnes) {
  const Params p = Params::from_assignments({"a=1.5", "b=x=y"});
  EXPECT_EQ(p.values().at("a"), "1.5");
  EXPECT_EQ(p.values().at("b"), "x=y");
  EXPECT_THROW(Params::from_assignments({"novalue"}), BadInput);
  EXPECT_THROW(Params::from_assignments({"=3"}), BadInput);
  EXPECT_THROW(Params::from_assignments({"a="}), BadInput);
  EXPECT_THROW(Params::from_assignments({"a=1", "a=2"}), BadInput);
}

TEST(Params, TypedReadsNameTheKeyOnBadValues) {
  Params p;
  p.set("x", "2.5e-3");
  p.set("n", "12");
  p.set("flag", "yes");
  p.set("bad", "1.5.2");
  EXPECT_DOUBLE_EQ(p.real("x"), 2.5e-3);
  EXPECT_EQ(p.integer("n"), 12);
  EXPECT_TRUE(p.boolean("flag"));
  try {
    p.real("bad");
    FAIL();
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("'bad'"), std::string::npos);
  }
  EXPECT_THROW(p.integer("x"), BadInput);
  EXPECT_THROW(p.real("undeclared"), std::logic_error);
}

TEST(Params, UnknownKeyIsRejectedNamingIt) {
  try {
    make_setup("kepler", {"rk4"}, Params::from_assignments({"e=0.2", "eccentricity=0.3"}));
    FAIL();
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("'eccentricity'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("e, gm, a"), std::string::npos)
        << e.what();  // what kepler takes
  }
}

TEST(Params, ChoicesAreChecked) {
  EXPECT_THROW(model_registry().create("prothero_robinson", Params::from_assignments({"phi=tan"})),
               BadInput);
  EXPECT_NO_THROW(
      model_registry().create("prothero_robinson", Params::from_assignments({"phi=cos"})));
}

// Every registered model and integrator can be created from its defaults, and reads every
// parameter it declares (Registry::create throws std::logic_error otherwise).
TEST(Registry, EveryEntryBuildsFromDefaultsAndReadsItsParameters) {
  for (const auto& e : model_registry().entries()) {
    EXPECT_NO_THROW(model_registry().create(e.info.name, Params{})) << e.info.name;
  }
  for (const auto& e : integrator_registry().entries()) {
    auto integ = integrator_registry().create(e.info.name, Params{});
    EXPECT_EQ(integ->info().name, e.info.name);
    EXPECT_EQ(integ->info().order, e.info.order);
  }
}

TEST(Registry, UnknownNameListsKnownOnes) {
  try {
    integrator_registry().at("rk5");
    FAIL();
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("'rk5'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("rk4"), std::string::npos);
  }
}

}  // namespace
}  // namespace stiffbench
