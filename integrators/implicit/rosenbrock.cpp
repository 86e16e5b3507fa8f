#include "integrators/implicit/rosenbrock.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "integrators/method_entry.hpp"
#include "integrators/method_file.hpp"

namespace stiffbench {

constexpr MethodText kSemiImplicitEulerText{
    .description = "linearly implicit Euler (I - hJ) dy = h f(t, y): one linear solve, no Newton",
    .kind = "linearly implicit",
    .reference = cite(kHairerWanner, "Sect. IV.9")};

SemiImplicitEuler::SemiImplicitEuler(ImplicitOptions opt)
    : Integrator(
          method_info("semi_implicit_euler", Family::implicit, 1, 1, {}, kSemiImplicitEulerText)),
      core_(std::move(opt)) {}

void SemiImplicitEuler::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  for (Vec* v : {&f_, &dy_, &ft_, &rhs_}) v->resize(sys.dimension());
}

void SemiImplicitEuler::restart(const OdeSystem& sys, double t, CVecRef y) {
  if (core_.system() != &sys) return reset(sys, t, y);
  core_.restart();  // its only state: every step evaluates J and factorises anew
}

Status SemiImplicitEuler::step(const OdeSystem& sys, double t, VecRef y, double h,
                               SolveStats& stats) {
  sys.rhs(t, y, f_);
  core_.update_jacobian(sys, t, y, f_, stats);
  if (!core_.prepare(h, stats)) {
    stats.message = "I - hJ at t = " + std::to_string(t) + " refused: " + core_.error();
    return Status::solver_error;
  }
  // Non-autonomous f: the method applied to the autonomised system (t' = 1) adds h² f_t, so a
  // stiff forced problem tracks its slow solution (without it y⁺ lags φ by h φ').
  rhs_ = h * f_;
  if (!sys.autonomous()) {
    const double dt = 1.4901161193847656e-08 * std::max(1.0, std::abs(t));
    sys.rhs(t + dt, y, ft_);
    rhs_.noalias() += (h * h / dt) * (ft_ - f_);
  }
  dy_.setZero();
  if (!core_.solve(rhs_, dy_, stats)) {
    stats.message = "linear solve failed at t = " + std::to_string(t);
    return Status::solver_error;
  }
  y += dy_;
  return Status::ok;
}

namespace {

// Rooted trees with at most 6 vertices, as the list of the root's subtrees (indices into the
// list, non-decreasing), each with its order and density γ(τ) = |τ| Π γ(children).
struct RootedTree {
  int order;
  std::vector<int> children;
  double density;
};

const std::vector<RootedTree>& rooted_trees() {
  static const std::vector<RootedTree> trees = [] {
    std::vector<RootedTree> t{{1, {}, 1.0}};
    for (int n = 2; n <= 6; ++n) {
      const int before = static_cast<int>(t.size());
      std::vector<int> pick;
      // Root plus a non-decreasing list of earlier trees whose orders sum to n - 1.
      const auto rec = [&](const auto& self, int remaining, int min_index) -> void {
        if (remaining == 0) {
          double g = n;
          for (int c : pick) g *= t[static_cast<std::size_t>(c)].density;
          t.push_back({n, pick, g});
          return;
        }
        for (int i = min_index; i < before; ++i) {
          const int o = t[static_cast<std::size_t>(i)].order;
          if (o > remaining) continue;
          pick.push_back(i);
          self(self, remaining - o, i);
          pick.pop_back();
        }
      };
      rec(rec, n - 1, 0);
    }
    return t;
  }();
  return trees;
}

// Stage i reuses the f value of the first earlier stage with the same argument: the same row of
// α (arguments are y + Σ α_ij k_j, at t + α_i h with α_i the row sum).
std::vector<Index> shared_stages(const RosenbrockTableau& t) {
  std::vector<Index> same(static_cast<std::size_t>(t.stages()));
  for (Index i = 0; i < t.stages(); ++i) {
    same[static_cast<std::size_t>(i)] = i;
    for (Index j = 0; j < i; ++j)
      if (t.alpha.row(i) == t.alpha.row(j)) {
        same[static_cast<std::size_t>(i)] = j;
        break;
      }
  }
  return same;
}

int distinct_evaluations(const RosenbrockTableau& t) {
  const std::vector<Index> same = shared_stages(t);
  int n = 0;
  for (std::size_t i = 0; i < same.size(); ++i) n += same[i] == static_cast<Index>(i);
  return n;
}

}  // namespace

Mat RosenbrockTableau::gamma_full() const {
  return gamma_lower + gamma * Mat::Identity(stages(), stages());
}

double RosenbrockTableau::order_defect(const Vec& weights, int p) const {
  if (p < 1 || p > 6) throw std::logic_error("RosenbrockTableau::order_defect: order in 1..6");
  const Mat beta = alpha + gamma_full();
  const auto& trees = rooted_trees();
  std::vector<Vec> phi;
  phi.reserve(trees.size());
  double worst = 0.0;
  for (const RootedTree& t : trees) {
    Vec v = Vec::Ones(stages());
    if (t.children.size() == 1)
      v = beta * phi[static_cast<std::size_t>(t.children[0])];
    else
      for (int c : t.children) v = v.cwiseProduct(alpha * phi[static_cast<std::size_t>(c)]);
    phi.push_back(v);
    if (t.order == p) worst = std::max(worst, std::abs(weights.dot(v) - 1.0 / t.density));
  }
  return worst;
}

RosenbrockTransformed transform(const RosenbrockTableau& t) {
  const Index s = t.stages();
  const Mat ginv = t.gamma_full().triangularView<Eigen::Lower>().solve(Mat::Identity(s, s));
  RosenbrockTransformed r;
  r.a = t.alpha * ginv;
  r.c = Mat(Vec::Constant(s, 1.0 / t.gamma).asDiagonal()) - ginv;
  r.c.diagonal().setZero();  // exactly 0 (1/γ - 1/γ)
  r.a.triangularView<Eigen::Upper>().setZero();
  r.c.triangularView<Eigen::Upper>().setZero();
  r.m = ginv.transpose() * t.b;
  if (t.b_embedded.size() == s) r.m_embedded = ginv.transpose() * t.b_embedded;
  r.alpha_sum = t.alpha.rowwise().sum();
  r.gamma_sum = t.gamma_full().rowwise().sum();
  return r;
}

RosenbrockTableau rosenbrock_from_transformed(std::string name, int order, int embedded_order,
                                              double gamma, const Mat& a, const Mat& c,
                                              const Vec& m, const Vec& m_embedded) {
  const Index s = m.size();
  Mat ginv = Mat(Vec::Constant(s, 1.0 / gamma).asDiagonal()) - c;
  ginv.diagonal().setConstant(1.0 / gamma);
  const Mat g = ginv.triangularView<Eigen::Lower>().solve(Mat::Identity(s, s));
  RosenbrockTableau r;
  r.name = std::move(name);
  r.order = order;
  r.embedded_order = embedded_order;
  r.gamma = gamma;
  r.alpha = a * g;
  r.alpha.triangularView<Eigen::Upper>().setZero();
  r.gamma_lower = g;
  r.gamma_lower.triangularView<Eigen::Upper>().setZero();  // the diagonal is γ
  r.b = g.transpose() * m;
  r.b_embedded = g.transpose() * m_embedded;
  return r;
}

const RosenbrockTableau& rosenbrock2_tableau() { return built_in_method("rosenbrock2").rosenbrock; }
const RosenbrockTableau& ros3p_tableau() { return built_in_method("ros3p").rosenbrock; }
const RosenbrockTableau& rodas4_tableau() { return built_in_method("rodas4").rosenbrock; }

Rosenbrock::Rosenbrock(RosenbrockTableau tableau, std::string description, ImplicitOptions opt,
                       ControllerOptions control)
    : Integrator({tableau.name,
                  Family::implicit,
                  tableau.order,
                  distinct_evaluations(tableau),
                  {},
                  std::move(description)}),
      tab_(std::move(tableau)),
      tr_(transform(tab_)),
      same_as_(shared_stages(tab_)),
      core_(std::move(opt)),
      control_(control),
      ctrl_(control, tab_.embedded_order + 1) {
  const Index s = tab_.stages();
  if (tab_.b_embedded.size() == s) m_diff_ = tr_.m - tr_.m_embedded;
}

void Rosenbrock::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  const Index n = sys.dimension();
  u_.resize(n, tab_.stages());
  fs_.resize(n, tab_.stages());
  for (Vec* v : {&ft_, &arg_, &rhs_, &ynew_, &err_}) v->resize(n);
  need_ft_ = !sys.autonomous();
  restart_state(t0);
}

void Rosenbrock::restart(const OdeSystem& sys, double t, CVecRef y) {
  if (core_.system() != &sys) return reset(sys, t, y);
  core_.restart();
  restart_state(t);
}

void Rosenbrock::restart_state(double t0) {
  t_ = t0;
  h_ = 0.0;
  lin_valid_ = false;
  counts_ = {};
  ctrl_.reset();
}

void Rosenbrock::linearise(const OdeSystem& sys, double t, CVecRef y, SolveStats& stats) {
  sys.rhs(t, y, fs_.col(0));
  core_.update_jacobian(sys, t, y, fs_.col(0), stats);
  if (need_ft_) {
    // f_t = (-3 f(t) + 4 f(t + δ) - f(t + 2δ)) / (2δ) + O(δ²) with δ = max(ε^⅓, ε^⅔ |t|) (see
    // the header): ε^⅓ balances truncation and round-off on an O(1) time scale; the second term
    // keeps δ a million ulps of t when |t| is large.
    const double t1 = t + std::max(6.0554544523933395e-06, 3.6668528625997858e-11 * std::abs(t));
    const double dt = t1 - t;  // representable
    sys.rhs(t1, y, ft_);
    sys.rhs(t + 2.0 * dt, y, rhs_);
    ft_ = (4.0 * ft_ - 3.0 * fs_.col(0) - rhs_) / (2.0 * dt);
  }
}

bool Rosenbrock::stages(const OdeSystem& sys, double t, CVecRef y, double h, bool estimate,
                        SolveStats& stats) {
  const Index s = tab_.stages();
  const double g = tab_.gamma;
  for (Index i = 0; i < s; ++i) {
    const Index same = same_as_[static_cast<std::size_t>(i)];
    if (same == i && i > 0) {
      arg_ = y;
      for (Index j = 0; j < i; ++j)
        if (const double a = tr_.a(i, j); a != 0.0) arg_.noalias() += a * u_.col(j);
      sys.rhs(t + tr_.alpha_sum[i] * h, arg_, fs_.col(i));
    }
    // (I - hγJ) u_i = hγ f_i + γ Σ c_ij u_j + γ γ_i h² f_t.
    rhs_ = (h * g) * fs_.col(same);
    for (Index j = 0; j < i; ++j)
      if (const double c = tr_.c(i, j); c != 0.0) rhs_.noalias() += (g * c) * u_.col(j);
    if (need_ft_ && tr_.gamma_sum[i] != 0.0) rhs_.noalias() += (g * tr_.gamma_sum[i] * h * h) * ft_;
    auto ui = u_.col(i);
    ui.setZero();
    if (!core_.solve(rhs_, ui, stats)) {
      stats.message = tab_.name + ": linear solve failed at t = " + std::to_string(t) + " (" +
                      core_.error() + ")";
      return false;
    }
  }
  ynew_ = y;
  for (Index i = 0; i < s; ++i)
    if (const double m = tr_.m[i]; m != 0.0) ynew_.noalias() += m * u_.col(i);
  if (estimate) {
    err_.setZero();
    for (Index i = 0; i < s; ++i)
      if (const double d = m_diff_[i]; d != 0.0) err_.noalias() += d * u_.col(i);
  }
  return true;
}

Status Rosenbrock::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  linearise(sys, t, y, stats);
  if (!core_.prepare(h * tab_.gamma, stats)) {
    stats.message = "I - hγJ at t = " + std::to_string(t) + " refused: " + core_.error();
    return Status::solver_error;
  }
  if (!stages(sys, t, y, h, false, stats)) return Status::solver_error;
  y = ynew_;
  return Status::ok;
}

Status Rosenbrock::advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) {
  if (!supports_adaptive()) return Integrator::advance_to(sys, t_out, y, stats);
  if (h_ == 0.0) {
    // The starting-step heuristic needs f(t0, y0): it is also the first trial's stage 1.
    if (!lin_valid_) {
      linearise(sys, t_, y, stats);
      lin_valid_ = true;
    }
    h_ = control_.h0 > 0 ? std::min(control_.h0, t_out - t_)
                         : ctrl_.initial_step(sys, t_, y, fs_.col(0), tab_.embedded_order,
                                              t_out - t_, arg_, rhs_);
  }
  const auto trial = [&](double t, double h) {
    if (!lin_valid_) {
      linearise(sys, t, y, stats);
      lin_valid_ = true;
    }
    if (!core_.prepare(h * tab_.gamma, stats)) return TrialResult{0.0, 0.5};
    if (!stages(sys, t, y, h, true, stats) || !ynew_.allFinite()) return TrialResult{0.0, 0.5};
    return TrialResult{ctrl_.norm(err_, y, ynew_), 0.0};
  };
  const auto commit = [&](double, double) {
    y = ynew_;
    lin_valid_ = false;
  };
  const Status st =
      advance_adaptive(ctrl_, t_, t_out, h_, y, counts_, stats.message, trial, commit);
  stats.steps = counts_.accepted;
  stats.error_test_failures = counts_.rejected;
  return st;
}

}  // namespace stiffbench
