// The mass-spring right-hand side's spring kernel (models/mass_spring/spring_kernel.cpp: springs in
// structure-of-arrays order, several per SIMD lane, partitions and cross-partition groups),
// checked against a straightforward evaluation written here, one spring at a time from the
// formulas of network.hpp (Baraff & Witkin 1998):
//   f_i += k (l - L) d + c ((v_j - v_i)·d) d,  f_j -= the same,  d = (x_j - x_i)/l,
//   a_i = g + (f_i - γ v_i)/m_i (free points), 0 (pinned points).
// The two differ only in rounding: each force is a sum of at most N terms, so the difference is
// bounded by N ε Σ|terms| (Higham, "Accuracy and Stability of Numerical Algorithms", 2002,
// §4.2), checked per coordinate with N = 64. Also: the same bits at 1 and 2 OpenMP threads and on
// the serial path.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

#include "models/mass_spring/network.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

const MassSpringNetwork& net(const OdeSystem& sys) {
  const auto* n = dynamic_cast<const MassSpringNetwork*>(&sys);
  if (!n) throw std::logic_error(sys.name() + " is not a MassSpringNetwork");
  return *n;
}

// Which springs the reference sums: all, or one part of split=stretch.
enum class Which { all, structural_only, others_only };

struct Reference {
  Vec a;    // accelerations
  Vec mag;  // Σ |terms| of each coordinate (the rounding bound's scale)
};

// One spring at a time, from the formulas above (independent of the kernel's layout and order).
Reference reference(const MassSpringNetwork& n, const Vec& y, Which which) {
  const int dim = n.dim();
  const Index nd = n.dofs();
  const NetworkOptions& o = n.options();
  Vec f = Vec::Zero(nd), mag = Vec::Zero(nd);
  for (const Spring& s : n.springs()) {
    if (which == Which::structural_only && s.kind != SpringKind::structural) continue;
    if (which == Which::others_only && s.kind == SpringKind::structural) continue;
    std::vector<double> d(static_cast<std::size_t>(dim));
    double l2 = 0.0;
    for (int c = 0; c < dim; ++c) {
      d[static_cast<std::size_t>(c)] = y[dim * s.j + c] - y[dim * s.i + c];
      l2 += d[static_cast<std::size_t>(c)] * d[static_cast<std::size_t>(c)];
    }
    const double l = std::sqrt(l2);
    double ud = 0.0;
    for (int c = 0; c < dim; ++c) {
      d[static_cast<std::size_t>(c)] /= l;
      ud += (y[nd + dim * s.j + c] - y[nd + dim * s.i + c]) * d[static_cast<std::size_t>(c)];
    }
    for (int c = 0; c < dim; ++c) {
      const double dc = d[static_cast<std::size_t>(c)];
      const double spring = s.k * (l - s.rest) * dc, dashpot = s.damping * ud * dc;
      f[dim * s.i + c] += spring + dashpot;
      f[dim * s.j + c] -= spring + dashpot;
      const double m = std::abs(spring) + std::abs(dashpot);
      mag[dim * s.i + c] += m;
      mag[dim * s.j + c] += m;
    }
  }
  Reference r{Vec::Zero(nd), Vec::Zero(nd)};
  for (Index p = 0; p < n.num_points(); ++p) {
    const MassPoint& pt = n.points()[static_cast<std::size_t>(p)];
    if (pt.pinned) continue;
    for (int c = 0; c < dim; ++c) {
      const Index i = dim * p + c;
      double g = o.gravity[static_cast<std::size_t>(c)], gamma = o.point_damping;
      if (which == Which::structural_only) g = gamma = 0.0;  // a_I: springs and dashpots only
      r.a[i] = g + (f[i] - gamma * y[nd + i]) / pt.mass;
      r.mag[i] = std::abs(g) + (mag[i] + std::abs(gamma * y[nd + i])) / pt.mass;
    }
  }
  return r;
}

// y0 with free coordinates displaced uniformly in [-dx, dx], velocities in [-dv, dv].
Vec perturbed(const MassSpringNetwork& n, double dx, double dv, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec y = n.initial_state();
  const Index nd = n.dofs();
  for (Index p = 0; p < n.num_points(); ++p) {
    if (n.points()[static_cast<std::size_t>(p)].pinned) continue;
    for (int c = 0; c < n.dim(); ++c) {
      y[n.dim() * p + c] += dx * u(rng);
      y[nd + n.dim() * p + c] = dv * u(rng);
    }
  }
  return y;
}

// max over coordinates of |a - a_ref| / (64 ε Σ|terms|): <= 1 when within the rounding bound.
double error_in_bounds(const Vec& a, const Reference& ref) {
  const double eps = std::numeric_limits<double>::epsilon();
  double worst = 0.0;
  for (Index i = 0; i < a.size(); ++i) {
    const double bound = 64.0 * eps * ref.mag[i];
    const double diff = std::abs(a[i] - ref.a[i]);
    worst = std::max(worst, bound > 0 ? diff / bound : (diff == 0 ? 0.0 : 1e300));
  }
  return worst;
}

Vec acceleration(const MassSpringNetwork& n, const Vec& y, int threads, Which part = Which::all) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  const Index nd = n.dofs();
  Vec f(2 * nd);
  if (part == Which::all)
    n.rhs(0.0, y, f);
  else if (part == Which::structural_only)
    n.rhs_implicit_part(0.0, y, f);
  else
    n.rhs_explicit_part(0.0, y, f);
  omp_set_num_threads(saved);
  return f.tail(nd);
}

// A 96² cloth (9,216 points: 32 partitions, the parallel path) with structural, shear and bend
// springs, dashpots, point damping, gravity and two pinned corners, at a randomly perturbed
// state with every spring stretched or compressed.
TEST(SpringKernel, ClothMatchesOneSpringAtATimeAndThreadCounts) {
  const auto sys = testing_support::model(
      "cloth", {"n=96", "dashpot=0.03", "damping=0.02", "pin=corners", "k_shear=300"});
  const MassSpringNetwork& n = net(*sys);
  ASSERT_TRUE(n.parallel());
  bool kinds[3] = {false, false, false};
  for (const Spring& s : n.springs()) kinds[static_cast<int>(s.kind)] = true;
  ASSERT_TRUE(kinds[0] && kinds[1] && kinds[2]);
  const Vec y = perturbed(n, 0.2 * n.springs()[0].rest, 0.7, 7);
  const Reference ref = reference(n, y, Which::all);
  const Vec a1 = acceleration(n, y, 1), a2 = acceleration(n, y, 2);
  EXPECT_LE(error_in_bounds(a1, ref), 1.0);
  EXPECT_GT(ref.a.cwiseAbs().maxCoeff(), 1.0);  // the forces are not trivially zero
  EXPECT_TRUE(a1 == a2);
  // The serial path (below the parallel threshold) sums in the same order.
  const auto ser =
      testing_support::model("cloth", {"n=96", "dashpot=0.03", "damping=0.02", "pin=corners",
                                       "k_shear=300", "parallel_threshold=100000"});
  ASSERT_FALSE(net(*ser).parallel());
  EXPECT_TRUE(acceleration(net(*ser), y, 2) == a1);
}

// The two parts of split=stretch (the kernel's per-spring selection): a_I the structural springs
// and their dashpots, a_E the others with gravity and point damping.
TEST(SpringKernel, StretchSplitPartsMatchOneSpringAtATime) {
  const auto sys = testing_support::model(
      "cloth", {"n=64", "dashpot=0.03", "damping=0.02", "pin=corners", "split=stretch"});
  const MassSpringNetwork& n = net(*sys);
  const Vec y = perturbed(n, 0.2 * n.springs()[0].rest, 0.7, 11);
  const Vec ai = acceleration(n, y, 2, Which::structural_only);
  const Vec ae = acceleration(n, y, 2, Which::others_only);
  EXPECT_LE(error_in_bounds(ai, reference(n, y, Which::structural_only)), 1.0);
  EXPECT_LE(error_in_bounds(ae, reference(n, y, Which::others_only)), 1.0);
  EXPECT_TRUE(ai == acceleration(n, y, 1, Which::structural_only));
  EXPECT_TRUE(ae == acceleration(n, y, 1, Which::others_only));
}

// A random 3D network: springs between any two of 4,096 points (so between partitions far apart:
// the serial group of cross springs), each with its own stiffness, rest length and dashpot (4,000
// distinct (k, L) pairs: the kernel's table of pairs past its short linear search).
TEST(SpringKernel, RandomNetworkMatchesOneSpringAtATimeAndThreadCounts) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Index np = 4096;
  std::vector<MassPoint> points(static_cast<std::size_t>(np));
  for (std::size_t p = 0; p < points.size(); ++p) {
    points[p].mass = 0.5 + u(rng);
    points[p].x = {u(rng), u(rng), u(rng)};
    points[p].v = {u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
    points[p].pinned = p % 97 == 0;
  }
  std::vector<Spring> springs;
  std::uniform_int_distribution<Index> any(0, np - 1);
  for (int e = 0; e < 20000; ++e) {
    Spring s;
    s.i = any(rng);
    s.j = any(rng);
    if (s.i == s.j) continue;
    if (e % 5 == 0) s.j = (s.i + 1) % np;  // some springs inside a partition too
    const bool shared = e % 5 == 1;        // and some sharing one (k, L) pair
    s.k = shared ? 100.0 : 50.0 + static_cast<double>(e % 4000);
    s.rest = shared ? 0.25 : 0.1 + 0.5 * u(rng);
    s.damping = e % 3 == 0 ? 0.0 : 0.1 * u(rng);
    s.kind = static_cast<SpringKind>(e % 3);
    springs.push_back(s);
  }
  NetworkOptions opt;
  opt.gravity = {0.0, -9.81, 0.0};
  opt.point_damping = 0.05;
  const MassSpringNetwork n("random_network", 3, points, springs, opt);
  ASSERT_TRUE(n.parallel());
  const Vec y = n.initial_state();
  const Reference ref = reference(n, y, Which::all);
  const Vec a1 = acceleration(n, y, 1), a2 = acceleration(n, y, 2);
  EXPECT_LE(error_in_bounds(a1, ref), 1.0);
  EXPECT_TRUE(a1 == a2);
  opt.parallel_threshold = 100000;
  const MassSpringNetwork ser("random_network", 3, points, springs, opt);
  EXPECT_TRUE(acceleration(ser, y, 2) == a1);
}

// Runs and loose springs in one network (2D, 4,096 points): a chain (i, i+1) across every
// partition (runs inside, single springs between partitions), a reversed run (i + 5, i) with its
// own dashpot per spring, a run of 5 (shorter than a run: loose), a repeated run (each spring
// twice), a pinned point inside a run, and random springs. The kernel's packing puts these in
// runs and loose lists; the sums must stay within the rounding bound of the one-spring-at-a-time
// reference and give the same bits at 1 and 2 threads and on the serial path.
TEST(SpringKernel, RunsAndLooseSpringsMatchOneSpringAtATime) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Index np = 4096;
  std::vector<MassPoint> points(static_cast<std::size_t>(np));
  for (std::size_t p = 0; p < points.size(); ++p) {
    points[p].mass = 0.5 + u(rng);
    points[p].x = {0.01 * static_cast<double>(p) + 0.003 * u(rng), 0.01 * u(rng), 0.0};
    points[p].v = {u(rng) - 0.5, u(rng) - 0.5, 0.0};
    points[p].pinned = p == 777;
  }
  std::vector<Spring> springs;
  const auto add = [&](Index i, Index j, double k, double rest, double damping) {
    springs.push_back({i, j, k, rest, damping, SpringKind::structural});
  };
  for (Index i = 0; i + 1 < np; ++i) add(i, i + 1, 100.0, 0.01, 0.0);
  for (Index i = 300; i < 340; ++i) add(i + 5, i, 40.0, 0.05, 0.2 * u(rng));
  for (Index i = 1000; i < 1005; ++i) add(i, i + 3, 60.0, 0.03, 0.1);
  for (int twice = 0; twice < 2; ++twice)
    for (Index i = 2000; i < 2100; ++i) add(i, i + 2, 80.0, 0.02, 0.0);
  std::uniform_int_distribution<Index> any(0, np - 1);
  for (int e = 0; e < 3000; ++e) {
    const Index i = any(rng), j = any(rng);
    if (i != j) add(i, j, 50.0 + static_cast<double>(e % 7), 0.1 * u(rng), 0.05 * u(rng));
  }
  NetworkOptions opt;
  opt.gravity = {0.0, -9.81, 0.0};
  opt.point_damping = 0.05;
  const MassSpringNetwork n("runs_network", 2, points, springs, opt);
  ASSERT_TRUE(n.parallel());
  const Vec y = perturbed(n, 0.002, 0.5, 9);
  const Reference ref = reference(n, y, Which::all);
  const Vec a1 = acceleration(n, y, 1), a2 = acceleration(n, y, 2);
  EXPECT_LE(error_in_bounds(a1, ref), 1.0);
  EXPECT_GT(ref.a.cwiseAbs().maxCoeff(), 1.0);
  EXPECT_TRUE(a1 == a2);
  opt.parallel_threshold = 100000;
  const MassSpringNetwork ser("runs_network", 2, points, springs, opt);
  EXPECT_TRUE(acceleration(ser, y, 2) == a1);
}

// The builds of the kernel (portable, AVX2, AVX-512 runs in 3D; MassSpringNetwork::kernel_isa)
// perform the same operations in the same order, so they must give the same bits, not merely
// agree to rounding. Checked for each build this processor has, against the portable one, on
// the dashpot cloth, both parts of split=stretch, and a 3D network of runs whose lengths leave
// every remainder of eight springs and cross blocks of 128 springs, with per-spring dashpots of
// which some are zero.
TEST(SpringKernel, EveryBuildGivesThePortableBits) {
  const auto cloth = testing_support::model(
      "cloth", {"n=96", "dashpot=0.03", "damping=0.02", "pin=corners", "k_shear=300"});
  const auto split = testing_support::model(
      "cloth", {"n=64", "dashpot=0.03", "damping=0.02", "pin=corners", "split=stretch"});
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Index np = 4096;
  std::vector<MassPoint> points(static_cast<std::size_t>(np));
  for (std::size_t p = 0; p < points.size(); ++p) {
    points[p].mass = 0.5 + u(rng);
    points[p].x = {0.01 * static_cast<double>(p) + 0.003 * u(rng), 0.01 * u(rng), 0.01 * u(rng)};
    points[p].v = {u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
    points[p].pinned = p == 777;
  }
  std::vector<Spring> springs;
  const auto add = [&](Index i, Index j, double k, double rest, double damping) {
    springs.push_back({i, j, k, rest, damping, SpringKind::structural});
  };
  for (Index i = 0; i + 1 < np; ++i) add(i, i + 1, 100.0, 0.01, 0.0);
  Index start = 200;
  for (Index len = 8; len < 24; ++len, start += len + 4)  // remainders 0..7 of eight springs
    for (Index i = start; i < start + len; ++i)
      add(i, i + 3, 60.0 + static_cast<double>(len), 0.03, 0.0);
  for (Index i = 1000; i < 1300; ++i)  // 300 springs: two full blocks and one of 44
    add(i + 5, i, 40.0, 0.05, i % 3 == 0 ? 0.0 : 0.2 * u(rng));
  NetworkOptions opt;
  opt.gravity = {0.0, -9.81, 0.0};
  opt.point_damping = 0.05;
  const MassSpringNetwork runs("runs_network_3d", 3, points, springs, opt);
  ASSERT_TRUE(runs.parallel());

  const SpringKernelIsa widest = MassSpringNetwork::kernel_isa();
  std::cout << "[ info ] widest spring kernel on this processor: " << to_string(widest) << "\n";
  struct Case {
    const MassSpringNetwork* n;
    Which part;
    Vec y;
  };
  std::vector<Case> cases;
  const MassSpringNetwork& c = net(*cloth);
  const MassSpringNetwork& sp = net(*split);
  cases.push_back({&c, Which::all, perturbed(c, 0.2 * c.springs()[0].rest, 0.7, 7)});
  const Vec ys = perturbed(sp, 0.2 * sp.springs()[0].rest, 0.7, 11);
  cases.push_back({&sp, Which::structural_only, ys});
  cases.push_back({&sp, Which::others_only, ys});
  cases.push_back({&runs, Which::all, perturbed(runs, 0.002, 0.5, 9)});
  std::vector<Vec> portable;
  MassSpringNetwork::limit_kernel_isa(SpringKernelIsa::portable);
  ASSERT_EQ(MassSpringNetwork::kernel_isa(), SpringKernelIsa::portable);
  for (const Case& k : cases) portable.push_back(acceleration(*k.n, k.y, 2, k.part));
  EXPECT_LE(error_in_bounds(portable.back(), reference(runs, cases.back().y, Which::all)), 1.0);
  for (int isa = 1; isa <= static_cast<int>(widest); ++isa) {
    MassSpringNetwork::limit_kernel_isa(static_cast<SpringKernelIsa>(isa));
    for (std::size_t t = 0; t < cases.size(); ++t)
      for (int threads : {1, 2})
        EXPECT_TRUE(acceleration(*cases[t].n, cases[t].y, threads, cases[t].part) == portable[t])
            << to_string(static_cast<SpringKernelIsa>(isa)) << ", case " << t << ", " << threads
            << " threads";
  }
  MassSpringNetwork::limit_kernel_isa(SpringKernelIsa::avx512);
  EXPECT_EQ(MassSpringNetwork::kernel_isa(), widest);
}

}  // namespace
}  // namespace stiffbench
