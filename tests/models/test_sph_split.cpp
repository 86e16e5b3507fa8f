// The SPH fluid's additive split (split=viscosity, models/sph/sph_fluid.hpp) and its
// angular momentum: the parts add up to f; split=none and the full f of a split model
// are the unsplit right-hand side bit for bit; the parts are bitwise independent of the thread
// count; a_I is linear in v for Müller's viscosity (positively homogeneous only for Monaghan's);
// an IMEX run stable at a step where rk4 blows up; angular momentum conserved by the symplectic
// methods on a spinning free drop with central pair forces and not with Müller's viscosity.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "models/sph/sph_fluid.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

constexpr double kEps = 2.220446049250313e-16;  // machine epsilon (double)

const SphFluid& fluid(const OdeSystem& sys) {
  const auto* f = dynamic_cast<const SphFluid*>(&sys);
  if (!f) throw std::logic_error(sys.name() + " is not an SphFluid");
  return *f;
}

struct Scene {
  std::string model;
  std::vector<std::string> params;
};

std::vector<std::string> with(std::vector<std::string> p, const std::vector<std::string>& extra) {
  p.insert(p.end(), extra.begin(), extra.end());
  return p;
}

// Small 2D and 3D scenes with a viscosity on, boundary particles or penalty walls, gravity.
std::vector<Scene> viscous_scenes() {
  return {
      {"sph_tank_2d", {"n=6", "width=0.1", "viscosity=muller", "mu=1"}},
      {"sph_tank_2d", {"n=6", "width=0.1", "viscosity=artificial", "alpha=0.5"}},
      {"sph_dam_break_2d", {"n=4", "boundary=penalty", "viscosity=muller", "mu=1"}},
      {"sph_drop_2d", {"n=8", "viscosity=artificial", "alpha=1"}},
      {"sph_tank_3d", {"n=4", "width=0.1", "viscosity=muller", "mu=1"}},
      {"sph_tank_3d",
       {"n=4", "width=0.1", "viscosity=artificial", "alpha=0.5", "boundary=penalty"}},
  };
}

std::string label(const Scene& s) {
  std::string out = s.model;
  for (const auto& p : s.params) out += " " + p;
  return out;
}

// The initial state with every position moved by up to 0.1 Δx and every velocity set to up to
// 0.2 m/s per component (uniform in [-1, 1]): every pair compresses or separates, so both
// viscosities and the pressure act.
Vec moved_state(const SphFluid& f, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec y = f.initial_state();
  const double dx = f.options().spacing;
  for (Index i = 0; i < f.dofs(); ++i) {
    y[i] += 0.1 * dx * u(rng);
    y[f.dofs() + i] = 0.2 * u(rng);
  }
  return y;
}

enum class Which { all, explicit_part, implicit_part };

Vec accel(const SphFluid& f, CVecRef x, CVecRef v, Which w) {
  Vec a(f.dofs());
  if (w == Which::all) f.acceleration(0.0, x, v, a);
  if (w == Which::explicit_part) f.acceleration_explicit_part(0.0, x, v, a);
  if (w == Which::implicit_part) f.acceleration_implicit_part(0.0, x, v, a);
  return a;
}

Vec accel(const SphFluid& f, CVecRef y, Which w) {
  return accel(f, y.head(f.dofs()), y.tail(f.dofs()), w);
}

// ---------------------------------------------------------------------------------------------
// The parts.

// a_E + a_I = a up to rounding: each component of a is gravity plus a sum over at most ~100
// neighbours (3D, boundary particles included) of pressure and viscosity terms, which the parts
// sum in two groups (pressure terms and gravity in a_E, viscosity terms in a_I; the artificial
// viscosity's term leaves the pressure coefficient it was added to). Regrouping a sum of K terms
// changes it by at most ~K eps times the sum of their magnitudes; the terms here are at most a
// few times the parts' largest components (the moved state's pressures vary over ±50% of the
// largest), so 1e3 eps (‖a_E‖∞ + ‖a_I‖∞) per component bounds it with room.
TEST(SphSplit, PartsAddUpToTheAcceleration) {
  for (const Scene& s : viscous_scenes()) {
    SCOPED_TRACE(label(s));
    auto sys = model(s.model, with(s.params, {"split=viscosity"}));
    const SphFluid& f = fluid(*sys);
    ASSERT_TRUE(sys->has_imex_split());
    ASSERT_TRUE(sys->imex_split().has_value());
    EXPECT_EQ(sys->imex_split()->name, "viscosity");
    EXPECT_FALSE(sys->has_implicit_part_jacobian());  // no analytic Jacobian
    EXPECT_TRUE(f.implicit_part_velocity_dependent());
    for (unsigned seed : {1u, 2u}) {
      const Vec y = moved_state(f, seed);
      const Vec a = accel(f, y, Which::all), ae = accel(f, y, Which::explicit_part),
                ai = accel(f, y, Which::implicit_part);
      const double scale = ae.cwiseAbs().maxCoeff() + ai.cwiseAbs().maxCoeff();
      EXPECT_GT(ae.cwiseAbs().maxCoeff(), 0.0);
      EXPECT_GT(ai.cwiseAbs().maxCoeff(), 0.0);
      EXPECT_LE(max_abs_diff(ae + ai, a), 1e3 * kEps * scale);
      // The same through the first-order parts: f_E = [0; a_E], f_I = [v; a_I].
      Vec fe(sys->dimension()), fi(sys->dimension()), full(sys->dimension());
      sys->rhs_explicit_part(0.0, y, fe);
      sys->rhs_implicit_part(0.0, y, fi);
      sys->rhs(0.0, y, full);
      EXPECT_TRUE(fe.head(f.dofs()).isZero(0.0));
      EXPECT_TRUE(fi.head(f.dofs()) == y.tail(f.dofs()));
      EXPECT_TRUE(fe.tail(f.dofs()) == ae);
      EXPECT_TRUE(fi.tail(f.dofs()) == ai);
      EXPECT_LE(max_abs_diff(fe + fi, full), 1e3 * kEps * scale);
    }
  }
}

// a_E holds no velocity-dependent term: it is the same bit for bit at v and at 0. Without a
// viscosity a_I is exactly 0 (x' = v alone is implicit).
TEST(SphSplit, ExplicitPartIgnoresVelocityAndInviscidImplicitPartIsZero) {
  for (const Scene& s : viscous_scenes()) {
    SCOPED_TRACE(label(s));
    auto sys = model(s.model, with(s.params, {"split=viscosity"}));
    const SphFluid& f = fluid(*sys);
    const Vec y = moved_state(f, 3);
    const Vec zero = Vec::Zero(f.dofs());
    EXPECT_TRUE(accel(f, y, Which::explicit_part) ==
                accel(f, y.head(f.dofs()), zero, Which::explicit_part));
  }
  auto inviscid = model("sph_tank_2d", {"n=6", "width=0.1", "viscosity=none", "split=viscosity"});
  const SphFluid& f = fluid(*inviscid);
  EXPECT_FALSE(f.implicit_part_velocity_dependent());
  const Vec y = moved_state(f, 4);
  EXPECT_TRUE(accel(f, y, Which::implicit_part).isZero(0.0));
  EXPECT_TRUE(accel(f, y, Which::explicit_part) == accel(f, y, Which::all));
}

// split=none is today's right-hand side: the model built without the parameter and with
// split=none give the same f bit for bit, and so does the full f of the split model (Part::all
// runs the unsplit code path). A model without a split refuses its parts (BadInput).
TEST(SphSplit, NoneAndTheSplitModelsFullRightHandSideAreUnchanged) {
  for (const Scene& s : viscous_scenes()) {
    SCOPED_TRACE(label(s));
    auto plain = model(s.model, s.params);
    auto none = model(s.model, with(s.params, {"split=none"}));
    auto split = model(s.model, with(s.params, {"split=viscosity"}));
    EXPECT_FALSE(plain->has_imex_split());
    EXPECT_FALSE(none->has_imex_split());
    EXPECT_FALSE(none->imex_split().has_value());
    EXPECT_FALSE(none->explicit_part_spectrum(0.0, none->initial_state()).has_value());
    const Vec y = moved_state(fluid(*plain), 5);
    Vec f0(plain->dimension()), f1(plain->dimension()), f2(plain->dimension());
    plain->rhs(0.0, y, f0);
    none->rhs(0.0, y, f1);
    split->rhs(0.0, y, f2);
    EXPECT_TRUE(f0 == f1);
    EXPECT_TRUE(f0 == f2);
    EXPECT_THROW(none->rhs_implicit_part(0.0, y, f1), BadInput);
    EXPECT_THROW(none->rhs_explicit_part(0.0, y, f1), BadInput);
  }
}

// Every particle's sums run in an order fixed by the positions (sph_fluid.hpp), in each part as
// in the whole: 1 and 2 OpenMP threads and the serial path give the same parts bit for bit.
struct ThreadCountGuard {
  int saved = omp_get_max_threads();
  ~ThreadCountGuard() { omp_set_num_threads(saved); }
};

TEST(SphSplit, PartsAreIdenticalForAnyThreadCount) {
  const ThreadCountGuard guard;
  for (const Scene& s : viscous_scenes()) {
    SCOPED_TRACE(label(s));
    auto par = model(s.model, with(s.params, {"split=viscosity", "parallel_threshold=0"}));
    auto ser = model(s.model, with(s.params, {"split=viscosity", "parallel_threshold=1000000000"}));
    const SphFluid& fp = fluid(*par);
    const Vec y = moved_state(fp, 6);
    for (Which w : {Which::explicit_part, Which::implicit_part}) {
      omp_set_num_threads(1);
      ASSERT_EQ(omp_get_max_threads(), 1);
      const Vec one = accel(fp, y, w);
      omp_set_num_threads(2);
      ASSERT_EQ(omp_get_max_threads(), 2);
      const Vec two = accel(fp, y, w);
      const Vec serial = accel(fluid(*ser), y, w);
      EXPECT_GT(one.cwiseAbs().maxCoeff(), 0.0);
      EXPECT_TRUE(one == two);
      EXPECT_TRUE(one == serial);
    }
  }
}

// Müller's a_I = (μ/ρ_i) Σ_j m_j (v_j - v_i)/ρ_j ∇²W(r_ij) - (μ/ρ_i) Σ_b V_b ∇²W(r_ib) v_i is
// linear in v at fixed x (the densities depend on x only). Scaling by 2 and negation are exact
// in binary floating point and commute with every product, difference and sum of that formula,
// so a_I(x, 2v) = 2 a_I(x, v) and a_I(x, -v) = -a_I(x, v) hold bit for bit; additivity
// a_I(x, v + w) = a_I(x, v) + a_I(x, w) holds to rounding (64 eps of the terms' scale).
// Monaghan's Π_ij ∝ v_ij·r_ij acts on approaching pairs only (v_ij·r_ij < 0): positively
// homogeneous (the switch is unchanged by a factor 2), but not odd: reversing v swaps which pairs
// it acts on.
TEST(SphSplit, MullerImplicitPartIsLinearInVelocity) {
  auto sys =
      model("sph_tank_2d", {"n=6", "width=0.1", "viscosity=muller", "mu=1", "split=viscosity"});
  const SphFluid& f = fluid(*sys);
  const Vec y = moved_state(f, 7), w = moved_state(f, 8);
  const Vec x = y.head(f.dofs()), v = y.tail(f.dofs()), v2 = w.tail(f.dofs());
  const Vec a = accel(f, x, v, Which::implicit_part);
  ASSERT_GT(a.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(accel(f, x, Vec(2.0 * v), Which::implicit_part) == 2.0 * a);
  EXPECT_TRUE(accel(f, x, Vec(-v), Which::implicit_part) == -a);
  const Vec b = accel(f, x, v2, Which::implicit_part);
  const Vec sum = accel(f, x, Vec(v + v2), Which::implicit_part);
  EXPECT_LE(max_abs_diff(sum, a + b),
            64 * kEps * (a.cwiseAbs().maxCoeff() + b.cwiseAbs().maxCoeff()));

  auto art = model("sph_tank_2d",
                   {"n=6", "width=0.1", "viscosity=artificial", "alpha=0.5", "split=viscosity"});
  const SphFluid& g = fluid(*art);
  const Vec aa = accel(g, x, v, Which::implicit_part);
  ASSERT_GT(aa.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(accel(g, x, Vec(2.0 * v), Which::implicit_part) == 2.0 * aa);
  EXPECT_GT(max_abs_diff(accel(g, x, Vec(-v), Which::implicit_part), -aa),
            1e-3 * aa.cwiseAbs().maxCoeff());
}

// explicit_part_spectrum(): the lattice's fastest pressure wave on the imaginary axis (the
// penalty walls' ω where larger). Independent check: the longitudinal wave of wave vector k on
// the lattice at rest has ω² = c² |T(k)|² / S² with T(k) = Σ_j ∇W(X_j) sin(k·X_j) and
// S = Σ_j W(X_j) (sph_fluid.hpp); summed in plain Python for the Wendland C2 kernel with support
// 2.5 Δx over the same wave-vector grid as the model (k = (π/Δx)(a, b[, c])/N, a >= b [>= c],
// N = 48 in 2D, 16 in 3D): max ω Δx/c = 0.8685635322457709 (2D, at k Δx = (π/3, π/3)) and
// 0.9008471549625455 (3D). (A 160 × 160 grid gives 0.86855 in 2D: the grid's maximum is the
// continuum's to 1e-5.) The symmetric pressure form halves ω².
TEST(SphSplit, ExplicitPartSpectrumIsTheLatticeAcousticRate) {
  auto sys = model("sph_drop_2d", {"n=10", "split=viscosity"});
  const SphFluid& f = fluid(*sys);
  const auto est = sys->explicit_part_spectrum(0.0, sys->initial_state());
  ASSERT_TRUE(est.has_value());
  EXPECT_EQ(est->ray, SpectrumEstimate::Ray::imaginary);
  const double expected = 0.8685635322457709 * f.sound_speed() / f.options().spacing;
  EXPECT_NEAR(est->radius, expected, 1e-12 * expected);
  auto cube = model("sph_tank_3d", {"n=4", "split=viscosity"});
  const SphFluid& f3 = fluid(*cube);
  const double expected3 = 0.9008471549625455 * f3.sound_speed() / f3.options().spacing;
  EXPECT_NEAR(cube->explicit_part_spectrum(0.0, cube->initial_state())->radius, expected3,
              1e-12 * expected3);
  auto sym = model("sph_drop_2d", {"n=10", "split=viscosity", "form=symmetric"});
  EXPECT_NEAR(sym->explicit_part_spectrum(0.0, sym->initial_state())->radius,
              est->radius / std::sqrt(2.0), 1e-12 * est->radius);
  auto pen = model("sph_dam_break_2d", {"n=4", "boundary=penalty", "split=viscosity"});
  const SphFluid& fp = fluid(*pen);
  EXPECT_EQ(pen->explicit_part_spectrum(0.0, pen->initial_state())->radius,
            std::max(fp.acoustic_rate(), fp.penalty_frequency()));
}

// IMEX against explicit on a viscosity-dominated drop: 2D, n = 10 (Δx = 0.02, support h = 0.05,
// h_s = 0.025), c = 10, Müller μ = 2000 (ν = 2 m²/s). The model's explicit viscous limit
// 0.125 h_s²/ν = 3.9e-5 is 50× below the acoustic one 0.4 h/c = 2e-3. The viscous operator's
// largest rate is about ν Σ_j V_j ∇²W(r_j) ≈ ν ∫∇²W dA = ν · 40/(3 h²) = 1.07e4 /s (the 2D
// Laplacian 40/(π h⁵)(h - r) integrated over the disc; the lattice's checkerboard mode reaches
// it), so rk4 (real-axis limit 2.785) needs h < 2.6e-4: at h = 5e-4 (12.8× the 0.125 limit)
// its viscous modes grow by |R(-5.3)| ≈ 18 per step and 40 steps blow up. ars232's implicit
// table (L-stable SDIRK) damps every viscous mode at any step, and its explicit table sees the
// pressure waves, ω = 434 /s, at hω = 0.22 (its imaginary-axis limit is 1.41): stable, and the
// viscosity dissipates the kinetic energy (by ~5e4 in 0.02 s, the ν k² decay of the drop's
// deformation; measured 2.0e-6 of 0.10).
TEST(SphSplit, ImexIsStableWhereRk4BlowsUpOnTheViscousModes) {
  auto sys = model("sph_drop_2d", {"n=10", "viscosity=muller", "mu=2000", "split=viscosity"});
  const SphFluid& f = fluid(*sys);
  const double ke0 = f.kinetic_energy(sys->initial_state());
  const FixedStepOptions opt{0.02, 5e-4, 0};
  auto imex = make("ars232");
  const RunResult r = run_fixed_step(*sys, *imex, opt);
  ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_EQ(r.n_steps, 40);
  EXPECT_TRUE(r.y.allFinite());
  EXPECT_LT(f.kinetic_energy(r.y), 1e-3 * ke0);
  EXPECT_GT(r.stats.fi_evals, 0);
  EXPECT_GT(r.stats.fe_evals, 0);
  auto rk4 = make("rk4");
  const RunResult e = run_fixed_step(*sys, *rk4, opt);
  EXPECT_TRUE(e.stats.status != Status::ok || !e.y.allFinite() || f.kinetic_energy(e.y) > ke0)
      << "rk4 final kinetic energy " << f.kinetic_energy(e.y) << " of " << ke0;
  // Below its viscous limit rk4 agrees with the IMEX run's dissipation.
  const RunResult ok = run_fixed_step(*sys, *rk4, FixedStepOptions{0.02, 2e-4, 0});
  ASSERT_EQ(ok.stats.status, Status::ok);
  EXPECT_LT(f.kinetic_energy(ok.y), 1e-3 * ke0);
}

// ---------------------------------------------------------------------------------------------
// Angular momentum.

// A spinning free drop (no gravity, no walls, rigid rotation v = A(-y, x), A = 5 /s). The
// pressure pair terms act along r_ij with coefficients symmetric in i, j, so every pair's
// torques cancel: d/dt Σ m x × v = Σ m x × a = 0 (Monaghan's artificial viscosity is along
// ∇W_ij ∥ r_ij too). Symplectic Euler (v+ = v + h a(x, v), x+ = x + h v+) keeps it exactly in
// exact arithmetic: the kick adds h Σ m x × a = 0 and the drift adds h Σ m v+ × v+ = 0.
// Velocity Verlet is kick–drift–kick of the same two maps, so it keeps it too. In floating
// point each step rounds every x and v (relative eps) and the torque sum cancels only to
// rounding: each step changes L by a few eps |L| (all terms of L have one sign for a rigid
// rotation, so |L| is their scale), at most 8 eps |L| per step allowed here (measured with the
// CLI: 4.3e-16 relative after 40 steps of either method).
TEST(SphSplit, SpinningDropConservesAngularMomentum) {
  const std::vector<std::string> spin = {"n=10", "velocity=rotation", "rate=5"};
  for (const auto& extra : std::vector<std::vector<std::string>>{
           {}, {"viscosity=artificial", "alpha=1"}, {"form=symmetric"}}) {
    auto sys = model("sph_drop_2d", with(spin, extra));
    const SphFluid& f = fluid(*sys);
    bool listed = false;
    for (const auto& inv : sys->invariants()) listed |= inv.name == "angular_momentum";
    EXPECT_TRUE(listed);
    const double l0 = f.angular_momentum(sys->initial_state())[0];
    // Σ m A r² for the rigid rotation: positive and of the size m N A R²/2.
    ASSERT_GT(l0, 0.0);
    std::vector<std::string> methods = {"symplectic_euler"};
    if (!f.velocity_dependent()) methods.push_back("velocity_verlet");
    for (const auto& name : methods) {
      SCOPED_TRACE(name);
      auto integ = make(name);
      const double h = f.suggested_step()->h;
      const RunResult r = run_fixed_step(*sys, *integ, FixedStepOptions{40 * h, h, 0});
      ASSERT_EQ(r.stats.status, Status::ok);
      EXPECT_NEAR(f.angular_momentum(r.y)[0], l0, 40 * 8 * kEps * l0);
      // The drop moved: the check is not on a state at rest.
      EXPECT_GT(max_abs_diff(r.y.head(f.dofs()), sys->initial_state().head(f.dofs())),
                0.01 * f.options().spacing);
    }
  }
}

// Müller's pair force (μ/ρ_i) m (v_j - v_i)/ρ_j ∇²W is along v_j - v_i, not r_ij: for the rigid
// rotation v_j - v_i = A e_z × (x_j - x_i), the pair torque (x_i - x_j) × (v_j - v_i) =
// -A |r_ij|² e_z with a positive coefficient, so every pair brakes the spin (a rigid rotation,
// which has no viscous stress in a real fluid, loses angular momentum). The invariant is not
// listed, and a run loses a visible share of L.
TEST(SphSplit, MullerViscosityDoesNotConserveAngularMomentum) {
  auto sys =
      model("sph_drop_2d", {"n=10", "velocity=rotation", "rate=5", "viscosity=muller", "mu=1"});
  const SphFluid& f = fluid(*sys);
  for (const auto& inv : sys->invariants()) EXPECT_NE(inv.name, "angular_momentum");
  const double l0 = f.angular_momentum(sys->initial_state())[0];
  auto integ = make("symplectic_euler");
  const double h = f.suggested_step()->h;
  const RunResult r = run_fixed_step(*sys, *integ, FixedStepOptions{40 * h, h, 0});
  ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_LT(f.angular_momentum(r.y)[0], (1 - 1e-3) * l0);
}

// angular_momentum() against Eigen's cross product, Σ m x × v, on a moved 3D state; in 2D the
// scalar is the z component of the same sum with z = v_z = 0.
TEST(SphSplit, AngularMomentumIsTheSumOfCrossProducts) {
  for (const char* name : {"sph_tank_3d", "sph_tank_2d"}) {
    SCOPED_TRACE(name);
    auto sys = model(name, {"n=4"});
    const SphFluid& f = fluid(*sys);
    const Vec y = moved_state(f, 9);
    const int d = f.dim();
    Eigen::Vector3d l = Eigen::Vector3d::Zero();
    double scale = 0.0;
    for (Index i = 0; i < f.fluid_particles(); ++i) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
      x.head(d) = y.segment(d * i, d);
      v.head(d) = y.segment(f.dofs() + d * i, d);
      const double m = f.particle_masses()[static_cast<std::size_t>(i)];
      l += m * x.cross(v);
      scale += m * x.norm() * v.norm();
    }
    const Vec got = f.angular_momentum(y);
    ASSERT_EQ(got.size(), d == 3 ? 3 : 1);
    if (d == 3)
      EXPECT_LE((got - Vec(l)).cwiseAbs().maxCoeff(), 16 * kEps * scale);
    else
      EXPECT_NEAR(got[0], l.z(), 16 * kEps * scale);
  }
}

// Gravity or walls exert torques: not listed. 3D tanks have walls.
TEST(SphSplit, AngularMomentumListedOnlyWhenConserved) {
  auto has = [](const OdeSystem& s, const std::string& name) {
    for (const auto& inv : s.invariants())
      if (inv.name.rfind(name, 0) == 0) return true;
    return false;
  };
  EXPECT_TRUE(has(*model("sph_drop_2d", {"n=6"}), "angular_momentum"));
  EXPECT_FALSE(has(*model("sph_drop_2d", {"n=6", "gravity=9.81"}), "angular_momentum"));
  EXPECT_FALSE(has(*model("sph_tank_2d", {"n=4"}), "angular_momentum"));
  EXPECT_FALSE(has(*model("sph_tank_3d", {"n=3", "gravity=0", "c0=10"}), "angular_momentum"));
  EXPECT_FALSE(has(*model("sph_dam_break_2d", {"n=4", "boundary=penalty", "gravity=0", "c0=10"}),
                   "angular_momentum"));
}

}  // namespace
}  // namespace stiffbench
