#include "integrators/splitting/operator_splitting.hpp"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "core/split_views.hpp"
#include "integrators/method_entry.hpp"

namespace stiffbench {

namespace {

constexpr const char* kSplittingReference =
    "G. Strang, On the construction and comparison of difference schemes, SIAM J. Numer. Anal. 5 "
    "(1968) 506-517; E. Hairer, C. Lubich & G. Wanner, Geometric Numerical Integration, 2nd ed., "
    "Springer 2006, Sect. II.5";

constexpr MethodText kLieText{
    .description =
        "Lie splitting of f = f_E + f_I: E(h) by the `explicit` sub-integrator on f_E, "
        "then I(h) by the `implicit` one on f_I; fixed step",
    .kind = "operator splitting (Lie-Trotter)",
    .reference = kSplittingReference};
constexpr MethodText kStrangText{
    .description =
        "Strang splitting of f = f_E + f_I: E(h/2), I(h), E(h/2) with the `explicit` "
        "and `implicit` sub-integrators on the two parts; fixed step",
    .kind = "operator splitting (Strang)",
    .reference = kSplittingReference};

const char* scheme_name(SplittingScheme s) { return s == SplittingScheme::lie ? "lie" : "strang"; }

// The registered MethodInfo (sub-integrators: the defaults) or, with their names, that of an
// instance, whose description names its sub-integrators.
// The order is the splitting's (1 or 2) unless a sub-integrator's is lower: each substep's local
// error O(h^(q+1)) adds to the splitting's, so the scheme converges with min(scheme, q_E, q_I)
// (Hairer, Lubich & Wanner, Geometric Numerical Integration, 2nd ed. 2006, §III.5; McLachlan &
// Quispel, Acta Numerica 11, 2002). Strang with forward and backward Euler is of order 1.
MethodInfo splitting_info(SplittingScheme scheme, int explicit_stages, int implicit_stages,
                          const std::string& explicit_name = {},
                          const std::string& implicit_name = {}, int sub_order = 2) {
  const bool lie = scheme == SplittingScheme::lie;
  Requirements needs;
  needs.split = true;
  MethodInfo info = method_info(
      scheme_name(scheme), Family::operator_splitting, std::min(lie ? 1 : 2, sub_order),
      (lie ? 1 : 2) * explicit_stages + implicit_stages, needs, lie ? kLieText : kStrangText);
  if (!explicit_name.empty())
    info.description = std::string(lie ? "Lie" : "Strang") + " splitting: f_E by " + explicit_name +
                       ", f_I by " + implicit_name + "; fixed step, order " +
                       std::to_string(info.order);
  return info;
}

// "integrator 'strang', parameter 'implicit' = 'verlet': " — the prefix of every message about a
// sub-integrator.
std::string sub_prefix(const std::string& who, const char* key, const std::string& name) {
  return "integrator '" + who + "', parameter '" + key + "' = '" + name + "': ";
}

// What the part views never offer (core/split_views.hpp): the explicit part is a plain
// OdeSystem; neither view has springs, grid operators, constraints or a split of its own.
void check_sub_requirements(const std::string& who, const char* key, const Integrator& sub,
                            bool explicit_part) {
  const std::string pre = sub_prefix(who, key, sub.info().name);
  require_input(sub.supports_fixed_step(),
                pre + "an adaptive-only integrator cannot take the fixed substeps of a splitting");
  const Requirements& r = sub.info().requires_;
  const char* lack = r.split            ? "an additive split"
                     : r.spring_network ? "the model's spring network"
                     : r.grid_fluid     ? "grid-fluid operators"
                     : r.constraints    ? "holonomic constraints"
                     : (explicit_part && (r.mechanical || r.velocity_independent))
                         ? "a mechanical system (the explicit part f_E = [0; a_E] is not of the "
                           "form [v; a])"
                         : nullptr;
  require_input(lack == nullptr, pre + "it needs " + std::string(lack ? lack : "") +
                                     ", which the " + (explicit_part ? "explicit" : "implicit") +
                                     " part's view does not have");
}

std::unique_ptr<Integrator> make_sub(const IntegratorRegistry& reg, const std::string& who,
                                     const char* key, const std::string& name, bool explicit_part) {
  std::unique_ptr<Integrator> sub;
  try {
    sub = reg.create(name, Params{});
  } catch (const BadInput& e) {
    throw BadInput(sub_prefix(who, key, name) + e.what());
  }
  check_sub_requirements(who, key, *sub, explicit_part);
  return sub;
}

// reset() of a sub-integrator on its part's view, with BadInput naming the parameter.
void reset_sub(Integrator& sub, const OdeSystem& view, double t, CVecRef y, const std::string& who,
               const char* key) {
  try {
    sub.reset(view, t, y);
  } catch (const BadInput& e) {
    throw BadInput(sub_prefix(who, key, sub.info().name) + e.what());
  }
}

}  // namespace

OperatorSplitting::OperatorSplitting(SplittingScheme scheme,
                                     std::unique_ptr<Integrator> explicit_part,
                                     std::unique_ptr<Integrator> implicit_part)
    : Integrator(
          splitting_info(scheme, explicit_part->info().stages, implicit_part->info().stages,
                         explicit_part->info().name, implicit_part->info().name,
                         std::min(explicit_part->info().order, implicit_part->info().order))),
      scheme_(scheme),
      explicit_(std::move(explicit_part)),
      implicit_(std::move(implicit_part)) {}

void OperatorSplitting::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  sys_ = &sys;
  explicit_view_ = explicit_part_view(sys);
  implicit_view_ = implicit_part_view(sys);
  // Checks now, naming the parameter, that each sub-integrator can run on its part's view.
  reset_sub(*explicit_, *explicit_view_, t0, y0, info().name, "explicit");
  reset_sub(*implicit_, *implicit_view_, t0, y0, info().name, "implicit");
}

// Each substep restarts its sub-integrator at the substep's (t, y): the other part changed y
// since the sub-integrator's last step, so its caches and history do not apply (header). A
// restart, not a reset: the structure analysed by reset() (patterns, symbolic factorisation,
// work vectors) is the same at every substep.
Status OperatorSplitting::explicit_substep(double t, VecRef y, double h, SolveStats& stats) {
  explicit_->restart(*explicit_view_, t, y);
  return explicit_->step(*explicit_view_, t, y, h, stats);
}

Status OperatorSplitting::implicit_substep(double t, VecRef y, double h, SolveStats& stats) {
  implicit_->restart(*implicit_view_, t, y);
  return implicit_->step(*implicit_view_, t, y, h, stats);
}

Status OperatorSplitting::step(const OdeSystem& sys, double t, VecRef y, double h,
                               SolveStats& stats) {
  if (&sys != sys_) throw std::logic_error("operator splitting: system differs from reset()");
  if (scheme_ == SplittingScheme::lie) {
    const Status st = explicit_substep(t, y, h, stats);
    if (st != Status::ok) return st;
    return implicit_substep(t, y, h, stats);
  }
  const double half = 0.5 * h;
  Status st = explicit_substep(t, y, half, stats);
  if (st != Status::ok) return st;
  st = implicit_substep(t, y, h, stats);
  if (st != Status::ok) return st;
  return explicit_substep(t + half, y, half, stats);
}

void register_splitting_integrators(IntegratorRegistry& reg) {
  for (const SplittingScheme scheme : {SplittingScheme::lie, SplittingScheme::strang}) {
    std::vector<ParamSpec> specs = {
        {"explicit", ParamType::text, "rk4",
         "fixed-step integrator (registered name, run with its defaults) that advances the "
         "explicit part f_E"},
        {"implicit", ParamType::text, "sdirk3",
         "fixed-step integrator (registered name, run with its defaults: Newton and linear "
         "solver options are not passed through) that advances the implicit part f_I"}};
    // The listed stage count is that of the default sub-integrators (registered before).
    const auto* e = reg.find("rk4");
    const auto* i = reg.find("sdirk3");
    const MethodInfo info = splitting_info(scheme, e ? e->info.stages : 0, i ? i->info.stages : 0);
    const IntegratorRegistry* r = &reg;
    add_built_in_integrator(
        reg, {info, std::move(specs), [r, scheme](const Params& p) -> std::unique_ptr<Integrator> {
                const std::string who = scheme_name(scheme);
                auto ex = make_sub(*r, who, "explicit", p.text("explicit"), true);
                auto im = make_sub(*r, who, "implicit", p.text("implicit"), false);
                return std::make_unique<OperatorSplitting>(scheme, std::move(ex), std::move(im));
              }});
  }
}

std::optional<LinearStability> OperatorSplitting::explicit_part_stability() const {
  auto ls = explicit_->linear_stability();
  if (!ls || scheme_ == SplittingScheme::lie) return ls;
  return substepped(*ls, 2);
}

std::optional<LinearStability> OperatorSplitting::partitioned_stability() const {
  // On x'' = a x + b x' with x' = v in f_I and the acceleration in f_E (and nothing else in f_I
  // on the test problem), I(τ) is the drift x ← x + τ v, exact for every consistent
  // sub-integrator (x is linear in t), and E(τ) advances v' = a x + b v with x frozen: a
  // one-step explicit method with R gives u ← R(τb) u + τ²a φ(τb) x (u = τ v, φ(z) = (R(z) − 1)/z,
  // the exact response of a one-step linear method to a constant forcing). So lie is the kick–drift
  // splitting (kick 1, drift 1) and strang (kick ½, drift 1, kick ½) with R-damped kicks; at
  // b = 0 they are symplectic Euler and velocity Verlet, whatever the explicit sub-integrator.
  const auto ls = explicit_->linear_stability();
  if (!ls || !ls->multiplier || ls->state_levels != 1) return std::nullopt;
  KickDriftCoefficients c;
  c.kick =
      scheme_ == SplittingScheme::lie ? std::vector<double>{1.0} : std::vector<double>{0.5, 0.5};
  c.drift =
      scheme_ == SplittingScheme::lie ? std::vector<double>{1.0} : std::vector<double>{1.0, 0.0};
  LinearStability s = kick_drift_stability(c);  // the half-trace at b = 0 (exact limit)
  s.kind =
      "partitioned splitting (x by the implicit part's drift, v by the explicit sub-integrator)";
  auto matrix = [c, r = ls->multiplier](double h2a, double hb) {
    double m00 = 1, m01 = 0, m10 = 0, m11 = 1;
    for (std::size_t j = 0; j < c.kick.size(); ++j) {
      const double z = c.kick[j] * hb;
      const double rz = r(std::complex<double>(z, 0.0)).real();
      const double phi = z == 0.0 ? 1.0 : (rz - 1.0) / z;
      const double n10 = c.kick[j] * h2a * phi * m00 + rz * m10;
      const double n11 = c.kick[j] * h2a * phi * m01 + rz * m11;
      m10 = n10;
      m11 = n11;
      m00 += c.drift[j] * m10;
      m01 += c.drift[j] * m11;
    }
    return std::array<double, 4>{m00, m01, m10, m11};
  };
  s.mechanical_amplification = [matrix](double h2a, double hb) {
    const auto m = matrix(h2a, hb);
    return spectral_radius_2x2(m[0], m[1], m[2], m[3]);
  };
  s.mechanical_multiplier = [matrix](double h2a, double hb) {
    const auto m = matrix(h2a, hb);
    return dominant_eigenvalue_2x2(m[0], m[1], m[2], m[3]);
  };
  return s;
}

}  // namespace stiffbench
