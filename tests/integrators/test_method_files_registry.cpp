// The built-in method files (methods/*.toml, compiled into the library: embedded_method_files())
// and the integrator registry agree: one source of truth for the coefficients, description, kind
// and reference of every coefficient-defined method.
//
// The files are read here with toml++ directly, not through parse_method_file: the expected
// values are the files' own keys (each coefficient evaluated by evaluate_coefficient, the
// [constants] in file order), compared with what the registry and the family lookups serve.
#include <gtest/gtest.h>

#include <toml++/toml.h>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "experiments/framework/catalog.hpp"
#include "integrators/coefficient_expr.hpp"
#include "integrators/embedded_methods.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/implicit/gauss.hpp"
#include "integrators/implicit/radau5.hpp"
#include "integrators/implicit/rosenbrock.hpp"
#include "integrators/method_file.hpp"
#include "integrators/symplectic/composition.hpp"
#include "integrators/symplectic/kick_drift.hpp"

namespace stiffbench {
namespace {

// One method file as written: its TOML table and its [constants] evaluated in file order.
struct RawFile {
  std::string file;
  toml::table root;
  CoefficientConstants constants;

  std::string text(const char* key) const { return root[key].value_or(std::string()); }
  bool has(const char* key) const { return root.contains(key); }

  double coefficient(const toml::node& n) const {
    if (const auto* s = n.as_string())
      return static_cast<double>(evaluate_coefficient(s->get(), constants));
    return n.value<double>().value();
  }
  Vec vector(const char* key) const {
    const toml::array& a = *root[key].as_array();
    Vec v(static_cast<Index>(a.size()));
    for (std::size_t i = 0; i < a.size(); ++i) v[static_cast<Index>(i)] = coefficient(a[i]);
    return v;
  }
  // An imex_ark file's [explicit] or [implicit] section, with the file's constants.
  RawFile section(const char* name) const {
    return RawFile{file, *root[name].as_table(), constants};
  }
  Mat matrix(const char* key) const {
    const toml::array& rows = *root[key].as_array();
    const auto s = static_cast<Index>(rows.size());
    Mat m(s, s);
    for (Index i = 0; i < s; ++i) {
      const toml::array& row = *rows[static_cast<std::size_t>(i)].as_array();
      for (Index j = 0; j < s; ++j) m(i, j) = coefficient(row[static_cast<std::size_t>(j)]);
    }
    return m;
  }
};

std::vector<RawFile> raw_files() {
  std::vector<RawFile> out;
  for (const auto& [file, text] : embedded_method_files()) {
    RawFile r{std::string(file), toml::parse(text, std::string(file)), {}};
    if (const toml::table* k = r.root["constants"].as_table()) {
      std::vector<std::pair<int, std::string>> order;
      for (const auto& [name, value] : *k)
        order.emplace_back(static_cast<int>(value.source().begin.line), std::string(name.str()));
      std::sort(order.begin(), order.end());
      for (const auto& [line, name] : order)
        r.constants[name] = evaluate_coefficient(*(*k)[name].value<std::string>(), r.constants);
    }
    out.push_back(std::move(r));
  }
  return out;
}

const std::vector<RawFile>& files() {
  static const std::vector<RawFile> all = raw_files();
  return all;
}

bool is_tableau_kind(const std::string& kind) {
  return kind == "explicit_rk" || kind == "dirk" || kind == "irk";
}

// The kick/drift form a splitting file describes: its kick and drift, or its Verlet composition
// (neighbouring half kicks merged, integrators/symplectic/composition.hpp).
KickDriftCoefficients splitting_of(const RawFile& r) {
  KickDriftCoefficients c;
  if (r.has("composition")) {
    const Vec g = r.vector("composition");
    c.kick.assign(static_cast<std::size_t>(g.size()) + 1, 0.0);
    c.drift.assign(static_cast<std::size_t>(g.size()) + 1, 0.0);
    for (Index j = 0; j < g.size(); ++j) {
      const auto u = static_cast<std::size_t>(j);
      c.kick[u] += 0.5 * g[j];
      c.kick[u + 1] += 0.5 * g[j];
      c.drift[u] = g[j];
    }
  } else {
    const Vec k = r.vector("kick"), d = r.vector("drift");
    c.kick.assign(k.begin(), k.end());
    c.drift.assign(d.begin(), d.end());
  }
  return c;
}

// f (or acceleration) evaluations per step after start-up, counted from the file as MethodInfo
// defines them: explicit RK and DIRK one per stage, less one for a first-same-as-last pair;
// a fully implicit tableau its s stages (per Newton iteration); a Rosenbrock method one per
// distinct stage argument (a row of alpha equal to an earlier one reuses that f); a kick/drift
// method one per non-zero kick, less one when the last kick's acceleration is reused (FSAL:
// velocity-independent forces, the first kick non-zero and no drift after the last kick).
int evaluations_of(const RawFile& r) {
  const std::string kind = r.text("kind");
  // An additive method: one stage per row of its tables (MethodInfo::stages; the evaluations of
  // each part per step are in integrators/imex/imex_ark.hpp).
  if (kind == "imex_ark") return static_cast<int>(r.section("explicit").vector("b").size());
  if (is_tableau_kind(kind)) {
    const int s = static_cast<int>(r.vector("b").size());
    return s - (r.root["fsal"].value_or(false) ? 1 : 0);
  }
  if (kind == "rosenbrock") {
    Mat alpha;
    if (r.text("convention") == "transformed") {
      // α = aΓ with Γ = (diag(1/γ) - c)⁻¹ (Hairer & Wanner II, Sect. IV.7, (7.24)).
      const Mat c = r.matrix("c_transformed");
      Mat gamma_inv = -c;
      gamma_inv.diagonal().setConstant(1.0 / r.coefficient(*r.root.get("gamma")));
      alpha = r.matrix("a") * gamma_inv.inverse();
    } else {
      alpha = r.matrix("alpha");
    }
    int n = 0;
    for (Index i = 0; i < alpha.rows(); ++i) {
      bool repeat = false;
      for (Index j = 0; j < i; ++j)
        repeat = repeat || (alpha.row(i) - alpha.row(j)).cwiseAbs().maxCoeff() <= 1e-12;
      n += repeat ? 0 : 1;
    }
    return n;
  }
  const KickDriftCoefficients c = splitting_of(r);
  int kicks = 0;
  std::size_t last = c.kick.size();
  for (std::size_t j = 0; j < c.kick.size(); ++j)
    if (c.kick[j] != 0.0) {
      ++kicks;
      last = j;
    }
  bool fsal = r.root["velocity_independent"].value_or(true) && c.kick.size() >= 2 &&
              c.kick[0] != 0.0 && last != 0;
  for (std::size_t j = last; fsal && j < c.drift.size(); ++j) fsal = c.drift[j] == 0.0;
  return kicks - (fsal ? 1 : 0);
}

std::string family_of(const std::string& kind) {
  if (kind == "explicit_rk") return to_string(Family::explicit_rk);
  if (kind == "kick_drift") return to_string(Family::symplectic);
  if (kind == "imex_ark") return to_string(Family::imex);
  return to_string(Family::implicit);
}

// Every file's method is registered under its name with the file's order, evaluation count,
// description, class and reference, in the family of its kind, with adaptive steps exactly when
// the file gives an embedded row (or the RADAU5 solver).
TEST(MethodFilesRegistry, EveryFileIsRegisteredAsWritten) {
  ASSERT_EQ(files().size(), built_in_methods().size());
  ASSERT_GE(files().size(), 31u);  // at least the 31 original coefficient methods
  for (const RawFile& r : files()) {
    SCOPED_TRACE(r.file);
    const std::string name = r.text("name");
    EXPECT_EQ(r.file, name + ".toml");  // one file per method, named after it
    const auto* e = integrator_registry().find(name);
    ASSERT_NE(e, nullptr);
    EXPECT_TRUE(e->built_in);
    EXPECT_EQ(e->info.order, r.root["order"].value<int>().value());
    EXPECT_EQ(e->info.description, r.text("description"));
    EXPECT_EQ(e->info.kind, r.text("class"));
    EXPECT_EQ(e->info.reference, r.text("reference"));
    EXPECT_EQ(to_string(e->info.family), family_of(r.text("kind")));
    const auto integ = integrator_registry().create(name, {});
    EXPECT_EQ(e->info.stages, evaluations_of(r));
    const bool adaptive = r.has("b_embedded") || r.has("m_embedded") ||
                          r.text("solver") == "radau5" ||
                          (r.text("kind") == "imex_ark" && r.section("explicit").has("b_embedded"));
    EXPECT_EQ(integ->supports_adaptive(), adaptive);
    EXPECT_TRUE(integ->supports_fixed_step());
    EXPECT_EQ(built_in_method(name).source, "methods/" + r.file + " (built in)");
  }
}

// Every registered coefficient-defined integrator (a Butcher tableau, a Rosenbrock tableau or
// kick/drift coefficients) is one of the files.
TEST(MethodFilesRegistry, EveryCoefficientIntegratorComesFromAFile) {
  std::set<std::string> names;
  for (const RawFile& r : files()) names.insert(r.text("name"));
  std::set<std::string> coefficient_defined;
  for (const auto& e : integrator_registry().entries()) {
    if (!e.built_in) continue;
    const auto integ = integrator_registry().create(e.info.name, {});
    if (integ->butcher_tableau() != nullptr || integ->additive_tableau() != nullptr ||
        dynamic_cast<const Rosenbrock*>(integ.get()) != nullptr ||
        dynamic_cast<const KickDriftIntegrator*>(integ.get()) != nullptr)
      coefficient_defined.insert(e.info.name);
  }
  EXPECT_EQ(coefficient_defined, names);
}

void expect_same(const Mat& served, const Mat& file, const std::string& what) {
  ASSERT_EQ(served.rows(), file.rows()) << what;
  ASSERT_EQ(served.cols(), file.cols()) << what;
  EXPECT_EQ(served, file) << what;
}

void expect_same(const Vec& served, const Vec& file, const std::string& what) {
  ASSERT_EQ(served.size(), file.size()) << what;
  EXPECT_EQ(served, file) << what;
}

// The tableau a file defines: A, b, b_embedded as written; c as written or the row sums.
void expect_tableau_of_file(const ButcherTableau& t, const RawFile& r) {
  const Mat a = r.matrix("A");
  expect_same(t.a, a, "A");
  expect_same(t.b, r.vector("b"), "b");
  if (r.has("c"))
    expect_same(t.c, r.vector("c"), "c");
  else
    expect_same(t.c, Vec(a.rowwise().sum()), "c (row sums)");
  if (r.has("b_embedded")) expect_same(t.b_embedded, r.vector("b_embedded"), "b_embedded");
  EXPECT_EQ(t.order, r.root["order"].value<int>().value());
  EXPECT_EQ(t.embedded_order, r.root["embedded_order"].value_or(0));
  EXPECT_EQ(t.fsal, r.root["fsal"].value_or(false));
  EXPECT_EQ(t.stage_order, r.root["stage_order"].value_or(0));
}

// The coefficients the registered integrators run on, and those the family lookups return, are
// the files' (bit for bit; Rosenbrock methods in the transformed form to round-off, since the
// integrator keeps α, Γ, b and transforms them back).
TEST(MethodFilesRegistry, CoefficientsEqualTheFiles) {
  std::map<std::string, const ButcherTableau*> lookups;
  for (const auto* list :
       {&explicit_tableaux(), &embedded_tableaux(), &implicit_tableaux(), &esdirk_tableaux()})
    for (const ButcherTableau& t : *list) lookups[t.name] = &t;
  lookups["gauss4"] = &gauss_tableau(2);
  lookups["gauss6"] = &gauss_tableau(3);
  lookups["radau5"] = &radau5_tableau();
  for (const RawFile& r : files()) {
    const std::string name = r.text("name"), kind = r.text("kind");
    SCOPED_TRACE(r.file);
    const auto integ = integrator_registry().create(name, {});
    if (is_tableau_kind(kind)) {
      ASSERT_NE(integ->butcher_tableau(), nullptr);
      expect_tableau_of_file(*integ->butcher_tableau(), r);
      ASSERT_TRUE(lookups.count(name));
      expect_tableau_of_file(*lookups[name], r);
      expect_tableau_of_file(built_in_method(name).tableau, r);
    } else if (kind == "imex_ark") {
      const AdditiveTableau* t = integ->additive_tableau();
      ASSERT_NE(t, nullptr);
      EXPECT_EQ(t->order, r.root["order"].value<int>().value());
      EXPECT_EQ(t->embedded_order, r.root["embedded_order"].value_or(0));
      for (const auto& [part, tab] :
           {std::pair{"explicit", &t->explicit_table}, std::pair{"implicit", &t->implicit_table}}) {
        SCOPED_TRACE(part);
        const RawFile sec = r.section(part);
        const Mat a = sec.matrix("A");
        expect_same(tab->a, a, "A");
        expect_same(tab->b, sec.vector("b"), "b");
        if (sec.has("b_embedded"))
          expect_same(tab->b_embedded, sec.vector("b_embedded"), "b_embedded");
        expect_same(tab->c,
                    sec.has("c") ? sec.vector("c")
                    : r.has("c") ? r.vector("c")
                                 : Vec(a.rowwise().sum()),
                    "c");
      }
    } else if (kind == "rosenbrock") {
      const auto* ros = dynamic_cast<const Rosenbrock*>(integ.get());
      ASSERT_NE(ros, nullptr);
      const RosenbrockTableau& t = ros->tableau();
      EXPECT_EQ(t.gamma, r.coefficient(*r.root.get("gamma")));
      if (r.text("convention") == "transformed") {
        const RosenbrockTransformed tr = transform(t);
        EXPECT_LE((tr.a - r.matrix("a")).cwiseAbs().maxCoeff(), 1e-13);
        EXPECT_LE((tr.c - r.matrix("c_transformed")).cwiseAbs().maxCoeff(), 1e-12);
        EXPECT_LE((tr.m - r.vector("m")).cwiseAbs().maxCoeff(), 1e-13);
        EXPECT_LE((tr.m_embedded - r.vector("m_embedded")).cwiseAbs().maxCoeff(), 1e-13);
      } else {
        expect_same(t.alpha, r.matrix("alpha"), "alpha");
        expect_same(t.gamma_lower, r.matrix("gamma_offdiag"), "gamma_offdiag");
        expect_same(t.b, r.vector("b"), "b");
        if (r.has("b_embedded")) expect_same(t.b_embedded, r.vector("b_embedded"), "b_embedded");
      }
      const RosenbrockTableau& looked_up = name == "rosenbrock2" ? rosenbrock2_tableau()
                                           : name == "ros3p"     ? ros3p_tableau()
                                                                 : rodas4_tableau();
      EXPECT_EQ(looked_up.b, t.b);
      EXPECT_EQ(looked_up.alpha, t.alpha);
    } else {
      const auto* kd = dynamic_cast<const KickDriftIntegrator*>(integ.get());
      ASSERT_NE(kd, nullptr);
      const KickDriftCoefficients c = splitting_of(r);
      EXPECT_EQ(kd->coefficients().kick, c.kick);
      EXPECT_EQ(kd->coefficients().drift, c.drift);
      EXPECT_EQ(kd->info().requires_.velocity_independent,
                r.root["velocity_independent"].value_or(true));
    }
  }
  // The splitting lookups: the order-1/2 kick/drift methods and the higher-order compositions.
  std::set<std::string> splittings;
  for (const KickDriftCoefficients& c : kick_drift_coefficients()) splittings.insert(c.name);
  for (const CompositionMethod& m : composition_methods()) splittings.insert(m.name);
  EXPECT_EQ(splittings,
            (std::set<std::string>{"symplectic_euler", "symplectic_euler_x", "velocity_verlet",
                                   "yoshida4", "yoshida6", "blanes_moan"}));
}

// The Verlet substeps composition_methods() recovers are the files' composition keys (Yoshida's
// methods), and none for a splitting written as kick and drift (Blanes-Moan).
TEST(MethodFilesRegistry, CompositionSubstepsAreTheFiles) {
  for (const CompositionMethod& m : composition_methods()) {
    SCOPED_TRACE(m.name);
    const auto it = std::find_if(files().begin(), files().end(),
                                 [&](const RawFile& r) { return r.text("name") == m.name; });
    ASSERT_NE(it, files().end());
    if (it->has("composition")) {
      const Vec g = it->vector("composition");
      EXPECT_EQ(m.gamma, std::vector<double>(g.begin(), g.end()));
    } else {
      EXPECT_TRUE(m.gamma.empty());
    }
  }
}

}  // namespace
}  // namespace stiffbench
