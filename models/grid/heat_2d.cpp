#include "models/grid/heat_2d.hpp"
#include "models/grid/grid_entry.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace stiffbench {

namespace {
double sq(double x) { return x * x; }
std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}
}  // namespace

Heat2d::Heat2d(int n, double nu, Boundary boundary, int kx, int ky)
    : n_(n), nu_(nu), boundary_(boundary), kx_(kx), ky_(ky) {
  const bool periodic = boundary == Boundary::periodic;
  require_input(n >= 3 && n <= 4096, "heat_2d: parameter 'n' must be in [3, 4096]");
  require_input(std::isfinite(nu) && nu > 0, "heat_2d: parameter 'nu' must be > 0");
  for (const auto& [key, k] : {std::pair{"kx", kx}, std::pair{"ky", ky}}) {
    if (periodic)
      require_input(k >= 1 && 2 * k < n, std::string("heat_2d: parameter '") + key +
                                             "' must be in [1, n/2) for periodic boundaries");
    else
      require_input(k >= 1 && k <= n, std::string("heat_2d: parameter '") + key +
                                          "' must be in [1, n] for dirichlet boundaries");
  }
  dx_ = periodic ? 1.0 / n : 1.0 / (n + 1);
  const double pi = std::numbers::pi;
  const double c = 4.0 * nu / (dx_ * dx_);
  // θ_k = π k Δx (periodic, wavenumber 2πk) or π k Δx / 2 (dirichlet, wavenumber πk).
  const double half = periodic ? 1.0 : 0.5;
  lambda_ = -c * (sq(std::sin(pi * kx * dx_ * half)) + sq(std::sin(pi * ky * dx_ * half)));
  // Largest |λ|: the mode closest to the checkerboard (k = N/2 periodic, k = N dirichlet).
  double smax = 0;
  for (int k = 1; k <= (periodic ? n / 2 : n); ++k)
    smax = std::max(smax, sq(std::sin(pi * k * dx_ * half)));
  rho_ = 2.0 * c * smax;
  u0_.resize(dimension());
  const double w = periodic ? 2.0 * pi : pi;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      u0_(i + static_cast<Index>(n) * j) =
          std::sin(w * kx * coordinate(i)) * std::sin(w * ky * coordinate(j));
}

double Heat2d::coordinate(int i) const {
  return boundary_ == Boundary::periodic ? (i + 0.5) * dx_ : (i + 1) * dx_;
}

double Heat2d::continuous_eigenvalue() const {
  const double w = boundary_ == Boundary::periodic ? 2.0 * std::numbers::pi : std::numbers::pi;
  return -nu_ * w * w * (kx_ * kx_ + ky_ * ky_);
}

std::optional<double> Heat2d::end_time() const { return 1.0 / std::abs(lambda_); }

Vec Heat2d::initial_state() const { return u0_; }

void Heat2d::exact(double t, VecRef y) const { y = std::exp(lambda_ * t) * u0_; }

std::optional<SuggestedStep> Heat2d::suggested_step() const {
  SuggestedStep s;
  s.h = 2.0 / rho_;
  s.rule = "explicit Euler's diffusion limit 2/rho, rho = " + num(rho_) +
           " the largest |eigenvalue| (8 nu/dx^2 for an even periodic n: h = dx^2/(4 nu)), nu = " +
           num(nu_) + ", dx = " + num(dx_);
  return s;
}

void Heat2d::eval_rhs(double, CVecRef y, VecRef dydt) const {
  const int n = n_;
  const double c = nu_ / (dx_ * dx_);
  const bool periodic = boundary_ == Boundary::periodic;
  const double* u = y.data();
  double* f = dydt.data();
  // Neighbour index along one axis: wrapped (periodic) or -1 outside (dirichlet, where u = 0).
  // Computed per row and column rather than with a modulo per neighbour (the modulos were most of
  // an explicit step's cost); the values and the order of the sum are unchanged.
  auto next = [&](int i) { return i + 1 < n ? i + 1 : (periodic ? 0 : -1); };
  auto prev = [&](int i) { return i > 0 ? i - 1 : (periodic ? n - 1 : -1); };
  const std::ptrdiff_t stride = n;
  for (int j = 0; j < n; ++j) {
    const int jn = next(j), jp = prev(j);
    const double* row = u + stride * j;
    const double* up = jn >= 0 ? u + stride * jn : nullptr;    // row j + 1
    const double* down = jp >= 0 ? u + stride * jp : nullptr;  // row j - 1
    double* out = f + stride * j;
    for (int i = 0; i < n; ++i) {
      const int in = next(i), ip = prev(i);
      const double east = in >= 0 ? row[in] : 0.0;
      const double west = ip >= 0 ? row[ip] : 0.0;
      const double north = up ? up[i] : 0.0;
      const double south = down ? down[i] : 0.0;
      out[i] = c * (east + west + north + south - 4.0 * row[i]);
    }
  }
}

void Heat2d::eval_jacobian(double, CVecRef, SparseMat& jac) const {
  const int n = n_;
  const double c = nu_ / (dx_ * dx_);
  const bool periodic = boundary_ == Boundary::periodic;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(5 * dimension()));
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const Index row = i + static_cast<Index>(n) * j;
      t.emplace_back(row, row, -4.0 * c);
      const int nbs[4][2] = {{i + 1, j}, {i - 1, j}, {i, j + 1}, {i, j - 1}};
      for (const auto& nb : nbs) {
        int a = nb[0], b = nb[1];
        if (periodic) {
          a = (a + n) % n;
          b = (b + n) % n;
        } else if (a < 0 || a >= n || b < 0 || b >= n) {
          continue;
        }
        t.emplace_back(row, a + static_cast<Index>(n) * b, c);  // duplicates (n = 2) are summed
      }
    }
  }
  jac.resize(dimension(), dimension());
  jac.setFromTriplets(t.begin(), t.end());
}

ModelRegistry::Entry heat_2d_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info =
          {.name = "heat_2d",
           .description =
               "heat equation u' = nu Laplace(u) on an n x n grid (5-point stencil), a sine mode; "
               "stiffness knob nu/dx^2",
           .exact = true,
           .source =
               "exact solution exp(lambda t) u0 of the semi-discrete system (lambda the stencil's "
               "eigenvalue of the mode)",
           // Sizes from the parameters alone (ModelSize, checked before anything is built).
           // heat_2d: n^2 unknowns, the 5-point Jacobian (5 n^2 nonzeros, 12 bytes each) kept by
           // the model, plus a few state-sized vectors.
           .size =
               [](const Params& p) {
                 const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                 return ModelSize{n * n, 12.0 * 5.0 * n * n + 32.0 * n * n, 5.0 * n * n,
                                  "n=" + std::to_string(p.integer("n"))};
               }},
      .params = {{"n", P::integer, "32", "grid points per direction (unknowns n^2)",
                  B::in(3, 4096)},
                 {"nu", P::real, "1", "diffusivity nu", B::positive()},
                 {"boundary",
                  P::text,
                  "periodic",
                  "periodic (cell centres, dx = 1/n) or dirichlet (u = 0, interior nodes, dx = "
                  "1/(n+1))",
                  {"periodic", "dirichlet"}},
                 {"kx", P::integer, "1", "mode number along x", B::in(1, 4096)},
                 {"ky", P::integer, "1", "mode number along y", B::in(1, 4096)}},
      .make = [](const Params& p) {
        const int n = grid_int(p, "n", "heat_2d", 3, 4096);
        const auto b = p.text("boundary") == "dirichlet" ? Heat2d::Boundary::dirichlet
                                                         : Heat2d::Boundary::periodic;
        return std::make_unique<Heat2d>(n, p.real("nu"), b, grid_int(p, "kx", "heat_2d", 1, 4096),
                                        grid_int(p, "ky", "heat_2d", 1, 4096));
      }};
}

}  // namespace stiffbench
