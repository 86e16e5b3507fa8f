#include "experiments/studies/fidelity_modes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "core/driver.hpp"
#include "experiments/output/progress.hpp"

namespace stiffbench::fidelity_internal {

namespace {

ModalBasis modal_basis(const StudyInputs& in, const MechanicalSystem& mech,
                       const FidelitySpec& spec) {
  const std::string who = "fidelity --model " + spec.model + ": ";
  require_input(mech.has_force_jacobians(),
                who + "needs the force Jacobian K = da/dx (the model has none)");
  ModalBasis b;
  const Vec y0 = mech.initial_state();
  const Index n = mech.dofs();
  b.x0 = y0.head(n);
  const Vec v0 = Vec::Zero(n);
  std::set<Index> fixed;
  for (Index i : mech.fixed_dofs()) fixed.insert(i);
  for (Index i = 0; i < n; ++i)
    if (!fixed.count(i)) b.free.push_back(i);
  const Index m = static_cast<Index>(b.free.size());
  require_input(m <= 4000, who +
                               "the dense modal analysis is limited to 4000 free dofs (the "
                               "model has " +
                               std::to_string(m) + ")");
  SparseMat k, d;
  mech.force_jacobians(0.0, b.x0, v0, k, d);
  require_input(d.norm() == 0.0, who +
                                     "the model is damped at rest (D = da/dv != 0): the "
                                     "modal curves are those of the undamped oscillator; "
                                     "switch its damping off");
  Vec yr(2 * n);
  yr << b.x0, v0;
  Vec f(2 * n);
  mech.rhs(0.0, yr, f);
  const double acc = f.tail(n).cwiseAbs().maxCoeff();
  const Mat kd = Mat(k);
  const double scale = (kd * b.x0).cwiseAbs().maxCoeff() + kd.cwiseAbs().maxCoeff();
  std::string rest;
  for (const auto& [key, value] : in.model_entry().info.rest_state)
    rest += (rest.empty() ? "" : ", ") + key + "=" + value;
  require_input(
      acc <= 1e-9 * std::max(scale, 1.0),
      who + "the initial state is not at rest (max |a| = " + format_short(acc) +
          "): the modes are those of an equilibrium; start the model at rest by "
          "setting what loads or displaces it to 0 (" +
          (rest.empty() ? "gravity, perturbation, an excited mode" : "its rest state: " + rest) +
          ")");
  const Vec masses = mech.masses();
  b.mass.resize(m);
  Mat a(m, m);
  for (Index i = 0; i < m; ++i) {
    b.mass(i) = masses(b.free[static_cast<std::size_t>(i)]);
    for (Index j = 0; j < m; ++j)
      a(i, j) = -kd(b.free[static_cast<std::size_t>(i)], b.free[static_cast<std::size_t>(j)]);
  }
  // −M K is symmetric for forces with a potential; symmetrise against round-off, then solve
  // the symmetric problem S ψ = ω² ψ with S = M^{1/2}(−K)M^{-1/2}, φ = M^{-1/2} ψ.
  const Vec sq = b.mass.cwiseSqrt();
  Mat s = sq.asDiagonal() * a * sq.cwiseInverse().asDiagonal();
  s = 0.5 * (s + s.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Mat> es(s);
  require_input(es.info() == Eigen::Success, who + "the eigensolver failed");
  const double top = std::max(es.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
  b.omega_max = std::sqrt(std::max(es.eigenvalues().maxCoeff(), 0.0));
  std::vector<Index> chosen;
  for (Index i = 0; i < m && static_cast<int>(chosen.size()) < spec.modes; ++i)
    if (es.eigenvalues()(i) > 1e-12 * top) chosen.push_back(i);
  require_input(!chosen.empty(), who + "no mode with omega > 0");
  b.phi.resize(m, static_cast<Index>(chosen.size()));
  b.omega.resize(static_cast<Index>(chosen.size()));
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    b.phi.col(static_cast<Index>(c)) =
        sq.cwiseInverse().asDiagonal() * es.eigenvectors().col(chosen[c]);
    b.omega(static_cast<Index>(c)) = std::sqrt(es.eigenvalues()(chosen[c]));
  }
  return b;
}

// The per-mode runs of one integrator at one step.
void measure_modes(const MechanicalSystem& mech, const ModalBasis& b, Integrator& integ,
                   const std::string& name, double h, const FidelitySpec& spec,
                   FidelityResult& out) {
  const Index n = mech.dofs(), nm = b.phi.cols();
  const Vec y0 = mech.initial_state();
  const double mean = b.x0.mean();
  const double spread = std::sqrt((b.x0.array() - mean).square().mean());
  const double eps = spec.amplitude * (spread > 0 ? spread : 1.0);
  Vec start = y0;
  start.tail(n).setZero();
  for (Index c = 0; c < nm; ++c) {
    const double inf = b.phi.col(c).cwiseAbs().maxCoeff();
    for (std::size_t i = 0; i < b.free.size(); ++i)
      start(b.free[i]) += eps * b.phi(static_cast<Index>(i), c) / inf;
  }
  std::vector<std::vector<double>> q(static_cast<std::size_t>(nm)), p(static_cast<std::size_t>(nm));
  FixedStepOptions fopt;
  fopt.h = h;
  fopt.t_end = h * static_cast<double>(spec.mode_steps);
  fopt.outputs = spec.mode_steps;
  fopt.blowup_factor = 1e100;
  Vec dx(static_cast<Index>(b.free.size())), v(static_cast<Index>(b.free.size()));
  const RunResult res = run_fixed_step_from(mech, integ, 0.0, start, fopt, [&](double, CVecRef y) {
    for (std::size_t i = 0; i < b.free.size(); ++i) {
      dx(static_cast<Index>(i)) = y(b.free[i]) - b.x0(b.free[i]);
      v(static_cast<Index>(i)) = y(n + b.free[i]);
    }
    const Vec mq = b.phi.transpose() * b.mass.cwiseProduct(dx);
    const Vec mp = b.phi.transpose() * b.mass.cwiseProduct(v);
    for (Index c = 0; c < nm; ++c) {
      q[static_cast<std::size_t>(c)].push_back(mq(c));
      p[static_cast<std::size_t>(c)].push_back(mp(c));
    }
  });
  const auto stab = integ.linear_stability();
  for (Index c = 0; c < nm; ++c) {
    ModePoint mp;
    mp.integrator = name;
    mp.h = h;
    mp.mode = static_cast<int>(c + 1);
    mp.omega = b.omega(c);
    const double nu = h * mp.omega;
    if (stab) mp.predicted = oscillator_response(*stab, nu);
    // The order of the recurrence is known for methods with stability data (2 × the state
    // state_levels); the fit is then least squares over the nonlinear and solver noise of the run.
    const int state_levels = stab ? stab->state_levels : 0;
    if (res.stats.status != Status::ok) {
      mp.note = "run " + to_string(res.stats.status) +
                " at this h (nu = " + format_short(h * b.omega_max) +
                " on the fastest mode of the system)";
    } else {
      const RecurrenceFit fit =
          fit_step_multiplier({q[static_cast<std::size_t>(c)], p[static_cast<std::size_t>(c)]},
                              2 * std::max(state_levels, 1), 1e-4, 2 * state_levels);
      if (fit.ok)
        mp.measured = oscillator_response(fit.multiplier, nu);
      else
        mp.note = fit.reason;
    }
    if (!stab) mp.note += (mp.note.empty() ? "" : "; ") + std::string("no stability data");
    out.modes.push_back(std::move(mp));
  }
}

}  // namespace

ModalSetup prepare_modes(const StudyInputs& in, const FidelitySpec& spec) {
  ModalSetup m;
  m.setup = make_setup(in, in.integrators, spec.params);
  m.mech = dynamic_cast<const MechanicalSystem*>(m.setup.model.get());
  require_input(m.mech != nullptr, "fidelity --model " + spec.model +
                                       ": per-mode analysis needs a mechanical model (y = [x; v])");
  m.basis = modal_basis(in, *m.mech, spec);
  return m;
}

void run_modes(const StudyInputs& in, const FidelitySpec& spec, const ModalSetup& m,
               FidelityResult& out, std::ostream* progress) {
  const ModalBasis& b = m.basis;
  std::vector<double> hs = spec.h;
  const double top = b.omega(b.omega.size() - 1);
  if (hs.empty()) hs = {0.1 / b.omega(0), 2.0 / top};
  out.mode_steps_used = hs;
  Progress prog(progress, "fidelity modes", static_cast<long>(hs.size() * spec.integrators.size()));
  for (std::size_t i = 0; i < spec.integrators.size(); ++i) {
    for (double h : hs) {
      auto integ = in.create_integrator(spec.integrators[i], spec.params);
      measure_modes(*m.mech, b, *integ, spec.integrators[i], h, spec, out);
      prog.tick(spec.integrators[i] + ", h = " + format_short(h));
    }
  }
}

}  // namespace stiffbench::fidelity_internal
