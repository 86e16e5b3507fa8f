// A user's own system and a user's own integrator, studied with stiffbench's one-call study
// functions and nothing registered by name: a stiff pair of undamped springs (frequencies 1 and
// 50, the classic split between a slow motion of interest and a fast stiff mode) integrated by
// Ralston's third-order Runge-Kutta method (Ralston 1962, Math. Comp. 16: 431-437) beside rk4 and
// CVODE, through convergence, stability, energy drift and work-precision. The system also splits
// additively, f = f_E + f_I (slow spring explicit, stiff spring implicit): the parts as systems
// of their own (explicit_part_view, implicit_part_view) and an IMEX method at a step beyond rk4's
// limit on the stiff mode.
// Usage: user_method [OUT_DIR]   (writes OUT_DIR/{convergence,stability,energy,work_precision}/)
#include <cmath>
#include <iostream>
#include <stiffbench/stiffbench.hpp>

using namespace stiffbench;

// y = (x1, x2, v1, v2), x_i'' = -w_i^2 x_i with w = (1, 50), from x = (1, 0.01), v = 0.
class StiffSprings final : public OdeSystem {
 public:
  std::string name() const override { return "stiff_springs"; }
  Index dimension() const override { return 4; }
  bool autonomous() const override { return true; }
  Vec initial_state() const override {
    Vec y(4);
    y << 1, 0.01, 0, 0;
    return y;
  }
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f << y[2], y[3], -w_[0] * w_[0] * y[0], -w_[1] * w_[1] * y[1];
  }
  bool has_jacobian() const override { return true; }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override {
    std::vector<Eigen::Triplet<double>> t = {
        {0, 2, 1.0}, {1, 3, 1.0}, {2, 0, -w_[0] * w_[0]}, {3, 1, -w_[1] * w_[1]}};
    jac.resize(4, 4);
    jac.setFromTriplets(t.begin(), t.end());
  }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override {
    const Vec y0 = initial_state();
    for (int i = 0; i < 2; ++i) {
      y[i] = y0[i] * std::cos(w_[i] * t);
      y[2 + i] = -y0[i] * w_[i] * std::sin(w_[i] * t);
    }
  }
  // Additive split: f_E = (v1, 0, -w1² x1, 0) (the slow spring), f_I = (0, v2, 0, -w2² x2) (the
  // stiff one, with its Jacobian J_I).
  bool has_imex_split() const override { return true; }
  bool has_implicit_part_jacobian() const override { return true; }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef f) const override {
    f << y[2], 0, -w_[0] * w_[0] * y[0], 0;
  }
  void eval_rhs_implicit_part(double, CVecRef y, VecRef f) const override {
    f << 0, y[3], 0, -w_[1] * w_[1] * y[1];
  }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    std::vector<Eigen::Triplet<double>> t = {{1, 3, 1.0}, {3, 1, -w_[1] * w_[1]}};
    jac.resize(4, 4);
    jac.setFromTriplets(t.begin(), t.end());
  }
  std::vector<Invariant> invariants() const override {
    return {{"energy", [this](double, CVecRef y) {
               double e = 0;
               for (int i = 0; i < 2; ++i)
                 e += 0.5 * y[2 + i] * y[2 + i] + 0.5 * w_[i] * w_[i] * y[i] * y[i];
               return e;
             }}};
  }

 private:
  double w_[2] = {1.0, 50.0};
};

// Ralston's third-order method: c = (0, 1/2, 3/4), b = (2/9, 1/3, 4/9).
class Ralston3 final : public Integrator {
 public:
  static MethodInfo method_info() {
    MethodInfo m;
    m.name = "ralston3";
    m.family = Family::explicit_rk;
    m.order = 3;
    m.stages = 3;
    m.description = "Ralston's third-order Runge-Kutta method (a user's own class)";
    m.kind = "explicit Runge-Kutta";
    m.reference = "Ralston 1962, Math. Comp. 16";
    return m;
  }
  Ralston3() : Integrator(method_info()) {}
  void reset(const OdeSystem& sys, double, CVecRef) override {
    check_compatible(info(), sys);
    const Index n = sys.dimension();
    k1_.resize(n), k2_.resize(n), k3_.resize(n), tmp_.resize(n);
  }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) override {
    sys.rhs(t, y, k1_);
    tmp_ = y + 0.5 * h * k1_;
    sys.rhs(t + 0.5 * h, tmp_, k2_);
    tmp_ = y + 0.75 * h * k2_;
    sys.rhs(t + 0.75 * h, tmp_, k3_);
    y += h * (2.0 / 9.0 * k1_ + 1.0 / 3.0 * k2_ + 4.0 / 9.0 * k3_);
    return Status::ok;
  }

 private:
  Vec k1_, k2_, k3_, tmp_;
};

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "results";
  // The objects: fresh copies for every run; results carry their names.
  const StudyObjects mine{[] { return std::make_unique<StiffSprings>(); },
                          {[] { return std::make_unique<Ralston3>(); }}};
  StudyContext ctx;  // settings of the pipeline: progress and notes to stderr, plots as PNG
  ctx.progress = &std::cerr;
  ctx.err = &std::cerr;
  ctx.out = &std::cout;

  ConvergenceSpec conv;  // exact reference: the system has one
  conv.integrators = {"rk4"};
  conv.t_end = 1;
  conv.h = 0.004;  // h*w from 0.2 down to 0.00625 on the stiff mode: the asymptotic range
  conv.levels = 6;
  const ConvergenceResult c =
      convergence_study(inputs_of(conv, mine), conv, out + "/convergence", false, ctx);

  // rk4 by name and the objects, resolved once into the inputs the next two studies run on.
  const StudyInputs in = resolve_inputs(StudyTarget{.integrators = {"rk4"}, .objects = mine});
  // Largest stable step of each method on the w = 50 mode.
  const StabilityResult s = stability_study(in, StabilitySpec{}, out + "/stability", ctx);

  EnergySpec energy;  // relative energy error of long fixed-step runs
  energy.h = 0.01;
  energy.t_end = 100;
  energy_study(in, energy, out + "/energy", ctx);

  WorkPrecisionSpec wp;  // error against f evaluations; CVODE over a tolerance ladder
  wp.integrators = {"rk4", "cvode_bdf"};
  wp.t_end = 1;
  wp.h = 0.01;
  wp.levels = 4;
  wp.tol_levels = 4;
  wp.repeats = 1;
  work_precision_study(inputs_of(wp, mine), wp, out + "/work_precision", ctx);

  // What theory says of ralston3: order 3 (the observed order of the finest pair), and, like every
  // three-stage third-order method, R(z) = 1 + z + z^2/2 + z^3/6 with |R(iy)| <= 1 exactly for
  // |y| <= sqrt(3), so h_max = sqrt(3)/50 on the w = 50 mode (measured a little above: a probe is
  // unstable once the norm grows tenfold over the horizon, about 0.2% past the limit here).
  double order = 0, h_max = 0;
  for (const auto& r : c.rows)
    if (r.integrator == "ralston3" && r.observed_order) order = *r.observed_order;
  for (const auto& r : s.rows)
    if (r.integrator == "ralston3" && r.h_measured) h_max = *r.h_measured;
  // The split through the public header (core/split_views.hpp): each component of f lies in one
  // part and is 0 in the other, so f_E + f_I = f exactly. ars232 (Ascher, Ruuth & Spiteri 1997:
  // an L-stable SDIRK for f_I, explicit for f_E) at h = 0.1, where h w2 = 5 is beyond rk4's
  // imaginary-axis limit 2.83: stable, the stiff spring damped, and the slow one at t = 1 within
  // the method's second-order error of cos 1 (h² = 0.01 bounds it; a run at h/2 is 4 times
  // closer). Its tables meet the additive order conditions (core/theory/additive_conditions.hpp) to
  // order 2 and not 3.
  StiffSprings springs;
  const Vec y0 = springs.initial_state();
  Vec fe(4), fi(4), f(4);
  explicit_part_view(springs)->rhs(0.0, y0, fe);
  implicit_part_view(springs)->rhs(0.0, y0, fi);
  springs.rhs(0.0, y0, f);
  const bool parts_add_up = fe + fi == f;
  double imex_error[2];
  for (int k = 0; k < 2; ++k) {
    auto ars = integrator_registry().create("ars232", Params{});
    const RunResult r = run_fixed_step(springs, *ars, {1.0, 0.1 / (k + 1)});
    imex_error[k] = r.stats.status == Status::ok ? std::abs(r.y[0] - std::cos(1.0)) : 1.0;
  }
  auto ars = integrator_registry().create("ars232", Params{});
  const AdditiveTableau& tab = *ars->additive_tableau();
  const int additive_order = additive_satisfied_order(
      tab.explicit_table, tab.implicit_table, tab.explicit_table.b, tab.implicit_table.b, 4);
  const bool split_ok = parts_add_up && imex_error[0] < 0.01 &&
                        std::abs(imex_error[0] / imex_error[1] - 4) < 0.5 && additive_order == 2;
  std::cout << "split: f_E + f_I = f " << (parts_add_up ? "exactly" : "NOT") << "; ars232 at h = "
            << "0.1, 0.05: |x1 - cos 1| = " << imex_error[0] << ", " << imex_error[1]
            << "; additive order " << additive_order << "\n";
  std::cout << "ralston3: observed order " << order << ", h_max " << h_max << "\n";
  return std::abs(order - 3) < 0.2 && std::abs(h_max * 50 - std::sqrt(3.0)) < 0.02 && split_ok ? 0
                                                                                               : 1;
}
