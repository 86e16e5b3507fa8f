#include "integrators/graphics/projective_dynamics.hpp"

#include <cmath>
#include <sstream>

#include "integrators/graphics/spring_requirements.hpp"
#include "integrators/method_entry.hpp"

namespace stiffbench {

std::vector<ParamSpec> projective_dynamics_param_specs() {
  return {{"iterations", ParamType::integer, "10",
           "local/global iterations per step (each: one projection of every spring, one "
           "prefactored solve per coordinate)",
           Bounds::in(1, 1000000)}};
}

ProjectiveDynamicsOptions read_projective_dynamics_options(const Params& p) {
  ProjectiveDynamicsOptions o;
  const long iterations = p.integer("iterations");
  require_input(iterations >= 1 && iterations <= 1000000,
                "projective_dynamics: parameter 'iterations' must be >= 1");
  o.iterations = static_cast<int>(iterations);
  return o;
}

namespace {
constexpr MethodText kProjectiveDynamicsText{
    .description =
        "projective dynamics / fast mass-spring (Liu, Bargteil, O'Brien & Kavan "
        "2013): local/global iterations of backward Euler, M + h^2 L factorised once "
        "per h; needs a spring network without dashpots",
    .kind = "local/global backward Euler",
    .reference =
        "T. Liu, A. W. Bargteil, J. F. O'Brien & L. Kavan, Fast simulation of "
        "mass-spring systems, ACM Trans. Graph. 32(6) (SIGGRAPH Asia 2013) 214"};
}  // namespace

ProjectiveDynamics::ProjectiveDynamics(ProjectiveDynamicsOptions opt)
    : Integrator(method_info("projective_dynamics", Family::graphics, 1, 0,
                             spring_network_requirements(), kProjectiveDynamicsText)),
      opt_(opt) {}

void ProjectiveDynamics::reset(const OdeSystem& sys, double /*t0*/, CVecRef y0) {
  check_compatible(info(), sys);
  net_ = sys.spring_network();
  if (net_->has_dashpots())
    throw BadInput(
        "integrator 'projective_dynamics' does not model spring dashpots "
        "(Liu et al. 2013 minimise the spring potential only); model '" +
        sys.name() +
        "' has springs with a dashpot coefficient > 0: set it to 0 (point damping "
        "is handled exactly) or use xpbd or an implicit method");
  const int dim = net_->dim;
  const Index np = net_->points();
  if (y0.size() != 2 * dim * np)
    throw std::logic_error("projective_dynamics: state size does not match the spring network");
  sys_ = &sys;
  // The structure is rebuilt for every run (a new system may reuse a freed one's address); the
  // factorisation is made on the first step and reused while h stays the same.
  row_of_.assign(static_cast<std::size_t>(np), -1);
  point_of_.clear();
  for (Index p = 0; p < np; ++p)
    if (!net_->pinned[static_cast<std::size_t>(p)]) {
      row_of_[static_cast<std::size_t>(p)] = static_cast<Index>(point_of_.size());
      point_of_.push_back(p);
    }
  const Index rows = static_cast<Index>(point_of_.size());
  links_.clear();
  std::vector<Eigen::Triplet<double>> trips;
  for (Index r = 0; r < rows; ++r) trips.emplace_back(r, r, 0.0);
  for (const SpringElement& s : net_->springs) {
    const Index ri = row_of_[static_cast<std::size_t>(s.i)];
    const Index rj = row_of_[static_cast<std::size_t>(s.j)];
    if (s.k == 0.0 || (ri < 0 && rj < 0)) continue;  // no force, or nothing moves
    links_.push_back({s.i, s.j, ri, rj, s.rest, s.k});
    if (ri >= 0) trips.emplace_back(ri, ri, s.k);
    if (rj >= 0) trips.emplace_back(rj, rj, s.k);
    if (ri >= 0 && rj >= 0) {
      trips.emplace_back(ri, rj, -s.k);
      trips.emplace_back(rj, ri, -s.k);
    }
  }
  laplacian_.resize(rows, rows);
  laplacian_.setFromTriplets(trips.begin(), trips.end());  // duplicates summed
  laplacian_.makeCompressed();
  matrix_ = laplacian_;
  diag_pos_.assign(static_cast<std::size_t>(rows), -1);
  for (Index c = 0; c < rows; ++c)
    for (Index k = laplacian_.outerIndexPtr()[c]; k < laplacian_.outerIndexPtr()[c + 1]; ++k)
      if (laplacian_.innerIndexPtr()[k] == c) diag_pos_[static_cast<std::size_t>(c)] = k;
  LinearSolverOptions lo;
  lo.kind = LinearSolverKind::ldlt;
  lo.symmetric = true;
  solver_ = make_linear_solver(lo, rows);
  solver_->analyze(matrix_);
  factored_h_ = 0.0;
  base_rhs_.resize(rows, dim);
  rhs_.resize(rows, dim);
  x_.resize(rows, dim);
}

bool ProjectiveDynamics::factor(double h) {
  // M̃ + h² L with M̃ = M + hγI (free points only).
  const double* l = laplacian_.valuePtr();
  double* a = matrix_.valuePtr();
  for (Index k = 0; k < laplacian_.nonZeros(); ++k) a[k] = h * h * l[k];
  for (std::size_t r = 0; r < point_of_.size(); ++r)
    a[diag_pos_[r]] += net_->mass[static_cast<std::size_t>(point_of_[r])] + h * net_->point_damping;
  if (!solver_->factor(matrix_)) return false;
  factored_h_ = h;
  return true;
}

Status ProjectiveDynamics::step(const OdeSystem& sys, double t, VecRef y, double h,
                                SolveStats& stats) {
  if (&sys != sys_) throw std::logic_error("ProjectiveDynamics::step: system differs from reset()");
  const int dim = net_->dim;
  const Index n = dim * net_->points();
  const Index rows = static_cast<Index>(point_of_.size());
  double* x = y.data();
  double* v = y.data() + n;
  if (h != factored_h_) {
    ++stats.linear_setups;
    if (!factor(h)) {
      std::ostringstream msg;
      msg << "projective_dynamics: M + h^2 L refused at t = " << t << ": " << solver_->error();
      stats.message = msg.str();
      return Status::solver_error;
    }
  }
  const double hg = h * net_->point_damping;
  for (Index r = 0; r < rows; ++r) {
    const Index p = point_of_[static_cast<std::size_t>(r)];
    const double m = net_->mass[static_cast<std::size_t>(p)];
    for (int c = 0; c < dim; ++c) {
      const double xc = x[dim * p + c];
      // M̃ s = M (x + h v + h² g) + hγ x; the first iterate is s.
      base_rhs_(r, c) =
          m * (xc + h * v[dim * p + c] + h * h * net_->gravity[static_cast<std::size_t>(c)]) +
          hg * xc;
      x_(r, c) = base_rhs_(r, c) / (m + hg);
    }
  }
  // Position of point p's coordinate c in the current iterate (pinned points stay at x).
  const auto pos = [&](Index p, Index r, int c) { return r >= 0 ? x_(r, c) : x[dim * p + c]; };
  const double h2 = h * h;
  for (int it = 0; it < opt_.iterations; ++it) {
    rhs_ = base_rhs_;
    for (const Link& s : links_) {
      double e[3] = {0.0, 0.0, 0.0};
      double l2 = 0.0;
      for (int c = 0; c < dim; ++c) {
        e[c] = pos(s.j, s.rj, c) - pos(s.i, s.ri, c);
        l2 += e[c] * e[c];
      }
      // Local step: d = L e/|e|, the closest vector of length L (0 when the ends coincide).
      const double scale = l2 > 0.0 ? s.rest / std::sqrt(l2) : 0.0;
      // Global right-hand side of ½ k |x_j - x_i - d|²: +h²k d in row j, -h²k d in row i, and
      // a pinned end's position moved over from the matrix.
      for (int c = 0; c < dim; ++c) {
        const double kd = h2 * s.k * scale * e[c];
        if (s.rj >= 0) rhs_(s.rj, c) += kd + (s.ri < 0 ? h2 * s.k * x[dim * s.i + c] : 0.0);
        if (s.ri >= 0) rhs_(s.ri, c) += -kd + (s.rj < 0 ? h2 * s.k * x[dim * s.j + c] : 0.0);
      }
    }
    for (int c = 0; c < dim; ++c) {
      const LinearSolveResult r = solver_->solve(rhs_.col(c), x_.col(c));
      ++stats.lin_solves;
      if (!r.ok) {
        stats.message = "projective_dynamics: solve failed: " + solver_->error();
        return Status::solver_error;
      }
    }
  }
  const double inv_h = 1.0 / h;
  for (Index r = 0; r < rows; ++r) {
    const Index p = point_of_[static_cast<std::size_t>(r)];
    for (int c = 0; c < dim; ++c) {
      v[dim * p + c] = (x_(r, c) - x[dim * p + c]) * inv_h;
      x[dim * p + c] = x_(r, c);
    }
  }
  return Status::ok;
}

}  // namespace stiffbench
