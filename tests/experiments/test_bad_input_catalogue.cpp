// The bad-input catalogue: what a new user can get wrong, each case refused with exit code 2,
// one message naming the bad value, and no file left behind.
//
// Two parts. (1, here) Every numeric parameter of every registered model and integrator, enumerated
// from the registries' ParamSpecs (so a new method is covered without editing this file),
// declares its valid range (ParamSpec::bounds) and is given NaN, ±Inf, zero, -1 and a value just
// outside each finite end of its range through the library: non-finite values and values
// outside the range must be refused as BadInput naming the key; zero and -1 inside the range
// must either be refused the same way or give a run whose numbers are honest (status ok means a
// finite state), never another exception. (2) The command
// line, on the real binary: tests/cli/test_bad_input_cli.cpp.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/resolve.hpp"

namespace fs = std::filesystem;
using namespace stiffbench;

namespace {

// ---- (1) parameters from the registries --------------------------------------------------

// What a bad value did: refused (BadInput naming the key), ran honestly, or broke a rule.
struct ParamOutcome {
  bool refused = false;
  std::string failure;  // non-empty: the rule broken
};

bool all_finite(const Vec& y) { return y.allFinite(); }

// Creates `model` with `integrator` and the user's parameters and, when that is accepted, runs
// a few steps (or a short adaptive run).
ParamOutcome try_params(const std::string& model, const std::string& integrator, const Params& user,
                        const std::string& key) {
  ParamOutcome o;
  try {
    Setup s = make_setup(model, {integrator}, user);
    const OdeSystem& sys = *s.model;
    Integrator& integ = *s.integrators.front();
    const double t0 = sys.initial_time();
    RunResult r;
    if (integ.supports_fixed_step()) {
      double h = 1e-3;
      if (const auto sug = sys.suggested_step()) h = std::min(h, sug->h);
      FixedStepOptions fo;
      fo.h = h;
      fo.t_end = t0 + 3 * h;
      r = run_fixed_step(sys, integ, fo);
    } else {
      r = run_adaptive(sys, integ, {t0 + 1e-3, 0, {}});
    }
    if (r.stats.status == Status::ok && !all_finite(r.y))
      o.failure = "status ok with a non-finite state";
  } catch (const BadInput& e) {
    o.refused = true;
    if (std::string(e.what()).find(key) == std::string::npos)
      o.failure = std::string("BadInput not naming '") + key + "': " + e.what();
  } catch (const std::exception& e) {
    o.failure = std::string("exception other than BadInput (exit 1): ") + e.what();
  }
  return o;
}

// A model (with the parameters it needs) the integrator accepts, small and quick: methods that
// need holonomic constraints (rattle) or a grid fluid (stable_fluids) get one.
struct TestModel {
  std::string name;
  Params params;
};
TestModel model_for(const std::string& integrator) {
  const std::vector<TestModel> candidates = {
      {"harmonic_oscillator", {}},
      {"kepler", {}},
      {"dahlquist", {}},
      {"spring_chain", {}},
      {"pendulum_chain", {{"constrained", "true"}, {"n", 3}}},
      {"fluid_2d", {{"n", 8}}},
      {"prothero_robinson", {}}};  // a model with an additive split (imex, lie, strang, arkode_mri)
  for (const TestModel& m : candidates) {
    try {
      make_setup(m.name, {integrator}, m.params);
      return m;
    } catch (const BadInput&) {
    }
  }
  return {};
}

struct Tally {
  int cases = 0, refused = 0, outside = 0;
  std::vector<std::string> failures;
};

// `base` holds the parameters the model needs; the probed key is added to (or overrides) them.
Params with_key(Params base, const std::string& key, const std::string& value) {
  base.set(key, value);
  return base;
}

bool numeric(const ParamSpec& spec) {
  return spec.type == ParamType::real || spec.type == ParamType::integer;
}

// A value just outside each finite end of the spec's range: the end itself when it is open,
// else one beyond it (integers) or a relative 1e-6 beyond it (reals).
std::vector<std::string> just_outside(const ParamSpec& spec) {
  std::vector<std::string> out;
  const Bounds& b = spec.bounds;
  auto text = [&](double x) {
    if (spec.type == ParamType::integer) return std::to_string(static_cast<long>(x));
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.12g", x);
    return std::string(buf);
  };
  auto beyond = [&](double end, bool open, double dir) {
    if (open) return end;
    return end +
           dir * (spec.type == ParamType::integer ? 1.0 : 1e-6 * std::max(1.0, std::abs(end)));
  };
  if (std::isfinite(b.lower())) out.push_back(text(beyond(b.lower(), b.lower_open(), -1)));
  if (std::isfinite(b.upper())) out.push_back(text(beyond(b.upper(), b.upper_open(), 1)));
  for (const auto& v : out) EXPECT_FALSE(b.contains(std::stod(v))) << spec.key << "=" << v;
  return out;
}

void probe(const std::string& model, const std::string& integrator, const ParamSpec& spec, Tally& t,
           const Params& base = {}) {
  if (!numeric(spec)) return;
  auto fail = [&](const std::string& v, const std::string& why) {
    t.failures.push_back(model + "/" + integrator + " " + spec.key + "=" + v + ": " + why);
  };
  const std::vector<std::string> non_finite = {"nan", "inf", "-inf", "1e999"};
  for (const auto& v : non_finite) {
    ++t.cases;
    const ParamOutcome o = try_params(model, integrator, with_key(base, spec.key, v), spec.key);
    t.refused += o.refused;
    if (!o.refused)
      fail(v, "accepted");
    else if (!o.failure.empty())
      fail(v, o.failure);
  }
  std::vector<std::string> values = {"0", "-1"};
  for (const auto& v : just_outside(spec))
    if (std::find(values.begin(), values.end(), v) == values.end()) values.push_back(v);
  for (const auto& v : values) {
    ++t.cases;
    const bool outside = !spec.bounds.contains(std::stod(v));
    t.outside += outside;
    const ParamOutcome o = try_params(model, integrator, with_key(base, spec.key, v), spec.key);
    t.refused += o.refused;
    if (outside && !o.refused)
      fail(v, "outside the declared range " + spec.bounds.to_string() + " but accepted");
    else if (!o.failure.empty())
      fail(v, o.failure);
  }
}

// The registries' numeric parameters all declare their range (a new one must, and `describe`
// shows it); the default lies inside it; text and boolean parameters declare none.
template <class Registry>
void check_declared_bounds(const Registry& reg, int* numeric_count) {
  for (const auto& e : reg.entries()) {
    if (!e.built_in) continue;
    for (const auto& spec : e.params) {
      const std::string where = reg.kind() + " " + e.info.name + " parameter " + spec.key;
      if (!numeric(spec)) {
        EXPECT_FALSE(spec.bounds.declared()) << where << ": bounds on a non-numeric parameter";
        continue;
      }
      ++*numeric_count;
      EXPECT_TRUE(spec.bounds.declared()) << where << ": no declared range (ParamSpec::bounds)";
      EXPECT_TRUE(spec.bounds.contains(std::stod(spec.default_value)))
          << where << ": default " << spec.default_value << " outside " << spec.bounds.to_string();
    }
  }
}

TEST(BadInputCatalogue, EveryNumericParameterDeclaresItsRange) {
  int models = 0, integrators = 0;
  check_declared_bounds(model_registry(), &models);
  check_declared_bounds(integrator_registry(), &integrators);
  std::printf("numeric parameters with a declared range: %d of models, %d of integrators\n", models,
              integrators);
  EXPECT_GT(models, 100);
  EXPECT_GT(integrators, 100);
}

TEST(BadInputCatalogue, EveryNumericModelParameter) {
  Tally t;
  for (const auto& e : model_registry().entries()) {
    if (!e.built_in) continue;
    for (const auto& spec : e.params) probe(e.info.name, "rk4", spec, t);
  }
  for (const auto& f : t.failures) ADD_FAILURE() << f;
  std::printf("model parameters: %d cases, %d outside the declared range, %d refused\n", t.cases,
              t.outside, t.refused);
  EXPECT_GT(t.cases, 100);  // the registries were enumerated
  EXPECT_GT(t.outside, 100);
  EXPECT_GE(t.refused, t.outside);
}

TEST(BadInputCatalogue, EveryNumericIntegratorParameter) {
  Tally t;
  for (const auto& e : integrator_registry().entries()) {
    if (!e.built_in) continue;
    const TestModel model = model_for(e.info.name);
    ASSERT_FALSE(model.name.empty()) << e.info.name << ": no test model accepts it";
    for (const auto& spec : e.params) probe(model.name, e.info.name, spec, t, model.params);
  }
  for (const auto& f : t.failures) ADD_FAILURE() << f;
  std::printf("integrator parameters: %d cases, %d outside the declared range, %d refused\n",
              t.cases, t.outside, t.refused);
  EXPECT_GT(t.cases, 100);
  EXPECT_GT(t.outside, 100);
  EXPECT_GE(t.refused, t.outside);
}

// Every built-in model estimates its size from its parameters, so `check_run_size` can refuse
// a run before anything is allocated (a new model family must add one).
TEST(BadInputCatalogue, EveryModelEstimatesItsSize) {
  for (const auto& e : model_registry().entries()) {
    if (!e.built_in) continue;
    ASSERT_TRUE(static_cast<bool>(e.info.size)) << e.info.name << " has no size estimate";
    // The estimate at the defaults is at least the real dimension (an underestimate would let a
    // too-large run through).
    const auto sys = model_registry().create(e.info.name, Params{});
    const RunMemory m = estimate_run_memory(e.info.name, {"rk4"}, Params{});
    EXPECT_GE(m.model.dimension, static_cast<double>(sys->dimension())) << e.info.name;
    EXPECT_LE(m.model.dimension, 8.0 * static_cast<double>(sys->dimension()) + 64) << e.info.name;
  }
}

TEST(BadInputCatalogue, ClosestNamesAreSuggested) {
  EXPECT_EQ(closest_names("clth", model_registry().names()).front(), "cloth");
  EXPECT_EQ(closest_names("Kepler", model_registry().names()).front(), "kepler");
  EXPECT_TRUE(closest_names("zzzzzzzz", model_registry().names()).empty());
  EXPECT_EQ(did_you_mean("rk", {"rk4", "rk45", "euler"}), "; did you mean 'rk4' or 'rk45'?");
}

TEST(BadInputCatalogue, MemorySizes) {
  EXPECT_EQ(parse_memory_size("512M"), 512.0 * 1024 * 1024);
  EXPECT_EQ(parse_memory_size("8GiB"), 8.0 * 1024 * 1024 * 1024);
  EXPECT_EQ(parse_memory_size("1000"), 1000.0);
  for (const char* bad : {"", "abc", "-1G", "0", "1Q", "nan", "inf"})
    EXPECT_THROW(parse_memory_size(bad), BadInput) << bad;
}

}  // namespace
