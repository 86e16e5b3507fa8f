#include "integrators/explicit/explicit_rk.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stiffbench {

namespace {

// out_e = base_e + c_0 k_0e + c_1 k_1e + … (left to right) for e in [begin, end). out may be
// base. M > 0 is the term count known at compile time, M = 0 a runtime count m. With Norm, also
// max |out_e| into mx (nan set when an entry is NaN).
template <int M, bool Norm>
void combine_range(Index begin, Index end, const double* base, int m, const double* const* k,
                   const double* c, double* out, double& mx, bool& nan) {
  const int terms = M > 0 ? M : m;
  for (Index e = begin; e < end; ++e) {
    double acc = base[e];
    for (int j = 0; j < terms; ++j) acc += c[j] * k[j][e];
    out[e] = acc;
    if constexpr (Norm) {
      const double a = std::abs(acc);
      nan = nan || std::isnan(a);
      mx = a > mx ? a : mx;
    }
  }
}

// The combination over all entries; returns ‖out‖∞ with Norm (NaN when an entry is NaN; max is
// order-independent, so the same for any thread count), 0 without.
template <int M, bool Norm>
double combine_all(Index n, const double* base, int m, const double* const* k, const double* c,
                   double* out) {
  double mx = 0.0;
  bool nan = false;
  if (n >= ExplicitRungeKutta::kParallelEntries) {
    const Index chunks = 64;  // contiguous ranges; each entry's arithmetic is the same anyway
#pragma omp parallel for schedule(static) reduction(max : mx) reduction(|| : nan)
    for (Index q = 0; q < chunks; ++q)
      combine_range<M, Norm>(n * q / chunks, n * (q + 1) / chunks, base, m, k, c, out, mx, nan);
  } else {
    combine_range<M, Norm>(0, n, base, m, k, c, out, mx, nan);
  }
  return nan ? std::numeric_limits<double>::quiet_NaN() : mx;
}

template <bool Norm>
double combine(Index n, const double* base, int m, const double* const* k, const double* c,
               double* out) {
  switch (m) {
    case 1:
      return combine_all<1, Norm>(n, base, m, k, c, out);
    case 2:
      return combine_all<2, Norm>(n, base, m, k, c, out);
    case 3:
      return combine_all<3, Norm>(n, base, m, k, c, out);
    case 4:
      return combine_all<4, Norm>(n, base, m, k, c, out);
    default:
      return combine_all<0, Norm>(n, base, m, k, c, out);
  }
}

}  // namespace

ExplicitRungeKutta::ExplicitRungeKutta(ButcherTableau tableau, std::string description)
    : Integrator({tableau.name,
                  Family::explicit_rk,
                  tableau.order,
                  tableau.stages(),
                  {},
                  std::move(description)}),
      tableau_(std::move(tableau)) {
  // BadInput naming the defect (sizes, nodes, claimed order, shape); completes an empty c.
  tableau_.validate(ButcherTableau::Shape::explicit_rk);
  const int s = tableau_.stages();
  terms_.resize(static_cast<std::size_t>(s) + 1);
  coefs_.resize(static_cast<std::size_t>(s) + 1);
  for (int i = 0; i <= s; ++i)
    for (int j = 0; j < (i < s ? i : s); ++j)
      if (const double c = i < s ? tableau_.a(i, j) : tableau_.b[j]; c != 0.0) {
        terms_[static_cast<std::size_t>(i)].push_back(j);
        coefs_[static_cast<std::size_t>(i)].push_back(c);
      }
  cols_.resize(static_cast<std::size_t>(s));
  scaled_.resize(static_cast<std::size_t>(s));
}

void ExplicitRungeKutta::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  k_.resize(sys.dimension(), tableau_.stages());
  ytmp_.resize(sys.dimension());
  norm_valid_ = false;
}

Status ExplicitRungeKutta::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  const int s = tableau_.stages();
  const Index n = y.size();
  // base + Σ (h c_j) k_j over row i's non-zero terms, entries [lo, lo + len) of base, out and
  // the columns of k_. With y_v (the mechanical path below, x-part only), a stage whose row of A
  // is zero contributes y's v-part in place of its column.
  const auto combine_rows = [&](int i, Index lo, Index len, const double* base, double* out,
                                const double* y_v) {
    const auto& terms = terms_[static_cast<std::size_t>(i)];
    const auto& coefs = coefs_[static_cast<std::size_t>(i)];
    const int m = static_cast<int>(terms.size());
    for (int j = 0; j < m; ++j) {
      const int col = terms[static_cast<std::size_t>(j)];
      const bool at_y = y_v != nullptr && terms_[static_cast<std::size_t>(col)].empty();
      cols_[static_cast<std::size_t>(j)] = at_y ? y_v : k_.col(col).data() + lo;
      scaled_[static_cast<std::size_t>(j)] = h * coefs[static_cast<std::size_t>(j)];
    }
    if (i == s) return combine<true>(len, base + lo, m, cols_.data(), scaled_.data(), out);
    return combine<false>(len, base + lo, m, cols_.data(), scaled_.data(), out);
  };
  norm_valid_ = false;
  const MechanicalSystem* mech = sys.as_mechanical();
  if (mech == nullptr) {
    for (int i = 0; i < s; ++i) {
      const double ti = t + tableau_.c[i] * h;
      if (terms_[static_cast<std::size_t>(i)].empty()) {
        sys.rhs(ti, y, k_.col(i));  // the stage argument is y itself
      } else {
        combine_rows(i, 0, n, y.data(), ytmp_.data(), nullptr);
        sys.rhs(ti, ytmp_, k_.col(i));
      }
    }
    if (!terms_[static_cast<std::size_t>(s)].empty()) {
      last_norm_ = combine_rows(s, 0, n, y.data(), y.data(), nullptr);
      norm_valid_ = true;
    }
    return Status::ok;
  }
  // y = [x; v], f = [v; a] (MechanicalSystem::eval_rhs is final): the x-part of k_i is stage
  // i's velocity V_i itself. Stage i writes X_i into ytmp_'s head and V_i straight into k_i's
  // x-part, so no stage copies v into k; a stage with a zero row of A (the first) has V = y's
  // v-part, read from y. Every entry gets the same operations as on the general path above, so
  // the results are bitwise the same (the test compares); only the copies are gone.
  const Index d = mech->dofs();
  const double* y_v = y.data() + d;
  for (int i = 0; i < s; ++i) {
    const double ti = t + tableau_.c[i] * h;
    auto a_i = k_.col(i).tail(d);
    if (terms_[static_cast<std::size_t>(i)].empty()) {
      mech->acceleration(ti, y.head(d), y.tail(d), a_i);
      continue;
    }
    combine_rows(i, 0, d, y.data(), ytmp_.data(), y_v);          // X_i
    combine_rows(i, d, d, y.data(), k_.col(i).data(), nullptr);  // V_i
    mech->acceleration(ti, ytmp_.head(d), k_.col(i).head(d), a_i);
  }
  if (!terms_[static_cast<std::size_t>(s)].empty()) {
    // The x-part first: it reads y's v-part (V of a zero-row stage) before the v-part is updated.
    const double mx = combine_rows(s, 0, d, y.data(), y.data(), y_v);
    const double mv = combine_rows(s, d, d, y.data(), y.data() + d, nullptr);
    last_norm_ = std::isnan(mx) || std::isnan(mv) ? std::numeric_limits<double>::quiet_NaN()
                                                  : std::max(mx, mv);
    norm_valid_ = true;
  }
  return Status::ok;
}

}  // namespace stiffbench
