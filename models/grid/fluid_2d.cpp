#include "models/grid/fluid_2d.hpp"
#include "models/grid/grid_entry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace stiffbench {

namespace {

using Triplet = Eigen::Triplet<double>;

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

int wrap(int i, int n) { return ((i % n) + n) % n; }

// Catmull–Rom weights of the nodes -1, 0, 1, 2 at fraction a ∈ [0, 1): the cubic through the
// four values with central-difference slopes at 0 and 1 (exact for quadratics).
void catmull_rom(double a, double w[4]) {
  const double a2 = a * a, a3 = a2 * a;
  w[0] = 0.5 * (-a + 2 * a2 - a3);
  w[1] = 0.5 * (2 - 5 * a2 + 3 * a3);
  w[2] = 0.5 * (a + 4 * a2 - 3 * a3);
  w[3] = 0.5 * (-a2 + a3);
}

}  // namespace

Fluid2d::Fluid2d(const Fluid2dOptions& options) : opt_(options) {
  require_input(options.n >= 4 && options.n <= 2048,
                "fluid_2d: parameter 'n' must be in [4, 2048]");
  require_input(std::isfinite(options.re) && options.re > 0,
                "fluid_2d: parameter 're' must be > 0");
  require_input(std::isfinite(options.lid) && options.lid > 0,
                "fluid_2d: parameter 'lid' must be > 0");
  require_input(std::isfinite(options.gravity), "fluid_2d: parameter 'gravity' must be finite");
  n_ = options.n;
  dx_ = 1.0 / n_;
  periodic_ = options.scene == Fluid2dOptions::Scene::taylor_green;
  nux_ = periodic_ ? n_ : n_ + 1;
  nvy_ = periodic_ ? n_ : n_ + 1;
  nu_count_ = static_cast<Index>(nux_) * n_;
  nv_count_ = static_cast<Index>(n_) * nvy_;
  speed_ = periodic_ ? 1.0 : options.lid;
  nu_ = speed_ / options.re;

  free_ = Vec::Ones(dimension());
  if (!periodic_) {
    for (int j = 0; j < n_; ++j) free_(u_index(0, j)) = free_(u_index(n_, j)) = 0;
    for (int i = 0; i < n_; ++i) free_(v_index(i, 0)) = free_(v_index(i, n_)) = 0;
  }
  y0_ = Vec::Zero(dimension());
  if (periodic_) {
    const double w = 2.0 * std::numbers::pi;
    for (int j = 0; j < n_; ++j)
      for (int i = 0; i < n_; ++i) {
        y0_(u_index(i, j)) = std::sin(w * i * dx_) * std::cos(w * (j + 0.5) * dx_);
        y0_(v_index(i, j)) = -std::cos(w * (i + 0.5) * dx_) * std::sin(w * j * dx_);
      }
  }
  build_operators();
  rhs_div_.resize(static_cast<Index>(n_) * n_);
  psi_ = Vec::Zero(rhs_div_.size());
  psi_e_ = psi_i_ = psi_;
  diff_rhs_.resize(dimension());
}

Fluid2d::Ref Fluid2d::u_ref(int i, int j) const {
  Ref r;
  r.s = 1.0;
  if (periodic_) {
    r.k = u_index(wrap(i, n_), wrap(j, n_));
    return r;
  }
  // x: faces 0..N with u = 0 at i = 0 and N: odd reflection about them.
  if (i < 0) {
    i = -i;
    r.s = -r.s;
  } else if (i > n_) {
    i = 2 * n_ - i;
    r.s = -r.s;
  }
  // y: rows 0..N-1 between the floor (speed 0) and the lid (speed U): u_ghost = 2U_wall - u.
  if (j < 0) {
    j = -1 - j;
    r.s = -r.s;
  } else if (j >= n_) {
    j = 2 * n_ - 1 - j;
    r.c = 2.0 * opt_.lid;
    r.s = -r.s;
  }
  r.k = u_index(std::clamp(i, 0, n_), std::clamp(j, 0, n_ - 1));
  return r;
}

Fluid2d::Ref Fluid2d::v_ref(int i, int j) const {
  Ref r;
  r.s = 1.0;
  if (periodic_) {
    r.k = v_index(wrap(i, n_), wrap(j, n_));
    return r;
  }
  if (j < 0) {
    j = -j;
    r.s = -r.s;
  } else if (j > n_) {
    j = 2 * n_ - j;
    r.s = -r.s;
  }
  if (i < 0) {
    i = -1 - i;
    r.s = -r.s;
  } else if (i >= n_) {
    i = 2 * n_ - 1 - i;
    r.s = -r.s;
  }
  r.k = v_index(std::clamp(i, 0, n_ - 1), std::clamp(j, 0, n_));
  return r;
}

double Fluid2d::u_at(const double* y, int i, int j) const {
  const Ref r = u_ref(i, j);
  return r.s * y[r.k] + r.c;
}

double Fluid2d::v_at(const double* y, int i, int j) const {
  const Ref r = v_ref(i, j);
  return r.s * y[r.k] + r.c;
}

void Fluid2d::build_operators() {
  const Index dim = dimension();
  const double inv2 = 1.0 / (dx_ * dx_);
  // Velocity Laplacian L and its constant b (ghosts across walls), free rows and columns only.
  std::vector<Triplet> t;
  lap_const_ = Vec::Zero(dim);
  auto add_row = [&](Index k, const Ref nbs[4]) {
    t.emplace_back(k, k, -4.0 * inv2);
    for (int q = 0; q < 4; ++q) {
      const Ref& r = nbs[q];
      if (free_(r.k) != 0) t.emplace_back(k, r.k, r.s * inv2);
      lap_const_(k) += r.c * inv2;
    }
  };
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < nux_; ++i) {
      const Index k = u_index(i, j);
      if (free_(k) == 0) continue;
      const Ref nbs[4] = {u_ref(i + 1, j), u_ref(i - 1, j), u_ref(i, j + 1), u_ref(i, j - 1)};
      add_row(k, nbs);
    }
  for (int j = 0; j < nvy_; ++j)
    for (int i = 0; i < n_; ++i) {
      const Index k = v_index(i, j);
      if (free_(k) == 0) continue;
      const Ref nbs[4] = {v_ref(i + 1, j), v_ref(i - 1, j), v_ref(i, j + 1), v_ref(i, j - 1)};
      add_row(k, nbs);
    }
  lap_.resize(dim, dim);
  lap_.setFromTriplets(t.begin(), t.end());

  // Divergence D over the free faces.
  t.clear();
  const Index cells = static_cast<Index>(n_) * n_;
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < n_; ++i) {
      const Index c = i + static_cast<Index>(n_) * j;
      const std::pair<Index, double> faces[4] = {{u_ref(i + 1, j).k, 1.0},
                                                 {u_ref(i, j).k, -1.0},
                                                 {v_ref(i, j + 1).k, 1.0},
                                                 {v_ref(i, j).k, -1.0}};
      for (const auto& [k, s] : faces)
        if (free_(k) != 0) t.emplace_back(c, k, s / dx_);
    }
  div_.resize(cells, dim);
  div_.setFromTriplets(t.begin(), t.end());
  div_t_ = div_.transpose();

  // DDᵀ with ψ_0 = 0 pinned.
  const SparseMat ddt = div_ * div_t_;
  t.clear();
  for (Index col = 0; col < ddt.outerSize(); ++col)
    for (SparseMat::InnerIterator it(ddt, col); it; ++it)
      if (it.row() != 0 && it.col() != 0) t.emplace_back(it.row(), it.col(), it.value());
  t.emplace_back(0, 0, 1.0);
  poisson_.resize(cells, cells);
  poisson_.setFromTriplets(t.begin(), t.end());
  if (opt_.solver == Fluid2dOptions::Solver::cholesky) {
    chol_.compute(poisson_);
    if (chol_.info() != Eigen::Success)
      throw std::runtime_error("fluid_2d: Cholesky factorisation of the pressure matrix failed");
  } else {
    cg_.setTolerance(1e-12);
    cg_.setMaxIterations(10 * static_cast<Index>(cells));
    cg_.compute(poisson_);
  }
}

void Fluid2d::solve_pressure(CVecRef div, Vec& psi) const {
  rhs_div_ = div;
  rhs_div_(0) = 0.0;
  if (opt_.solver == Fluid2dOptions::Solver::cholesky) {
    psi = chol_.solve(rhs_div_);
  } else {
    psi = cg_.solveWithGuess(rhs_div_, psi);
    if (cg_.info() != Eigen::Success)
      throw std::runtime_error("fluid_2d: conjugate gradients did not converge on the pressure");
  }
}

void Fluid2d::advection_terms(CVecRef yv, VecRef f) const {
  const double* y = yv.data();
  const double inv2dx = 0.5 / dx_;
  // -(u·∇)u at the u faces, then the v faces.
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < nux_; ++i) {
      const Index k = u_index(i, j);
      if (free_(k) == 0) {
        f(k) = 0.0;
        continue;
      }
      const double dudx = (u_at(y, i + 1, j) - u_at(y, i - 1, j)) * inv2dx;
      const double dudy = (u_at(y, i, j + 1) - u_at(y, i, j - 1)) * inv2dx;
      const double vbar =
          0.25 * (v_at(y, i - 1, j) + v_at(y, i, j) + v_at(y, i - 1, j + 1) + v_at(y, i, j + 1));
      f(k) = -(y[k] * dudx + vbar * dudy);
    }
  for (int j = 0; j < nvy_; ++j)
    for (int i = 0; i < n_; ++i) {
      const Index k = v_index(i, j);
      if (free_(k) == 0) {
        f(k) = 0.0;
        continue;
      }
      const double dvdx = (v_at(y, i + 1, j) - v_at(y, i - 1, j)) * inv2dx;
      const double dvdy = (v_at(y, i, j + 1) - v_at(y, i, j - 1)) * inv2dx;
      const double ubar =
          0.25 * (u_at(y, i, j - 1) + u_at(y, i + 1, j - 1) + u_at(y, i, j) + u_at(y, i + 1, j));
      f(k) = -(ubar * dvdx + y[k] * dvdy) - opt_.gravity;
    }
}

void Fluid2d::project_in_place(VecRef f, Vec& psi) const {
  solve_pressure(div_ * f, psi);
  f.noalias() -= div_t_ * psi;
}

void Fluid2d::eval_rhs(double, CVecRef yv, VecRef f) const {
  advection_terms(yv, f);
  // + ν(L u + b), then the projection.
  f.noalias() += nu_ * (lap_ * yv);
  f += nu_ * lap_const_;
  project_in_place(f, psi_);
}

void Fluid2d::eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const {
  advection_terms(y, fe);
  project_in_place(fe, psi_e_);
}

void Fluid2d::eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const {
  fi.noalias() = nu_ * (lap_ * y);
  fi += nu_ * lap_const_;
  project_in_place(fi, psi_i_);
}

std::optional<SplitInfo> Fluid2d::imex_split() const {
  if (!has_imex_split()) return std::nullopt;
  return SplitInfo{"diffusion",
                   "advection and gravity P[-(u.grad)u + g] (central differences, projected)",
                   "diffusion P[nu Laplace(u) + nu b] (5-point stencil with the walls' and lid's "
                   "ghost values, projected)"};
}

std::optional<SpectrumEstimate> Fluid2d::explicit_part_spectrum(double, CVecRef yv) const {
  if (!has_imex_split()) return std::nullopt;
  // The central transport operator -(u ∂_x + v̄ ∂_y) at a u face (and -(ū ∂_x + v ∂_y) at a v
  // face) has the local symbol -i (u sin θ_x + v̄ sin θ_y)/Δx, of modulus at most (|u| + |v̄|)/Δx;
  // its largest value over the faces (see the header comment).
  const double* y = yv.data();
  double speed = 0.0;
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < nux_; ++i) {
      const Index k = u_index(i, j);
      if (free_(k) == 0) continue;
      const double vbar =
          0.25 * (v_at(y, i - 1, j) + v_at(y, i, j) + v_at(y, i - 1, j + 1) + v_at(y, i, j + 1));
      speed = std::max(speed, std::abs(y[k]) + std::abs(vbar));
    }
  for (int j = 0; j < nvy_; ++j)
    for (int i = 0; i < n_; ++i) {
      const Index k = v_index(i, j);
      if (free_(k) == 0) continue;
      const double ubar =
          0.25 * (u_at(y, i, j - 1) + u_at(y, i + 1, j - 1) + u_at(y, i, j) + u_at(y, i + 1, j));
      speed = std::max(speed, std::abs(ubar) + std::abs(y[k]));
    }
  return SpectrumEstimate{speed / dx_, SpectrumEstimate::Ray::imaginary};
}

double Fluid2d::kinetic_energy(CVecRef y) const { return 0.5 * y.squaredNorm() * dx_ * dx_; }

Vec Fluid2d::divergence(CVecRef y) const { return div_ * y; }

double Fluid2d::max_divergence(CVecRef y) const { return divergence(y).cwiseAbs().maxCoeff(); }

Vec Fluid2d::pressure(CVecRef y) const {
  // eval_rhs leaves the projection's ψ in psi_: f = F - Dᵀψ = F - Gp with G = -Dᵀ, so p = -ψ
  // (defined up to a constant: the mean is removed).
  Vec f(dimension());
  eval_rhs(0.0, y, f);
  Vec p = -psi_;
  p.array() -= p.mean();
  return p;
}

Vec Fluid2d::vorticity(CVecRef yv) const {
  const double* y = yv.data();
  // Corner (i, j) at (iΔx, jΔx): ∂v/∂x - ∂u/∂y by differences across the corner.
  auto corner = [&](int i, int j) {
    return (v_at(y, i, j) - v_at(y, i - 1, j) - u_at(y, i, j) + u_at(y, i, j - 1)) / dx_;
  };
  Vec w(static_cast<Index>(n_) * n_);
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < n_; ++i)
      w(i + static_cast<Index>(n_) * j) =
          0.25 * (corner(i, j) + corner(i + 1, j) + corner(i, j + 1) + corner(i + 1, j + 1));
  return w;
}

void Fluid2d::cell_velocity(CVecRef yv, Vec& uc, Vec& vc) const {
  const double* y = yv.data();
  uc.resize(static_cast<Index>(n_) * n_);
  vc.resize(uc.size());
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < n_; ++i) {
      const Index c = i + static_cast<Index>(n_) * j;
      uc(c) = 0.5 * (u_at(y, i, j) + u_at(y, i + 1, j));
      vc(c) = 0.5 * (v_at(y, i, j) + v_at(y, i, j + 1));
    }
}

std::vector<std::pair<double, double>> Fluid2d::centreline_u(CVecRef yv) const {
  const double* y = yv.data();
  std::vector<std::pair<double, double>> out;
  for (int j = 0; j < n_; ++j) {
    const double u = n_ % 2 == 0 ? u_at(y, n_ / 2, j)
                                 : 0.5 * (u_at(y, (n_ - 1) / 2, j) + u_at(y, (n_ + 1) / 2, j));
    out.emplace_back((j + 0.5) * dx_, u);
  }
  return out;
}

std::optional<double> Fluid2d::end_time() const {
  if (!periodic_) return std::nullopt;
  return 1.0 / (16.0 * std::numbers::pi * std::numbers::pi * nu_);
}

std::optional<double> Fluid2d::stiffness(double, CVecRef) const {
  return 8.0 * nu_ / (dx_ * dx_) + 2.0 * speed_ / dx_;
}

std::optional<SuggestedStep> Fluid2d::suggested_step() const {
  const double diffusion = dx_ * dx_ / (4.0 * nu_), advection = dx_ / speed_;
  SuggestedStep s;
  s.h = std::min(diffusion, advection);
  s.rule = "min(dx^2/(4 nu), dx/U) = min(" + num(diffusion) + ", " + num(advection) +
           "): explicit diffusion and advection limits, dx = " + num(dx_) + ", nu = " + num(nu_) +
           ", U = " + num(speed_);
  return s;
}

std::vector<Invariant> Fluid2d::observables() const {
  std::vector<Invariant> out = {
      {"kinetic_energy", [this](double, CVecRef y) { return kinetic_energy(y); }},
      {"max_divergence", [this](double, CVecRef y) { return max_divergence(y); }}};
  if (periodic_) {
    // E(t) / (E(0) e^{-16π²νt}): 1 for the PDE's Taylor–Green decay.
    const double e0 = kinetic_energy(y0_), rate = 16.0 * std::numbers::pi * std::numbers::pi * nu_;
    out.push_back({"ke_over_exact_decay", [this, e0, rate](double t, CVecRef y) {
                     return kinetic_energy(y) / (e0 * std::exp(-rate * t));
                   }});
  }
  return out;
}

GridFrame Fluid2d::grid_frame(double, CVecRef y) const {
  GridFrame g;
  g.nx = g.ny = n_;
  g.spacing = dx_;
  const std::size_t cells = static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_);
  Vec uc, vc;
  cell_velocity(y, uc, vc);
  ParticleFrame::Field vel{"velocity", 3, std::vector<double>(3 * cells, 0.0)};
  for (std::size_t c = 0; c < cells; ++c) {
    vel.values[3 * c] = uc(static_cast<Index>(c));
    vel.values[3 * c + 1] = vc(static_cast<Index>(c));
  }
  const Vec p = pressure(y), w = vorticity(y);
  g.cell_fields.push_back(std::move(vel));
  g.cell_fields.push_back({"pressure", 1, std::vector<double>(p.data(), p.data() + p.size())});
  g.cell_fields.push_back({"vorticity", 1, std::vector<double>(w.data(), w.data() + w.size())});
  return g;
}

std::vector<Profile> Fluid2d::profiles(double, CVecRef y) const {
  if (periodic_) return {};
  Profile p{"centreline", {"y", "u"}, {}};
  for (const auto& [yc, u] : centreline_u(y)) p.rows.push_back({yc, u});
  return {p};
}

// --- GridFluid ---------------------------------------------------------------------------------

void Fluid2d::add_body_force(double h, VecRef y) const {
  if (opt_.gravity == 0) return;
  for (Index k = nu_count_; k < dimension(); ++k) y(k) -= h * opt_.gravity * free_(k);
}

double Fluid2d::sample(const double* y, int comp, double px, double py) const {
  // Fractional face indices: u at (iΔx, (j + ½)Δx), v at ((i + ½)Δx, jΔx).
  const double fi = px / dx_ - (comp == 0 ? 0.0 : 0.5);
  const double fj = py / dx_ - (comp == 0 ? 0.5 : 0.0);
  const double i0f = std::floor(fi), j0f = std::floor(fj);
  const int i0 = static_cast<int>(i0f), j0 = static_cast<int>(j0f);
  const double a = fi - i0f, b = fj - j0f;
  auto at = [&](int i, int j) { return comp == 0 ? u_at(y, i, j) : v_at(y, i, j); };
  if (opt_.advection == Fluid2dOptions::Advection::linear) {
    return (1 - b) * ((1 - a) * at(i0, j0) + a * at(i0 + 1, j0)) +
           b * ((1 - a) * at(i0, j0 + 1) + a * at(i0 + 1, j0 + 1));
  }
  double wa[4], wb[4];
  catmull_rom(a, wa);
  catmull_rom(b, wb);
  double s = 0;
  for (int q = 0; q < 4; ++q) {
    double row = 0;
    for (int p = 0; p < 4; ++p) row += wa[p] * at(i0 - 1 + p, j0 - 1 + q);
    s += wb[q] * row;
  }
  return s;
}

void Fluid2d::advect(double h, CVecRef vel, CVecRef q, VecRef out) const {
  const double* v = vel.data();
  const double* src = q.data();
  auto clamp_box = [&](double& x, double& y) {
    if (periodic_) return;  // the samples wrap
    x = std::clamp(x, 0.0, 1.0);
    y = std::clamp(y, 0.0, 1.0);
  };
  auto trace = [&](Index k, double x, double y, int comp) {
    if (free_(k) == 0) {
      out(k) = 0.0;
      return;
    }
    // Midpoint rule backwards along the field.
    const double u1 = sample(v, 0, x, y), v1 = sample(v, 1, x, y);
    double xm = x - 0.5 * h * u1, ym = y - 0.5 * h * v1;
    clamp_box(xm, ym);
    double xd = x - h * sample(v, 0, xm, ym), yd = y - h * sample(v, 1, xm, ym);
    clamp_box(xd, yd);
    out(k) = sample(src, comp, xd, yd);
  };
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < nux_; ++i) trace(u_index(i, j), i * dx_, (j + 0.5) * dx_, 0);
  for (int j = 0; j < nvy_; ++j)
    for (int i = 0; i < n_; ++i) trace(v_index(i, j), (i + 0.5) * dx_, j * dx_, 1);
}

int Fluid2d::diffuse(double h, CVecRef in, VecRef out) const {
  if (h != last_h_) {
    SparseMat m(dimension(), dimension());
    m.setIdentity();
    m -= (h * nu_) * lap_;
    diff_chol_.compute(m);
    if (diff_chol_.info() != Eigen::Success)
      throw std::runtime_error("fluid_2d: factorisation of the diffusion matrix failed");
    last_h_ = h;
  }
  diff_rhs_ = in + (h * nu_) * lap_const_;
  out = diff_chol_.solve(diff_rhs_);
  out.array() *= free_.array();
  return 1;
}

int Fluid2d::project_divergence_free(VecRef y) const {
  project_in_place(y, psi_);
  return 1;
}

ModelRegistry::Entry fluid_2d_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info =
          {.name = "fluid_2d",
           .description =
               "incompressible Navier-Stokes on a MAC grid, u' = P[-(u.grad)u + nu Laplace(u) + "
               "g] "
               "(pressure projection); scenes taylor_green (periodic) and cavity (lid-driven); "
               "observables kinetic_energy, max_divergence; split=diffusion: advection explicit, "
               "diffusion implicit",
           .source =
               "Taylor-Green: kinetic energy decays as exp(-16 pi^2 t/Re) (Taylor & Green 1937); "
               "cavity: Ghia, Ghia & Shin 1982 centreline profiles",
           // fluid_2d: about 2 n^2 face velocities; the pressure Laplacian on n^2 cells and its
           // sparse Cholesky factor (nested-dissection fill of a 2D grid, about n^2 (6 + 2 log2 n)
           // entries of 12 bytes), work vectors; f has no analytic Jacobian.
           .size =
               [](const Params& p) {
                 const double n = std::max(static_cast<double>(p.integer("n")), 1.0);
                 const double cells = n * n;
                 const double factor = cells * (6.0 + 2.0 * std::log2(n)) + 5.0 * cells;
                 return ModelSize{2.0 * cells + 2.0 * n, 12.0 * factor + 96.0 * cells, 0.0,
                                  "n=" + std::to_string(p.integer("n"))};
               }},
      .params = {{"scene",
                  P::text,
                  "taylor_green",
                  "taylor_green (periodic unit box, u = sin 2pi x cos 2pi y) or cavity (walls, lid "
                  "at y = 1, starting at rest)",
                  {"taylor_green", "cavity"}},
                 {"n", P::integer, "32", "cells per direction (unknowns about 2 n^2)",
                  B::in(4, 2048)},
                 {"re", P::real, "100", "Reynolds number U L / nu (U = 1 or the lid speed, L = 1)",
                  B::positive()},
                 {"lid", P::real, "1", "cavity lid speed U along x", B::positive()},
                 {"gravity", P::real, "0", "body force along -y", B::any()},
                 {"solver",
                  P::text,
                  "cholesky",
                  "pressure Poisson solver: cholesky (sparse LDLT factorised once per grid) or cg",
                  {"cholesky", "cg"}},
                 {"advection",
                  P::text,
                  "linear",
                  "interpolation of the semi-Lagrangian advection (stable_fluids only): linear "
                  "(Stam 1999) or cubic (Catmull-Rom)",
                  {"linear", "cubic"}},
                 {"split",
                  P::text,
                  "none",
                  "additive split f = f_E + f_I: none (f is not divided) or diffusion (f_E = "
                  "P[-(u.grad)u + g] explicit, f_I = P[nu Laplace(u) + nu b] implicit, no analytic "
                  "J_I)",
                  {"none", "diffusion"}}},
      .make = [](const Params& p) {
        Fluid2dOptions o;
        o.scene = p.text("scene") == "cavity" ? Fluid2dOptions::Scene::cavity
                                              : Fluid2dOptions::Scene::taylor_green;
        o.n = grid_int(p, "n", "fluid_2d", 4, 2048);
        o.re = p.real("re");
        o.lid = p.real("lid");
        o.gravity = p.real("gravity");
        o.solver = p.text("solver") == "cg" ? Fluid2dOptions::Solver::cg
                                            : Fluid2dOptions::Solver::cholesky;
        o.advection = p.text("advection") == "cubic" ? Fluid2dOptions::Advection::cubic
                                                     : Fluid2dOptions::Advection::linear;
        o.split = p.text("split") == "diffusion" ? Fluid2dOptions::Split::diffusion
                                                 : Fluid2dOptions::Split::none;
        return std::make_unique<Fluid2d>(o);
      }};
}

}  // namespace stiffbench
