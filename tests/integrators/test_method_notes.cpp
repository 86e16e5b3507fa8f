// Every built-in integrator carries its method class and literature reference, and `list` /
// `describe` print them.
#include <gtest/gtest.h>

#include <sstream>
#include <stdexcept>
#include <string>

#include "experiments/commands/list_describe.hpp"
#include "experiments/framework/catalog.hpp"
#include "integrators/method_entry.hpp"

namespace stiffbench {
namespace {

TEST(MethodNotes, EveryBuiltInIntegratorHasKindAndReference) {
  for (const auto& e : integrator_registry().entries()) {
    if (!e.built_in) continue;
    EXPECT_FALSE(e.info.description.empty()) << e.info.name << " has no description";
    EXPECT_FALSE(e.info.kind.empty()) << e.info.name << " has no kind";
    EXPECT_FALSE(e.info.reference.empty()) << e.info.name << " has no reference";
  }
}

// The methods implemented as classes build their MethodInfo with their text (method_info(),
// integrators/method_entry.hpp): an instance made by the registry carries the registered kind
// and reference.
TEST(MethodNotes, ClassMethodsCarryTheirTextInTheirMethodInfo) {
  for (const char* name :
       {"verlet", "leapfrog", "rattle", "bdf2", "semi_implicit_euler", "baraff_witkin", "xpbd",
        "projective_dynamics", "stable_fluids", "cvode_bdf", "cvode_adams", "arkode_erk",
        "arkode_dirk", "arkode_imex", "gsl_rk4", "gsl_msbdf"}) {
    SCOPED_TRACE(name);
    const auto* e = integrator_registry().find(name);
    ASSERT_NE(e, nullptr);
    const auto integ = integrator_registry().create(name, {});
    EXPECT_EQ(integ->info().kind, e->info.kind);
    EXPECT_EQ(integ->info().reference, e->info.reference);
  }
}

// A built-in registration without its text is refused, naming that method only.
TEST(MethodNotes, RegistrationWithoutTextNamesTheMethod) {
  IntegratorRegistry reg("integrator");
  MethodInfo info;
  info.name = "no_text";
  info.description = "a method without kind or reference";
  try {
    add_built_in_integrator(
        reg, {info, {}, [](const Params&) { return std::unique_ptr<Integrator>(); }});
    FAIL() << "registered without a kind";
  } catch (const std::logic_error& err) {
    EXPECT_NE(std::string(err.what()).find("integrator 'no_text'"), std::string::npos)
        << err.what();
    EXPECT_NE(std::string(err.what()).find("kind"), std::string::npos) << err.what();
  }
  EXPECT_EQ(reg.find("no_text"), nullptr);
}

// join_text()/cite() keep the text of every part.
TEST(MethodNotes, JoinedTextKeepsEveryPart) {
  constexpr Text t = join_text("A", "; ", cite("Book", "Sect. 1"));
  EXPECT_EQ(t.str(), "A; Book, Sect. 1");
}

// The coefficient-defined methods carry their kind, reference and step modes in their method
// files (methods/*.toml); tests/integrators/test_method_files_registry.cpp checks that the
// registry agrees with them.

TEST(MethodNotes, DescribePrintsReferenceAndStepModes) {
  std::ostringstream dp;
  cmd_describe("dopri5", dp);
  EXPECT_NE(dp.str().find("family: explicit (embedded RK pair)"), std::string::npos) << dp.str();
  EXPECT_NE(dp.str().find("reference: J. R. Dormand & P. J. Prince"), std::string::npos);
  EXPECT_NE(dp.str().find("step: fixed, adaptive"), std::string::npos) << dp.str();
  std::ostringstream cv;
  cmd_describe("cvode_bdf", cv);
  EXPECT_NE(cv.str().find("\nstep: adaptive\n"), std::string::npos) << cv.str();
  std::ostringstream rk;
  cmd_describe("rk4", rk);
  EXPECT_NE(rk.str().find("\nstep: fixed\n"), std::string::npos) << rk.str();
}

TEST(MethodNotes, ListShowsKindAndStepColumns) {
  std::ostringstream out;
  cmd_list("integrators", out);
  const std::string s = out.str();
  // The count column is MethodInfo::stages, f evaluations per step after start-up (describe
  // calls it "evaluations per step"): ros3p has 3 stages but 2 evaluations, velocity_verlet 1
  // (first-same-as-last), and the column says so.
  EXPECT_NE(s.find("| integrator | family | kind | order | f evals/step | step |"),
            std::string::npos)
      << s.substr(0, 300);
  EXPECT_NE(s.find("| ros3p | implicit | Rosenbrock (embedded pair) | 3 | 2 |"), std::string::npos);
  EXPECT_NE(s.find("| velocity_verlet | symplectic | splitting | 2 | 1 |"), std::string::npos);
  EXPECT_NE(s.find("| radau5 | implicit | Radau IIA collocation |"), std::string::npos);
}

}  // namespace
}  // namespace stiffbench
