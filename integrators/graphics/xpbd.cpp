#include "integrators/graphics/xpbd.hpp"

#include <algorithm>
#include <cmath>

#include "integrators/graphics/spring_requirements.hpp"
#include "integrators/method_entry.hpp"

namespace stiffbench {

std::vector<ParamSpec> xpbd_param_specs() {
  return {{"substeps", ParamType::integer, "1",
           "substeps per step h, each of size h/substeps with its own prediction and "
           "multipliers (Macklin et al. 2019)",
           Bounds::in(1, 1000000)},
          {"iterations", ParamType::integer, "10", "constraint sweeps per substep",
           Bounds::in(1, 1000000)},
          {"variant",
           ParamType::text,
           "gauss_seidel",
           "gauss_seidel: each spring's correction applied at once; jacobi: all from the same "
           "iterate, each scaled by 1/(springs at its busier end)",
           {"gauss_seidel", "jacobi"}}};
}

XpbdOptions read_xpbd_options(const Params& p) {
  XpbdOptions o;
  const long substeps = p.integer("substeps");
  const long iterations = p.integer("iterations");
  require_input(substeps >= 1 && substeps <= 1000000, "xpbd: parameter 'substeps' must be >= 1");
  require_input(iterations >= 1 && iterations <= 1000000,
                "xpbd: parameter 'iterations' must be >= 1");
  o.substeps = static_cast<int>(substeps);
  o.iterations = static_cast<int>(iterations);
  o.variant = p.text("variant") == "jacobi" ? XpbdOptions::Variant::jacobi
                                            : XpbdOptions::Variant::gauss_seidel;
  return o;
}

namespace {
constexpr MethodText kXpbdText{
    .description =
        "XPBD (Macklin, Mueller & Chentanez 2016): springs as compliant distance "
        "constraints, compliance 1/k, multipliers reset each substep; substeps "
        "(Macklin et al. 2019), Gauss-Seidel or Jacobi sweeps; needs a spring network",
    .kind = "position-based (compliant constraints)",
    .reference =
        "M. Macklin, M. Mueller & N. Chentanez, XPBD: position-based simulation of "
        "compliant constrained dynamics, Motion in Games (MIG) 2016, 49-54; substeps: "
        "M. Macklin et al., Small steps in physics simulation, SCA 2019"};
}  // namespace

Xpbd::Xpbd(XpbdOptions opt)
    : Integrator(
          method_info("xpbd", Family::graphics, 1, 0, spring_network_requirements(), kXpbdText)),
      opt_(opt) {}

void Xpbd::reset(const OdeSystem& sys, double /*t0*/, CVecRef y0) {
  check_compatible(info(), sys);
  sys_ = &sys;
  net_ = sys.spring_network();
  const Index np = net_->points();
  if (y0.size() != 2 * net_->dim * np)
    throw std::logic_error("xpbd: state size does not match the spring network");
  inv_mass_.resize(static_cast<std::size_t>(np));
  for (Index p = 0; p < np; ++p) inv_mass_[static_cast<std::size_t>(p)] = net_->inverse_mass(p);
  // Springs per point (for the Jacobi scaling), counting only those that act.
  std::vector<int> count(static_cast<std::size_t>(np), 0);
  const auto acts = [&](const SpringElement& s) {
    return s.k > 0.0 &&
           inv_mass_[static_cast<std::size_t>(s.i)] + inv_mass_[static_cast<std::size_t>(s.j)] >
               0.0;
  };
  for (const SpringElement& s : net_->springs)
    if (acts(s)) {
      ++count[static_cast<std::size_t>(s.i)];
      ++count[static_cast<std::size_t>(s.j)];
    }
  constraints_.clear();
  for (const SpringElement& s : net_->springs) {
    if (!acts(s)) continue;
    const double wi = inv_mass_[static_cast<std::size_t>(s.i)];
    const double wj = inv_mass_[static_cast<std::size_t>(s.j)];
    // n_i w_i + n_j w_j: the Gershgorin bound of this constraint's row of J W Jᵀ (Jacobi).
    const double busy =
        count[static_cast<std::size_t>(s.i)] * wi + count[static_cast<std::size_t>(s.j)] * wj;
    constraints_.push_back({s.i, s.j, s.rest, 1.0 / s.k, s.damping, wi, wj, busy});
  }
  const Index n = net_->dim * np;
  x_start_.resize(n);
  dx_.resize(n);
  lambda_.resize(static_cast<Index>(constraints_.size()));
}

template <int D, bool Jacobi>
void Xpbd::sweep(double* x, double hs) {
  const double* xn = x_start_.data();
  double* dx = dx_.data();
  if constexpr (Jacobi) dx_.setZero();
  const double inv_h2 = 1.0 / (hs * hs);
  for (std::size_t c = 0; c < constraints_.size(); ++c) {
    const Constraint& s = constraints_[c];
    double* xi = x + D * s.i;
    double* xj = x + D * s.j;
    double n[D];
    double l2 = 0.0;
    for (int d = 0; d < D; ++d) {
      n[d] = xj[d] - xi[d];
      l2 += n[d] * n[d];
    }
    if (!(l2 > 0.0)) continue;  // no direction: skipped this sweep
    const double l = std::sqrt(l2);
    double rel = 0.0;  // n·(Δx_j - Δx_i), Δx = x - x^n (damping)
    for (int d = 0; d < D; ++d) {
      n[d] /= l;
      rel += n[d] * ((xj[d] - xn[D * s.j + d]) - (xi[d] - xn[D * s.i + d]));
    }
    const double alpha = s.compliance * inv_h2;          // α̃ = α/h_s²
    const double gamma = s.damping * s.compliance / hs;  // γ_c = α̃ β̃ / h_s = c/(k h_s)
    const double lam = lambda_[static_cast<Index>(c)];
    const double diag = (1.0 + gamma) * (s.wi + s.wj) + alpha;
    double dl = (-(l - s.rest) - alpha * lam - gamma * rel) / diag;
    if constexpr (Jacobi) {
      dl *= diag / ((1.0 + gamma) * s.busy + alpha);  // ω_c <= 1, -> 1 as h_s -> 0
      for (int d = 0; d < D; ++d) {
        dx[D * s.i + d] -= s.wi * n[d] * dl;
        dx[D * s.j + d] += s.wj * n[d] * dl;
      }
    } else {
      for (int d = 0; d < D; ++d) {
        xi[d] -= s.wi * n[d] * dl;
        xj[d] += s.wj * n[d] * dl;
      }
    }
    lambda_[static_cast<Index>(c)] = lam + dl;
  }
  if constexpr (Jacobi) {
    const Index n = net_->dim * net_->points();
    for (Index k = 0; k < n; ++k) x[k] += dx[k];
  }
}

template <int D>
void Xpbd::substep(double* x, double* v, double hs) {
  const Index np = net_->points();
  const double gamma = net_->point_damping;
  for (Index p = 0; p < np; ++p) {
    const double w = inv_mass_[static_cast<std::size_t>(p)];
    for (int d = 0; d < D; ++d) x_start_[D * p + d] = x[D * p + d];
    if (w == 0.0) continue;  // pinned: v = 0, never moves
    const double damp = 1.0 / (1.0 + hs * gamma * w);
    for (int d = 0; d < D; ++d) {
      const double vd = (v[D * p + d] + hs * net_->gravity[static_cast<std::size_t>(d)]) * damp;
      v[D * p + d] = vd;
      x[D * p + d] += hs * vd;
    }
  }
  lambda_.setZero();
  for (int it = 0; it < opt_.iterations; ++it) {
    if (opt_.variant == XpbdOptions::Variant::jacobi)
      sweep<D, true>(x, hs);
    else
      sweep<D, false>(x, hs);
  }
  const double inv_hs = 1.0 / hs;
  for (Index p = 0; p < np; ++p) {
    if (inv_mass_[static_cast<std::size_t>(p)] == 0.0) continue;
    for (int d = 0; d < D; ++d) v[D * p + d] = (x[D * p + d] - x_start_[D * p + d]) * inv_hs;
  }
}

Status Xpbd::step(const OdeSystem& sys, double /*t*/, VecRef y, double h, SolveStats& /*stats*/) {
  if (&sys != sys_) throw std::logic_error("Xpbd::step: system differs from reset()");
  const Index n = net_->dim * net_->points();
  double* x = y.data();
  double* v = y.data() + n;
  const double hs = h / opt_.substeps;
  for (int s = 0; s < opt_.substeps; ++s) {
    switch (net_->dim) {
      case 1:
        substep<1>(x, v, hs);
        break;
      case 2:
        substep<2>(x, v, hs);
        break;
      default:
        substep<3>(x, v, hs);
        break;
    }
  }
  return Status::ok;
}

}  // namespace stiffbench
