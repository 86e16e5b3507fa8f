// Params and the registries: unknown or unused keys and values outside a parameter's declared
// range are errors naming the key.
#include <gtest/gtest.h>

#include "experiments/framework/catalog.hpp"
#include "experiments/framework/resolve.hpp"

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

TEST(Bounds, ContainsTheirEdgesOnlyWhenClosed) {
  const double tiny = 1e-300;
  EXPECT_FALSE(Bounds::positive().contains(0));
  EXPECT_TRUE(Bounds::positive().contains(tiny));
  EXPECT_TRUE(Bounds::non_negative().contains(0));
  EXPECT_FALSE(Bounds::non_negative().contains(-tiny));
  EXPECT_TRUE(Bounds::at_least(1).contains(1));
  EXPECT_FALSE(Bounds::at_least(1).contains(0.999));
  EXPECT_FALSE(Bounds::above(1).contains(1));
  EXPECT_TRUE(Bounds::above(1).contains(1.0000001));
  EXPECT_TRUE(Bounds::in(3, 4096).contains(3));
  EXPECT_TRUE(Bounds::in(3, 4096).contains(4096));
  EXPECT_FALSE(Bounds::in(3, 4096).contains(4097));
  EXPECT_FALSE(Bounds::in(3, 4096).contains(2));
  EXPECT_TRUE(Bounds::in_closed_open(0, 1).contains(0));
  EXPECT_FALSE(Bounds::in_closed_open(0, 1).contains(1));
  EXPECT_FALSE(Bounds::in_open_closed(0, 1).contains(0));
  EXPECT_TRUE(Bounds::in_open_closed(0, 1).contains(1));
  EXPECT_TRUE(Bounds::any().contains(-1e308));
  EXPECT_TRUE(Bounds::any().declared());
  EXPECT_FALSE(Bounds().declared());
  EXPECT_TRUE(Bounds().contains(-1));  // not declared: only finiteness is checked
}

TEST(Bounds, PrintAsTheMessagesAndDescribeShowThem) {
  EXPECT_EQ(Bounds::positive().to_string(), "> 0");
  EXPECT_EQ(Bounds::non_negative().to_string(), ">= 0");
  EXPECT_EQ(Bounds::at_least(2).to_string(), ">= 2");
  EXPECT_EQ(Bounds::above(1).to_string(), "> 1");
  EXPECT_EQ(Bounds::in(1, 1000000).to_string(), "in [1, 1000000]");
  EXPECT_EQ(Bounds::in_closed_open(0, 1).to_string(), "in [0, 1)");
  EXPECT_EQ(Bounds::in_open_closed(0, 0.5).to_string(), "in (0, 0.5]");
  EXPECT_EQ(Bounds::any().to_string(), "any finite value");
  EXPECT_EQ(Bounds().to_string(), "not declared");
}

// The message of resolve_params for `value` of `spec` ("" when accepted).
std::string refusal(const ParamSpec& spec, const std::string& value) {
  try {
    resolve_params({spec}, Params{{spec.key, value}}, nullptr, "model 'm'");
    return "";
  } catch (const BadInput& e) {
    return e.what();
  }
}

TEST(Params, ValuesOutsideTheBoundsAreRefusedNamingKeyValueRangeAndOwner) {
  const ParamSpec k{"k", ParamType::real, "1", "stiffness", Bounds::positive()};
  EXPECT_EQ(refusal(k, "-1"), "parameter 'k' = -1 is out of range: must be > 0 (model 'm')");
  EXPECT_EQ(refusal(k, "0"), "parameter 'k' = 0 is out of range: must be > 0 (model 'm')");
  EXPECT_EQ(refusal(k, "1e-300"), "");
  // The value as the user typed it.
  const ParamSpec e{"e", ParamType::real, "0", "eccentricity", Bounds::in_closed_open(0, 1)};
  EXPECT_EQ(refusal(e, "0"), "");
  EXPECT_EQ(refusal(e, "0.999"), "");
  EXPECT_EQ(refusal(e, "1.0"),
            "parameter 'e' = 1.0 is out of range: must be in [0, 1) (model 'm')");
  // Non-finite values keep their own message.
  EXPECT_NE(refusal(k, "inf").find("'inf' is not finite"), std::string::npos);
  // An undeclared range checks only finiteness.
  EXPECT_EQ(refusal({"x", ParamType::real, "1", "free"}, "-1"), "");
}

TEST(Params, IntegerBoundsAreChecked) {
  const ParamSpec n{"n", ParamType::integer, "32", "grid points", Bounds::in(3, 4096)};
  EXPECT_EQ(refusal(n, "3"), "");
  EXPECT_EQ(refusal(n, "4096"), "");
  EXPECT_EQ(refusal(n, "2"), "parameter 'n' = 2 is out of range: must be in [3, 4096] (model 'm')");
  EXPECT_EQ(refusal(n, "4097"),
            "parameter 'n' = 4097 is out of range: must be in [3, 4096] (model 'm')");
  const ParamSpec iters{"newton_max_iter", ParamType::integer, "10", "", Bounds::at_least(1)};
  EXPECT_EQ(refusal(iters, "-9223372036854775808"),
            "parameter 'newton_max_iter' = -9223372036854775808 is out of range: must be >= 1 "
            "(model 'm')");
  // The default is checked too (a default outside its range is refused, not run).
  EXPECT_THROW(resolve_params({{"n", ParamType::integer, "2", "", Bounds::in(3, 4096)}}, {},
                              nullptr, "model 'm'"),
               BadInput);
}

// The registries refuse before the factory runs, with the registry's owner in the message.
TEST(Params, RegistriesRefuseOutOfRangeValuesBeforeBuilding) {
  try {
    model_registry().create("spring_chain", {{"k", -1}});
    FAIL();
  } catch (const BadInput& e) {
    EXPECT_STREQ(e.what(),
                 "parameter 'k' = -1 is out of range: must be > 0 (model 'spring_chain')");
  }
  try {
    integrator_registry().create("rattle", {{"newton_max_iter", 0}});
    FAIL();
  } catch (const BadInput& e) {
    EXPECT_STREQ(e.what(),
                 "parameter 'newton_max_iter' = 0 is out of range: must be in [1, 1000] "
                 "(integrator 'rattle')");
  }
}

// Regression: CVodeSetMaxOrd refuses an increase over 5 (BDF) or 12 (Adams) with CV_ILL_INPUT,
// which ended `solve --param max_order=6` with exit 1 after the model was built.
TEST(Params, CvodeMaxOrderAboveTheMethodsMaximumIsBadInput) {
  EXPECT_THROW(integrator_registry().create("cvode_bdf", {{"max_order", 6}}), BadInput);
  EXPECT_NO_THROW(integrator_registry().create("cvode_bdf", {{"max_order", 5}}));
  EXPECT_THROW(integrator_registry().create("cvode_adams", {{"max_order", 13}}), BadInput);
  EXPECT_NO_THROW(integrator_registry().create("cvode_adams", {{"max_order", 12}}));
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
