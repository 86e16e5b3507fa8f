// The SUNDIALS registry entries: their parameters, how each reads them into Settings, and the
// front-end each creates (cvode.cpp, arkode.cpp, mri.cpp).
#include <sundials/sundials_version.h>

#include <algorithm>

#include "integrators/method_entry.hpp"
#include "integrators/reference/sundials.hpp"
#include "integrators/reference/sundials/front_end.hpp"
#include "integrators/reference/sundials/tables.hpp"

namespace stiffbench {

using namespace sundials_detail;

namespace {

std::vector<ParamSpec> common_specs(bool linear) {
  using P = ParamType;
  using B = Bounds;
  std::vector<ParamSpec> s = {
      {"rtol", P::real, "1e-6",
       "relative tolerance (adaptive mode; also scales Newton's tolerance)", B::positive()},
      {"atol", P::real, "1e-10", "absolute tolerance", B::non_negative()},
      {"max_steps", P::integer, "100000", "maximum internal steps per output interval",
       B::at_least(1)},
  };
  if (linear) {
    s.push_back({"linear_solver",
                 P::text,
                 "auto",
                 "dense, band, klu (sparse, needs the analytic Jacobian), spgmr (matrix-free "
                 "GMRES) or velocity (flexible GMRES preconditioned by the velocity-form solve "
                 "of I - gamma J; mechanical models with force Jacobians); auto: dense up to " +
                     std::to_string(kSundialsAutoDenseMax) +
                     " unknowns; above, velocity for mechanical models with force Jacobians, "
                     "klu with another analytic sparse Jacobian, spgmr otherwise (jacobian=dq "
                     "counts as none); solve prints the choice and the rule first in the library "
                     "statistics",
                 {"auto", "dense", "band", "klu", "spgmr", "velocity"}});
    s.push_back({"jacobian",
                 P::text,
                 "auto",
                 "analytic, dq (library difference quotients); auto: analytic where provided",
                 {"auto", "analytic", "dq"}});
  }
  return s;
}

Settings read_common(const Params& p, bool linear) {
  Settings s;
  s.rtol = p.real("rtol");
  s.atol = p.real("atol");
  require_input(s.rtol > 0, "parameter 'rtol' must be > 0");
  require_input(s.atol >= 0, "parameter 'atol' must be >= 0");
  s.max_steps = p.integer("max_steps");
  require_input(s.max_steps >= 1, "parameter 'max_steps' must be >= 1");
  if (linear) {
    const std::string& l = p.text("linear_solver");
    s.lin = l == "band"       ? Lin::band
            : l == "klu"      ? Lin::klu
            : l == "spgmr"    ? Lin::spgmr
            : l == "velocity" ? Lin::velocity
            : l == "dense"    ? Lin::dense
                              : Lin::automatic;
    s.jacobian = p.text("jacobian");
  }
  return s;
}

// ARKODE's Newton iteration on the implicit stages. It stops when its estimate of the stage
// error, in the WRMS norm of the weights 1/(rtol |y| + atol), is below nonlin_conv_coef; ARKODE's
// defaults (0.1, 3 iterations) leave a stage error near 0.1 rtol. A fixed-step run that is to
// agree with another implementation of the same tables to round-off needs the iteration
// converged: rtol=1e-12 atol=1e-14 nonlin_conv_coef=1e-3 max_nonlin_iters=20 (docs/design.md).
std::vector<ParamSpec> nonlin_specs() {
  return {{"nonlin_conv_coef", ParamType::real, "0.1",
           "Newton stops when its error estimate (WRMS norm with the rtol/atol weights) is below "
           "this (ARKStepSetNonlinConvCoef; ARKODE's default 0.1); fixed-step comparisons: "
           "1e-3 with rtol=1e-12 atol=1e-14",
           Bounds::positive()},
          {"max_nonlin_iters", ParamType::integer, "3",
           "Newton iterations per stage before the step fails (ARKStepSetMaxNonlinIters; "
           "ARKODE's default 3; a failure in fixed-step mode ends the run)",
           Bounds::at_least(1)}};
}
void read_nonlin(const Params& p, Settings& s) {
  s.nonlin_conv_coef = p.real("nonlin_conv_coef");
  require_input(s.nonlin_conv_coef > 0, "parameter 'nonlin_conv_coef' must be > 0");
  s.max_nonlin_iters = static_cast<int>(p.integer("max_nonlin_iters"));
  require_input(s.max_nonlin_iters >= 1, "parameter 'max_nonlin_iters' must be >= 1");
}

// ARKODE's default reuses M - γJ for up to 20 steps; with ARKODE_SDIRK_5_3_4 and a matrix
// solver that gave errors of 2e-6 at rtol = 1e-8 on y' = (-1+3i)y (SPGMR: 5e-11), measured
// with a standalone ARKODE 5.4.1 program. A setup every step restores the accuracy.
ParamSpec lsetup_spec() {
  return {"lsetup_frequency", ParamType::integer, "1",
          "steps between linear-solver setups (ARKODE's own default, 20, lost accuracy with a "
          "matrix solver on oscillatory problems; 1 sets the matrix up every step)",
          Bounds::at_least(1)};
}

// The keys of every ARKStep with implicit stages (arkode_dirk, arkode_imex and arkode_mri's
// inner ARKStep): the common ones with a linear solver, lsetup_frequency and ARKODE's Newton.
std::vector<ParamSpec> implicit_arkstep_specs() {
  auto specs = common_specs(true);
  specs.push_back(lsetup_spec());
  for (const ParamSpec& n : nonlin_specs()) specs.push_back(n);
  return specs;
}
Settings read_implicit_arkstep(const Params& p) {
  Settings s = read_common(p, true);
  s.lsetup_frequency = p.integer("lsetup_frequency");
  require_input(s.lsetup_frequency >= 1, "parameter 'lsetup_frequency' must be >= 1");
  read_nonlin(p, s);
  return s;
}

constexpr MethodText kArkodeMriText{
    .description =
        "SUNDIALS ARKODE MRIStep on the model's split: slow f_E explicit (MRI coupling "
        "table), fast f_I by an inner implicit ARKStep with J_I; fixed slow step",
    .kind = "library: ARKODE (multirate)",
    .reference =
        "D. R. Reynolds, D. J. Gardner, C. S. Woodward & R. Chinomona, ARKODE: a "
        "flexible IVP solver infrastructure for one-step methods, ACM Trans. Math. "
        "Softw. 49 (2023) 19; A. Sandu, A class of multirate infinitesimal GARK methods, "
        "SIAM J. Numer. Anal. 57 (2019) 2300-2327"};

void register_arkode_mri(IntegratorRegistry& reg) {
  auto specs = implicit_arkstep_specs();
  std::vector<std::string> keys;
  for (const MriTable& m : kMriTables) keys.emplace_back(m.key);
  specs.push_back({"coupling", ParamType::text, "mri_gark_erk33a",
                   "slow coupling table (MRIStepSetCoupling): mri_gark_erk33a (order 3, Sandu "
                   "2019), mis_kw3 (order 3, ARKODE's own default at order 3; Knoth & Wolke "
                   "1998), mri_gark_erk45a (order 4)",
                   keys});
  specs.push_back({"fast_steps", ParamType::integer, "0",
                   "fast (inner) steps of h/fast_steps (ARKStepSetFixedStep on the inner "
                   "ARKStep); 0: the inner ARKStep adapts its step to rtol/atol",
                   Bounds::at_least(0)});
  specs.push_back({"implicit_table", ParamType::text, "ARKODE_SDIRK_5_3_4",
                   "the inner ARKStep's DIRK table for f_I, by ARKODE name"});
  add_built_in_integrator(
      reg, {method_info("arkode_mri", Family::reference, 3, 0, Requirements{.split = true},
                        kArkodeMriText),
            specs, [](const Params& p) {
              Settings s = read_implicit_arkstep(p);
              s.fast_steps = p.integer("fast_steps");
              require_input(s.fast_steps >= 0, "parameter 'fast_steps' must be >= 0");
              s.implicit_table = p.text("implicit_table");
              dirk_order(s.implicit_table);  // BadInput for an unknown name
              const std::string key = p.text("coupling");
              int order = 0;
              for (const MriTable& m : kMriTables)
                if (key == m.key) {
                  s.mri_table = m.id;
                  order = m.order;
                }
              require_input(order > 0, "parameter 'coupling': unknown MRI table '" + key + "'");
              Requirements needs;
              needs.split = true;
              MethodInfo info =
                  method_info("arkode_mri", Family::reference, order, 0, needs, kArkodeMriText);
              info.description = "ARKODE MRIStep " + key + ", fast " + s.implicit_table +
                                 (s.fast_steps > 0 ? " at h/" + std::to_string(s.fast_steps)
                                                   : std::string(" adaptive"));
              return make_mri_integrator(info, s);
            }});
}

}  // namespace

// A dense n x n matrix is 8n² bytes (4.8 GB for cloth n = 64's 24,576 unknowns) and its LU costs
// 2n³/3 flops per setup; KLU factorises the sparse I - γJ instead, and without an analytic
// Jacobian SPGMR needs only f and products (no n difference quotients per setup). The limit's
// measurements are in sundials.hpp.
SundialsLinearSolverChoice sundials_auto_linear_solver(Index unknowns, bool analytic_jacobian,
                                                       bool mechanical_blocks) {
  const std::string size = std::to_string(unknowns) + " unknowns";
  const std::string limit = std::to_string(kSundialsAutoDenseMax);
  if (unknowns <= kSundialsAutoDenseMax) return {"dense", size + " <= " + limit};
  if (analytic_jacobian && mechanical_blocks)
    return {"velocity", size + " > " + limit + " and a mechanical model with force Jacobians"};
  if (analytic_jacobian) return {"klu", size + " > " + limit + " and an analytic sparse Jacobian"};
  return {"spgmr", size + " > " + limit + " and no analytic Jacobian"};
}

namespace {

constexpr const char* kSundials =
    "A. C. Hindmarsh et al., SUNDIALS: suite of nonlinear and differential/algebraic equation "
    "solvers, ACM Trans. Math. Softw. 31 (2005) 363-396";
constexpr const char* kArkode =
    "D. R. Reynolds, D. J. Gardner, C. S. Woodward & R. Chinomona, ARKODE: a flexible IVP "
    "solver infrastructure for one-step methods, ACM Trans. Math. Softw. 49 (2023) 19";

struct CvodeMethod {
  const char* name;
  int lmm;
  int max_order;
  MethodText text;
};

constexpr MethodText kArkodeErkText{
    .description = "SUNDIALS ARKODE ARKStep, explicit table by name; adaptive or fixed step",
    .kind = "library: ARKODE",
    .reference = kArkode};
constexpr MethodText kArkodeDirkText{
    .description =
        "SUNDIALS ARKODE ARKStep, DIRK table by name (default L-stable SDIRK order 4); "
        "adaptive or fixed step",
    .kind = "library: ARKODE",
    .reference = kArkode};
constexpr MethodText kArkodeImexText{
    .description = "SUNDIALS ARKODE ARKStep IMEX with the model's split (all-implicit without one)",
    .kind = "library: ARKODE",
    .reference = kArkode};

// The MethodInfo of an ARKODE integrator created with the given tables: the registered kind
// and reference, and a description naming the tables.
MethodInfo arkode_info(const char* name, int order, const MethodText& text,
                       std::string description) {
  MethodInfo info = method_info(name, Family::reference, order, 0, {}, text);
  info.description = std::move(description);
  return info;
}

}  // namespace

void register_sundials_integrators(IntegratorRegistry& reg) {
  using P = ParamType;
  using B = Bounds;
  // CVodeSetMaxOrd refuses an order above the method's (CV_ILL_INPUT): at most 5 for BDF, 12 for
  // Adams.
  for (const CvodeMethod& m :
       {CvodeMethod{
            "cvode_bdf",
            CV_BDF,
            5,
            {.description = "SUNDIALS CVODE, variable-order BDF (1-5) with Newton; adaptive",
            .kind = "library: CVODE",
            .reference = kSundials}},
        CvodeMethod{"cvode_adams",
                    CV_ADAMS,
                    12,
                    {.description = "SUNDIALS CVODE, variable-order Adams-Moulton (1-12) with "
                                    "Newton; adaptive",
                    .kind = "library: CVODE",
                    .reference = kSundials}}}) {
    auto cvode_specs = common_specs(true);
    cvode_specs.push_back({"max_order", P::integer, "0",
                           "maximum order (0: CVODE default, 5 for BDF, 12 for Adams)",
                           B::in(0, m.max_order)});
    const MethodInfo info = method_info(m.name, Family::reference, 0, 0, {}, m.text);
    add_built_in_integrator(reg, {info, cvode_specs, [info, lmm = m.lmm](const Params& p) {
                                    Settings s = read_common(p, true);
                                    s.max_order = static_cast<int>(p.integer("max_order"));
                                    require_input(s.max_order >= 0,
                                                  "parameter 'max_order' must be >= 0");
                                    return make_cvode_integrator(info, lmm, s);
                                  }});
  }
  auto erk_specs = common_specs(false);
  erk_specs.push_back({"explicit_table", P::text, "ARKODE_DORMAND_PRINCE_7_4_5",
                       "ARKODE explicit Butcher table name"});
  add_built_in_integrator(
      reg, {method_info("arkode_erk", Family::reference, erk_order("ARKODE_DORMAND_PRINCE_7_4_5"),
                        7, {}, kArkodeErkText),
            erk_specs, [](const Params& p) {
              Settings s = read_common(p, false);
              s.explicit_table = p.text("explicit_table");
              MethodInfo info = arkode_info("arkode_erk", erk_order(s.explicit_table),
                                            kArkodeErkText, "ARKODE ERK " + s.explicit_table);
              return make_arkode_integrator(info, ArkodeMode::explicit_only, s);
            }});
  auto dirk_specs = implicit_arkstep_specs();
  dirk_specs.push_back(
      {"implicit_table", P::text, "ARKODE_SDIRK_5_3_4", "ARKODE implicit Butcher table name"});
  add_built_in_integrator(
      reg, {method_info("arkode_dirk", Family::reference, dirk_order("ARKODE_SDIRK_5_3_4"), 5, {},
                        kArkodeDirkText),
            dirk_specs, [](const Params& p) {
              Settings s = read_implicit_arkstep(p);
              s.implicit_table = p.text("implicit_table");
              MethodInfo info = arkode_info("arkode_dirk", dirk_order(s.implicit_table),
                                            kArkodeDirkText, "ARKODE DIRK " + s.implicit_table);
              return make_arkode_integrator(info, ArkodeMode::implicit_only, s);
            }});
  auto imex_specs = implicit_arkstep_specs();
  std::vector<std::string> pair_keys;
  for (const ArkPair& a : kArkPairs) pair_keys.emplace_back(a.key);
  pair_keys.emplace_back("named");
  imex_specs.push_back(
      {"tables", P::text, "ark436l2sa",
       "the ARK pair (ARKStepSetTableNum): ark324l2sa = ARKODE_ARK324L2SA_ERK_4_2_3 + "
       "ARKODE_ARK324L2SA_DIRK_4_2_3 (order 3, ARKODE's default at order 3), ark436l2sa = "
       "ARK436L2SA_ERK_6_3_4 + _DIRK_6_3_4 (order 4, ARKODE's default), ark437l2sa, ark548l2sa "
       "(ARKODE's default at order 5), ark548l2sab; named: explicit_table and implicit_table",
       pair_keys});
  imex_specs.push_back({"explicit_table", P::text, "",
                        "with tables=named: the explicit table of the pair by ARKODE name"});
  imex_specs.push_back({"implicit_table", P::text, "",
                        "with tables=named: the implicit table of the pair by ARKODE name"});
  const ArkPair& def = kArkPairs[1];
  add_built_in_integrator(
      reg, {method_info("arkode_imex", Family::reference, dirk_order(def.dirk_name), 6, {},
                        kArkodeImexText),
            imex_specs, [](const Params& p) {
              Settings s = read_implicit_arkstep(p);
              read_ark_pair(p, s);
              const int q = std::min(erk_order(s.explicit_table), dirk_order(s.implicit_table));
              MethodInfo info =
                  arkode_info("arkode_imex", q, kArkodeImexText,
                              "ARKODE IMEX " + s.explicit_table + " / " + s.implicit_table);
              return make_arkode_integrator(info, ArkodeMode::imex, s);
            }});
  register_arkode_mri(reg);
}

std::string sundials_library_version() {
  char version[64] = {};
  if (SUNDIALSGetVersion(version, static_cast<int>(sizeof version)) != 0) return "unknown";
  return version;
}

}  // namespace stiffbench
