#include "integrators/explicit/explicit_rk.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <thread>

#include <omp.h>

namespace stiffbench {

namespace {

// out_e = acc, and with Norm max |acc| into mx (nan_flag set to 1 when acc is NaN). Called
// from the loop bodies below with their reduction variables, so it updates the loop's copies.
template <bool Norm>
inline void store_entry(double* out, Index e, double acc, double& mx, double& nan_flag) {
  out[e] = acc;
  if constexpr (Norm) {
    const double a = std::abs(acc);
    nan_flag = a != a ? 1.0 : nan_flag;
    mx = a > mx ? a : mx;
  }
}

// out_e = base_e + c_0 k_0e + c_1 k_1e + … (left to right) for e in [begin, end). out may be
// base. M > 0 is the term count known at compile time, M = 0 a runtime count m. With Norm, also
// max |out_e| into mx (nan set when an entry is NaN).
template <int M, bool Norm>
void combine_range(Index begin, Index end, const double* base, int m, const double* const* k,
                   const double* c, double* out, double& mx, bool& nan) {
  // Local accumulators (not the references): the compiler vectorises the norm with them.
  double local_mx = mx, local_nan = 0.0;
  if constexpr (M > 0) {
    // The columns and coefficients in locals, and `omp simd`: without them GCC 12 could not rule
    // out that out overlaps a column or a coefficient, and for M = 4 with the norm (rk4's final
    // update) or with out == base (an update in place) ran the loop one entry at a time. Each
    // entry reads base_e and the k_je and then writes out_e only, so entries are independent
    // even when out is base; the per-entry arithmetic is the same in every lane (no contraction:
    // -ffp-contract=off), so the bits do not change.
    const double* cols[M];
    double cc[M];
    for (int j = 0; j < M; ++j) {
      cols[j] = k[j];
      cc[j] = c[j];
    }
#pragma omp simd reduction(max : local_mx, local_nan)
    for (Index e = begin; e < end; ++e) {
      double acc = base[e];
#pragma GCC unroll 4
      for (int j = 0; j < M; ++j) acc += cc[j] * cols[j][e];
      store_entry<Norm>(out, e, acc, local_mx, local_nan);
    }
  } else {
    for (Index e = begin; e < end; ++e) {
      double acc = base[e];
      for (int j = 0; j < m; ++j) acc += c[j] * k[j][e];
      store_entry<Norm>(out, e, acc, local_mx, local_nan);
    }
  }
  mx = local_mx;
  nan = nan || local_nan != 0.0;
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

using RangeFn = void (*)(Index, Index, const double*, int, const double* const*, const double*,
                         double*, double&, bool&);

template <bool Norm>
RangeFn range_fn(int m) {
  switch (m) {
    case 1:
      return &combine_range<1, Norm>;
    case 2:
      return &combine_range<2, Norm>;
    case 3:
      return &combine_range<3, Norm>;
    case 4:
      return &combine_range<4, Norm>;
    default:
      return &combine_range<0, Norm>;
  }
}

// One combination of the mechanical path (ExplicitRungeKutta::step_mechanical): base, its m
// terms' columns and coefficients, and where it goes.
struct Combination {
  const double* base;
  int m;
  const double* const* cols;
  const double* coefs;
  double* out;  // nullptr: not wanted
};

// Two combinations over entries [lo, hi) in one pass: sub-blocks of kSub entries, the first
// combination's then the second's, so the columns both read come from cache the second time.
// The first is computed before the second for every entry (the second may overwrite what the
// first reads). With Norm, max(‖out1‖∞, ‖out2‖∞) over the range into mx (nan set when an entry
// is NaN).
template <bool Norm>
void pair_range(Index lo, Index hi, const Combination& one, const Combination& two, double& mx,
                bool& nan) {
  constexpr Index kSub = 512;
  const RangeFn f1 = range_fn<Norm>(one.m), f2 = range_fn<Norm>(two.m);
  for (Index b = lo; b < hi; b += kSub) {
    const Index e = std::min(hi, b + kSub);
    if (one.out) f1(b, e, one.base, one.m, one.cols, one.coefs, one.out, mx, nan);
    if (two.out) f2(b, e, two.base, two.m, two.cols, two.coefs, two.out, mx, nan);
  }
}

// The s stages of one step as a wavefront over an AccelerationChain's blocks (header): task
// T(i, q) evaluates stage i on block q (its clear, link and finish calls) and runs the pass after
// it there, pass(i + 1, b, e) on the block's dofs [b, e) (row i + 1's stage values, or the update
// after the last stage). Sweep position p runs T(i, q) for q = p - i, i = 0 .. s-1 in that order,
// so T(i, q) comes after T(i - 1, q + 1) (its link reads stage i's values on block q + 1) and
// T(i, q - 1) (whose link added to block q), and before any task overwrites what it reads:
// T(i - 1, q + 1)'s pass overwrites stage i - 1's values on block q + 1 only after T(i - 1, q),
// and the update of block q (T(s - 1, q)) comes after every task that reads x or v there. On two
// threads the blocks split into [0, m) and [m, Q): the second sweeps up from m as above, the first
// down from m - 1 (the mirror image: T(i, q) links q - 1 and q), and the link between m - 1 and m
// is the first thread's, run once the second has cleared block m for that stage (which it does
// only after its pass of the stage before there) and awaited by the second before it finishes
// block m. Every entry gets the same terms in the same order on either schedule (no entry has
// terms from two links), so the bits do not depend on the threads. A call that throws stops both
// sweeps (a waiting sweep sees the failure) and its exception is rethrown after them; y is then
// partly updated (the caller must not use it).
template <class StageX, class StageV, class StageA, class Pass>
void chained_stages(const AccelerationChain& chain, int s, Index d, double t, double h,
                    const Vec& c, const StageX& stage_x, const StageV& stage_v,
                    const StageA& stage_a, const Pass& pass, bool two_threads) {
  const Index nq = chain.blocks();
  const auto x_of = [&](int i) { return Eigen::Map<const Vec>(stage_x(i), d); };
  const auto v_of = [&](int i) { return Eigen::Map<const Vec>(stage_v(i), d); };
  const auto a_of = [&](int i) { return Eigen::Map<Vec>(stage_a(i), d); };
  const auto clear = [&](int i, Index q) { chain.clear(q, a_of(i)); };
  const auto link = [&](int i, Index q) { chain.link(q, t + c[i] * h, x_of(i), v_of(i), a_of(i)); };
  const auto finish_and_pass = [&](int i, Index q) {
    chain.finish(q, t + c[i] * h, x_of(i), v_of(i), a_of(i));
    pass(i + 1, chain.begin(q), chain.begin(q + 1));
  };
  // Handshakes at the split: stages (counted from 1) for which the second thread has cleared
  // block m, and for which the first has added the link between m - 1 and m.
  std::atomic<int> cleared{0}, linked{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  // Waits until c reaches `stage` (false when the other sweep failed).
  const auto wait_for = [&](const std::atomic<int>& counter, int stage) {
    for (int spins = 0; counter.load(std::memory_order_acquire) < stage; ++spins) {
      if (failed.load(std::memory_order_relaxed)) return false;
      if (spins > 32) std::this_thread::yield();
    }
    return true;
  };
  // The sweep up over [m, nq); paired: the first thread sweeps [0, m).
  const auto up = [&](Index m, bool paired) {
    const Index len = nq - m;
    for (Index p = 0; p < len + s - 1; ++p)
      for (int i = 0; i < s; ++i) {
        const Index q = m + p - i;
        if (q < m || q >= nq) continue;
        if (q == m) {
          clear(i, q);
          if (paired) cleared.store(i + 1, std::memory_order_release);
        }
        if (q + 1 < nq) {
          clear(i, q + 1);
          link(i, q);
        }
        if (q == m && paired && !wait_for(linked, i + 1)) return;
        finish_and_pass(i, q);
      }
  };
  const auto down = [&](Index m) {
    for (Index p = 0; p < m + s - 1; ++p)
      for (int i = 0; i < s; ++i) {
        const Index q = m - 1 - (p - i);
        if (q < 0 || q >= m) continue;
        if (q == m - 1) {
          clear(i, q);
          if (!wait_for(cleared, i + 1)) return;
          link(i, q);
          linked.store(i + 1, std::memory_order_release);
        }
        if (q > 0) {
          clear(i, q - 1);
          link(i, q - 1);
        }
        finish_and_pass(i, q);
      }
  };
  const auto guarded = [&](const auto& sweep) {
    try {
      sweep();
    } catch (...) {
#pragma omp critical(stiffbench_chained_stages)
      if (!error) error = std::current_exception();
      failed.store(true, std::memory_order_relaxed);
    }
  };
  if (!two_threads) {
    guarded([&] { up(0, false); });
  } else {
#pragma omp parallel num_threads(2)
    {
      if (omp_get_num_threads() < 2)
        guarded([&] { up(0, false); });
      else if (omp_get_thread_num() == 0)
        guarded([&] { down(nq / 2); });
      else
        guarded([&] { up(nq / 2, true); });
    }
  }
  if (error) std::rethrow_exception(error);
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
  // The mechanical path's position combinations (header): row i < s has Σ_j a_ij on v and
  // (A²)_ik = Σ_j a_ij a_jk on A_k; row s has Σ_j b_j and (bA)_k = Σ_j b_j a_jk.
  const auto weight = [&](int i, int j) { return i < s ? tableau_.a(i, j) : tableau_.b[j]; };
  x_v_coef_.assign(static_cast<std::size_t>(s) + 1, 0.0);
  x_terms_.resize(static_cast<std::size_t>(s) + 1);
  x_coefs_.resize(static_cast<std::size_t>(s) + 1);
  for (int i = 0; i <= s; ++i) {
    const int row_end = i < s ? i : s;
    for (int j = 0; j < row_end; ++j) x_v_coef_[static_cast<std::size_t>(i)] += weight(i, j);
    for (int k = 0; k < row_end; ++k) {
      double c = 0.0;
      for (int j = k + 1; j < row_end; ++j) c += weight(i, j) * tableau_.a(j, k);
      if (c != 0.0) {
        x_terms_[static_cast<std::size_t>(i)].push_back(k);
        x_coefs_[static_cast<std::size_t>(i)].push_back(c);
      }
    }
  }
  // A stage position may instead be formed from the previous one still in the stage buffer,
  // X_i = X_j + h (r_i - r_j) v + h² Σ_k ((A²)_ik - (A²)_jk) A_k (j the last row before i that
  // formed one), in place: that pass writes the buffer it reads (no read for ownership of a
  // cold line) and, where r_i = r_j, reads no v (rk4's X_3 = X_2 + (h²/4) A_1: 3 vector streams
  // instead of 4, and no read for ownership). It is taken where it reads no more vectors than the
  // direct form.
  x_from_prev_.assign(static_cast<std::size_t>(s) + 1, false);
  // The differences are taken between the direct forms (a row converted below keeps its
  // differences in the same members, so the next row must not read those).
  const std::vector<double> direct_v = x_v_coef_;
  const std::vector<std::vector<int>> direct_terms = x_terms_;
  const std::vector<std::vector<double>> direct_coefs = x_coefs_;
  for (int i = 1, j = -1; i < s; ++i) {
    if (terms_[static_cast<std::size_t>(i)].empty()) continue;
    if (j >= 0) {
      const auto ui = static_cast<std::size_t>(i), uj = static_cast<std::size_t>(j);
      const double dv = direct_v[ui] - direct_v[uj];
      std::vector<double> delta(static_cast<std::size_t>(i), 0.0);
      for (std::size_t t2 = 0; t2 < direct_terms[ui].size(); ++t2)
        delta[static_cast<std::size_t>(direct_terms[ui][t2])] += direct_coefs[ui][t2];
      for (std::size_t t2 = 0; t2 < direct_terms[uj].size(); ++t2)
        delta[static_cast<std::size_t>(direct_terms[uj][t2])] -= direct_coefs[uj][t2];
      std::vector<int> d_terms;
      std::vector<double> d_coefs;
      for (int k = 0; k < i; ++k)
        if (delta[static_cast<std::size_t>(k)] != 0.0) {
          d_terms.push_back(k);
          d_coefs.push_back(delta[static_cast<std::size_t>(k)]);
        }
      // Vectors read: the base (x or X_j), v when its coefficient is non-zero, and the A_k.
      const std::size_t direct = 1 + (direct_v[ui] != 0.0 ? 1 : 0) + direct_terms[ui].size();
      const std::size_t from_prev = 1 + (dv != 0.0 ? 1 : 0) + d_terms.size();
      if (from_prev <= direct) {
        x_from_prev_[ui] = true;
        x_v_coef_[ui] = dv;
        x_terms_[ui] = std::move(d_terms);
        x_coefs_[ui] = std::move(d_coefs);
      }
    }
    j = i;
  }
  cols_.resize(static_cast<std::size_t>(s));
  scaled_.resize(static_cast<std::size_t>(s));
  for (auto* w : {&row_x_cols_, &row_v_cols_}) w->resize(static_cast<std::size_t>(s) + 1);
  for (auto* w : {&row_x_scaled_, &row_v_scaled_}) w->resize(static_cast<std::size_t>(s) + 1);
  row_x_count_.assign(static_cast<std::size_t>(s) + 1, 0);
  for (std::size_t i = 0; i <= static_cast<std::size_t>(s); ++i) {
    row_x_cols_[i].resize(1 + x_terms_[i].size());
    row_x_scaled_[i].resize(1 + x_terms_[i].size());
    row_v_cols_[i].resize(terms_[i].size());
    row_v_scaled_[i].resize(terms_[i].size());
  }
}

void ExplicitRungeKutta::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  k_.resize(sys.dimension(), tableau_.stages());
  ytmp_.resize(sys.dimension());
  norm_valid_ = false;
}

Status ExplicitRungeKutta::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  const int s = tableau_.stages();
  norm_valid_ = false;
  if (const MechanicalSystem* mech = sys.as_mechanical()) return step_mechanical(*mech, t, y, h);
  const Index n = y.size();
  // y + Σ (h c_j) k_j over row i's non-zero terms into out.
  const auto combine_row = [&](int i, double* out) {
    const auto& terms = terms_[static_cast<std::size_t>(i)];
    const auto& coefs = coefs_[static_cast<std::size_t>(i)];
    const int m = static_cast<int>(terms.size());
    for (int j = 0; j < m; ++j) {
      cols_[static_cast<std::size_t>(j)] = k_.col(terms[static_cast<std::size_t>(j)]).data();
      scaled_[static_cast<std::size_t>(j)] = h * coefs[static_cast<std::size_t>(j)];
    }
    if (i == s) return combine<true>(n, y.data(), m, cols_.data(), scaled_.data(), out);
    return combine<false>(n, y.data(), m, cols_.data(), scaled_.data(), out);
  };
  for (int i = 0; i < s; ++i) {
    const double ti = t + tableau_.c[i] * h;
    if (terms_[static_cast<std::size_t>(i)].empty()) {
      sys.rhs(ti, y, k_.col(i));  // the stage argument is y itself
    } else {
      combine_row(i, ytmp_.data());
      sys.rhs(ti, ytmp_, k_.col(i));
    }
  }
  if (!terms_[static_cast<std::size_t>(s)].empty()) {
    last_norm_ = combine_row(s, y.data());
    norm_valid_ = true;
  }
  return Status::ok;
}

// y = [x; v], f = [v; a]: the method written in its accelerations alone (header). k_'s columns
// hold A_i in their v-part; X_i goes to ytmp_'s head and V_i, when a depends on v, to its tail.
// Each pass runs inside the evaluation before it: on each range of dofs as soon as the system
// has finished it (acceleration_in_ranges), or block by block in a wavefront over the stages
// (chained_stages), while that range's A_i, X_i and V_i are in cache.
Status ExplicitRungeKutta::step_mechanical(const MechanicalSystem& mech, double t, VecRef y,
                                           double h) {
  const int s = tableau_.stages();
  const Index d = mech.dofs();
  double* x = y.data();
  double* v = y.data() + d;
  const bool need_v = mech.velocity_dependent();
  // Row i's two combinations, in row i's own workspace (so that the passes of several rows may
  // run at once): positions x + (h r_i) v + Σ (h² c_k) A_k into x_out (or, for a row formed from
  // the previous stage position, x_out + (h Δr) v + Σ (h² Δc_k) A_k in place), velocities
  // v + Σ (h a_ij) A_j into v_out (nullptr: not formed). Rows i < s write the stage buffer, row s
  // (the update) y itself.
  const auto prepare_row = [&](int i) {
    const auto u = static_cast<std::size_t>(i);
    int mx = 0;
    if (x_v_coef_[u] != 0.0) {
      row_x_cols_[u][0] = v;
      row_x_scaled_[u][0] = h * x_v_coef_[u];
      mx = 1;
    }
    for (std::size_t t2 = 0; t2 < x_terms_[u].size(); ++t2, ++mx) {
      row_x_cols_[u][static_cast<std::size_t>(mx)] = k_.col(x_terms_[u][t2]).data() + d;
      row_x_scaled_[u][static_cast<std::size_t>(mx)] = h * h * x_coefs_[u][t2];
    }
    row_x_count_[u] = mx;
    for (std::size_t j = 0; j < terms_[u].size(); ++j) {
      row_v_cols_[u][j] = k_.col(terms_[u][j]).data() + d;
      row_v_scaled_[u][j] = h * coefs_[u][j];
    }
  };
  // Row i's combinations from its prepared workspace (read only: several rows' passes may run
  // at once).
  const auto combinations = [&](int i) {
    const auto u = static_cast<std::size_t>(i);
    double* x_out = i < s ? ytmp_.data() : x;
    double* v_out = i < s ? (need_v ? ytmp_.data() + d : nullptr) : v;
    return std::pair{Combination{x_from_prev_[u] ? x_out : x, row_x_count_[u],
                                 row_x_cols_[u].data(), row_x_scaled_[u].data(), x_out},
                     Combination{v, static_cast<int>(terms_[u].size()), row_v_cols_[u].data(),
                                 row_v_scaled_[u].data(), v_out}};
  };
  // The update's ‖y‖∞ over the ranges, which may finish on several threads at once (max is
  // order-independent: the same value for any thread count).
  std::atomic<double> norm{0.0};
  std::atomic<bool> nan{false};
  // Row i's pass over dofs [b, e) (positions first in each block: they read v before the
  // update's velocities overwrite it).
  const auto pass = [&](int i, Index b, Index e) {
    const auto [cx, cv] = combinations(i);
    double mx = 0.0;
    bool n = false;
    if (i < s) return pair_range<false>(b, e, cx, cv, mx, n);
    pair_range<true>(b, e, cx, cv, mx, n);
    if (n) nan.store(true, std::memory_order_relaxed);
    for (double cur = norm.load(std::memory_order_relaxed);
         mx > cur && !norm.compare_exchange_weak(cur, mx, std::memory_order_relaxed);) {
    }
  };
  // A row without terms evaluates at y itself and needs no pass.
  const auto has_pass = [&](int i) { return !terms_[static_cast<std::size_t>(i)].empty(); };
  bool all_passes = true;
  for (int i = 1; i <= s; ++i) all_passes = all_passes && has_pass(i);
  const AccelerationChain* chain = mech.acceleration_chain();
  if (chain && all_passes && omp_get_max_threads() <= 2) {
    for (int i = 1; i <= s; ++i) prepare_row(i);
    for (int i = 0; i < s; ++i) mech.count_chained_evaluation();  // may throw: before any work
    // Stage i's arguments: y itself for the first (no row), the stage buffer after.
    const auto stage_x = [&](int i) { return i == 0 ? x : ytmp_.data(); };
    const auto stage_v = [&](int i) { return i == 0 || !need_v ? v : ytmp_.data() + d; };
    const auto stage_a = [&](int i) { return k_.col(i).data() + d; };
    chained_stages(*chain, s, d, t, h, tableau_.c, stage_x, stage_v, stage_a, pass,
                   d >= kParallelChainDofs && chain->blocks() >= 2 && omp_get_max_threads() == 2);
  } else {
    for (int i = 0; i < s; ++i) {
      const double ti = t + tableau_.c[i] * h;
      auto a_i = k_.col(i).tail(d);
      const bool at_y = !has_pass(i);
      const Eigen::Map<const Vec> stage_x(at_y ? x : ytmp_.data(), d);
      const Eigen::Map<const Vec> stage_v(at_y || !need_v ? v : ytmp_.data() + d, d);
      // The pass after this stage: the next row's, or the update after the last stage.
      if (!has_pass(i + 1)) {
        mech.acceleration(ti, stage_x, stage_v, a_i);
        continue;
      }
      prepare_row(i + 1);
      const auto ranges = [&](Index b, Index e) { pass(i + 1, b, e); };
      mech.acceleration_in_ranges(ti, stage_x, stage_v, a_i, ranges);
    }
  }
  if (has_pass(s)) {
    last_norm_ = nan.load() ? std::numeric_limits<double>::quiet_NaN() : norm.load();
    norm_valid_ = true;
  }
  return Status::ok;
}

}  // namespace stiffbench
