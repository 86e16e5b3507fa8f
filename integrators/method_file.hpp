// Methods as files: one TOML file per coefficient-defined method (methods/*.toml in the
// repository, compiled into the library; a user's own anywhere). The format:
//
//   name = "heun3"                    # [a-z0-9_]+, unique among the registered integrators
//   kind = "explicit_rk"              # explicit_rk | dirk | irk | rosenbrock | kick_drift |
//                                     # imex_ark (kick_drift's old name "splitting" still reads)
//   order = 3                         # claimed; every order condition up to it must hold
//   stage_order = 1                   # optional claim (C(q))
//   description = "..."               # what `list integrators` prints
//   reference = "..."                 # authors, venue, year
//   class = "explicit RK"             # optional: the kind column of `list` (default from kind)
//   A = [[0, 0, 0], ["1/3", 0, 0], [0, "2/3", 0]]
//   b = ["1/4", 0, "3/4"]
//   c = [0, "1/3", "2/3"]             # optional (default: row sums; given ones are checked)
//   b_embedded = [...]                # optional, with embedded_order: fixed or adaptive steps
//   embedded_order = 2
//   fsal = true                       # optional claim, checked
//
// Coefficients are TOML numbers or strings holding an exact expression: rationals "1/3",
// sqrt(...), + - * / ^ and parentheses, and names defined in an optional [constants] table
// (evaluated in order, each may use the earlier ones), evaluated in long double.
// [constants] may come first: TOML then puts the keys after it into the table, and the file's
// top-level keys of its kind found there (they cannot name constants) are read as top-level
// keys; likewise an imex_ark file's top-level keys after [explicit] or [implicit]. Any other
// key in the wrong table is BadInput naming the table and what to move.
//
// Kinds and their keys:
//   explicit_rk  A strictly lower triangular.
//   dirk         A lower triangular (SDIRK/ESDIRK; a zero first diagonal is an explicit first
//                stage), solved stage by stage by Newton (ImplicitCore).
//   irk          A, b, c: fully implicit, one coupled simplified-Newton system with A⁻¹'s
//                eigenvalue transformation (ImplicitRungeKutta; A must be invertible);
//                solver = "radau5" runs a 3-stage Radau IIA tableau with Hairer & Wanner's
//                RADAU5 (adaptive).
//   rosenbrock   gamma (the diagonal γ), alpha and gamma_offdiag (strictly lower), b,
//                optional b_embedded/embedded_order — the form of Hairer & Wanner II, §IV.7,
//                (7.4); or convention = "transformed" with a, c_transformed, m, m_embedded
//                (HW II (7.24)); optional w_order: the claimed W-order (the order for an
//                arbitrary matrix in place of J, <= order; core/theory/method_analysis.hpp).
//   kick_drift   kick, drift (kick/drift coefficients, run as v += h kick_j a; x += h drift_j v),
//                or composition = [γ...] (a composition of velocity Verlet steps);
//                velocity_independent = true|false (default true).
//   imex_ark     an additive (implicit-explicit) Runge-Kutta method (integrators/imex/imex_ark.hpp)
//                for models with an additive split f = f_E + f_I: the tables in two sections,
//                  [explicit]  A (strictly lower triangular), b, optional b_embedded
//                  [implicit]  A (lower triangular: DIRK/ESDIRK), b, optional b_embedded
//                with the same number of stages; c at the top (shared nodes, checked against
//                the row sums of both A) or, for methods whose tables have different nodes
//                (Pareschi & Russo's IMEX-SSP), c in each section (each checked against its
//                own A; leave both out to take the row sums); b_embedded in both sections or
//                in neither, with embedded_order (fixed or adaptive steps); stage_order: a claim
//                about the implicit table (C(q)). Checked: each table's own order conditions
//                up to `order` (rooted trees up to 8), then the coupling conditions of the pair
//                up to min(order, 4) (bi-coloured trees, core/theory/additive_conditions.hpp), the
//                first violated one named ("coupling condition bE·AI·c = 1/6 (order 3) has
//                residual ..."); likewise the embedded rows up to embedded_order.
//
// A bad file is BadInput (exit 2) naming the file, the line and what is wrong: wrong shapes,
// the wrong triangle for the kind, an unparseable expression, an unknown key, a claimed order
// the coefficients do not meet (the first violated condition: its order, its tree, its
// residual).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/integrator.hpp"
#include "core/registry_types.hpp"
#include "core/theory/tableau.hpp"
#include "integrators/implicit/rosenbrock.hpp"
#include "integrators/method_kinds.hpp"
#include "integrators/symplectic/kick_drift.hpp"

namespace stiffbench {

enum class MethodKind {
  explicit_rk,
  dirk,
  irk,
  rosenbrock,
  kick_drift,
  imex_ark,
  splitting = kick_drift  // the old name of kick_drift, kept for one version
};
std::string to_string(MethodKind k);

struct MethodDefinition {
  std::string name;
  MethodKind kind = MethodKind::explicit_rk;
  int order = 0;
  std::string description, reference, class_text;
  std::string source;                   // the file's path, or "methods/<file>.toml (built in)"
  std::string solver;                   // irk: "" (ImplicitRungeKutta) or "radau5"
  ButcherTableau tableau;               // explicit_rk, dirk, irk (validated, c completed)
  RosenbrockTableau rosenbrock;         // rosenbrock
  KickDriftScheme splitting{{}, true};  // kick_drift
  AdditiveTableau additive;             // imex_ark (validated, c completed)
  // Fixed and adaptive steps (embedded weights), or fixed only.
  bool adaptive() const;
};

// Parses and checks one method file's text; `origin` names it in messages ("my.toml").
MethodDefinition parse_method_file(const std::string& text, const std::string& origin);
// Reads `path` and parses it; BadInput naming the path when it cannot be read.
MethodDefinition load_method_file(const std::string& path);

// The integrator the definition describes, with the family's parameters (Newton, linear
// solver, controller) read from `p` (declared by method_param_specs).
std::unique_ptr<Integrator> make_integrator(const MethodDefinition& m, const Params& p = {});
std::vector<ParamSpec> method_param_specs(const MethodDefinition& m);
// The registry entry of a definition (MethodInfo with its text, parameters, factory).
IntegratorRegistry::Entry method_registry_entry(const MethodDefinition& m);

// The built-in methods: the files of methods/ compiled into the library, parsed once, in
// registration order.
const std::vector<MethodDefinition>& built_in_methods();
const MethodDefinition& built_in_method(const std::string& name);

}  // namespace stiffbench
