// A user's own ODE studied with stiffbench: the 1D Brusselator of Hairer & Wanner, Solving ODEs
// II, §IV.1 (N = 32, α = 1/50, t in [0, 10]), with an analytic sparse Jacobian, registered as a
// model and run through a convergence study (with a CVODE reference) and a work-precision study.
// The library has the same problem built in as the model `brusselator`; a model registered by a
// user needs a name of its own (a name registered twice is a std::logic_error).
// Usage: user_system [OUT_DIR]  (writes OUT_DIR/convergence/ and OUT_DIR/work_precision/).
#include <cmath>
#include <iostream>
#include <numbers>
#include <stiffbench/stiffbench.hpp>

using namespace stiffbench;

// y = (u_1, v_1, ..., u_N, v_N); boundary values u = 1, v = 3.
class Brusselator final : public OdeSystem {
 public:
  explicit Brusselator(int n) : n_(n), c_((n + 1.0) * (n + 1.0) / 50.0) {}
  std::string name() const override { return "my_brusselator"; }
  Index dimension() const override { return 2 * n_; }
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  Vec initial_state() const override {
    Vec y(2 * n_);
    for (int i = 0; i < n_; ++i)
      y.segment<2>(2 * i) << 1 + std::sin(2 * std::numbers::pi * (i + 1.0) / (n_ + 1.0)), 3;
    return y;
  }
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    for (int i = 0; i < n_; ++i) {
      const double u = y[2 * i], v = y[2 * i + 1], uuv = u * u * v;
      const double ul = i > 0 ? y[2 * i - 2] : 1, ur = i < n_ - 1 ? y[2 * i + 2] : 1;
      const double vl = i > 0 ? y[2 * i - 1] : 3, vr = i < n_ - 1 ? y[2 * i + 3] : 3;
      f[2 * i] = 1 + uuv - 4 * u + c_ * (ul - 2 * u + ur);
      f[2 * i + 1] = 3 * u - uuv + c_ * (vl - 2 * v + vr);
    }
  }
  void eval_jacobian(double, CVecRef y, SparseMat& jac) const override {
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n_; ++i) {
      const double u = y[2 * i], v = y[2 * i + 1];
      t.insert(t.end(), {{2 * i, 2 * i, 2 * u * v - 4 - 2 * c_}, {2 * i, 2 * i + 1, u * u}});
      t.insert(t.end(),
               {{2 * i + 1, 2 * i, 3 - 2 * u * v}, {2 * i + 1, 2 * i + 1, -u * u - 2 * c_}});
      for (int k : {2 * i - 2, 2 * i + 2})  // the neighbours' u and v (diffusion)
        if (k >= 0 && k < 2 * n_) t.insert(t.end(), {{2 * i, k, c_}, {2 * i + 1, k + 1, c_}});
    }
    jac.resize(2 * n_, 2 * n_);
    jac.setFromTriplets(t.begin(), t.end());
  }

 private:
  int n_;
  double c_;  // α (N+1)²
};

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "results";
  register_model(
      {{"my_brusselator", "1D Brusselator, Hairer-Wanner II IV.1", false, false, "HW II"},
       {{"n", ParamType::integer, "32", "grid points"}},
       [](const Params& p) {
         return std::make_unique<Brusselator>(static_cast<int>(p.integer("n")));
       }});
  ConvergenceSpec conv;
  conv.model = "my_brusselator";
  conv.integrators = {"backward_euler", "sdirk3", "bdf2"};
  conv.t_end = 10;
  conv.h = 0.1;
  conv.levels = 5;
  conv.reference = "cvode_bdf";
  convergence_study(conv, out + "/convergence", false, &std::cerr, std::cerr);
  WorkPrecisionSpec wp;
  wp.model = "my_brusselator";
  wp.integrators = {"sdirk3", "radau5", "cvode_bdf"};
  wp.t_end = 10;
  wp.h = 0.05;
  wp.levels = 4;
  wp.tol_levels = 4;
  wp.rtol_max = 1e-4;
  const auto res = work_precision_study(wp, out + "/work_precision", &std::cerr, std::cerr);
  std::cout << work_precision_table(res).to_markdown();
}
