// Air drag on the cloth's triangles (models/mass_spring/network.hpp, parameter `drag`), checked
// against theory: the quadratic law on a flat cloth moving along its normal (total force and one
// interior point, by hand), the energy rate against the dissipated power written from the
// triangles' geometry, the explicit part's spectrum estimate against dense eigenvalues, and the
// methods that cannot take the force refusing the model. Its Jacobian blocks are checked against
// finite differences with the other mass-spring Jacobians (tests/models/test_mass_spring.cpp),
// its split parts and their thread independence in tests/models/test_splits.cpp.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/integrator.hpp"
#include "models/mass_spring/network.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

const MassSpringNetwork& as_net(const OdeSystem& sys) {
  const auto* n = dynamic_cast<const MassSpringNetwork*>(&sys);
  if (!n) throw std::logic_error(sys.name() + " is not a MassSpringNetwork");
  return *n;
}

// A flat, undeformed n × n cloth (spacing s, point mass m, no gravity, no pins) whose points all
// move with velocity (0, 0, w): the springs are at rest, so the acceleration is the drag alone.
// Every triangle has area s²/2, normal ±e_z and v̄·n = ±w, so it feels F = -b (s²/2) w|w| e_z and
// gives each of its points a third. Theory: the total force is -b ((n-1) s)² w|w| e_z (the
// cloth's area), and an interior point, in 6 triangles, has a_z = -6 b (s²/2) w|w| / (3 m) =
// -b s² w|w| / m.
TEST(AirDrag, FlatClothMovingAlongItsNormalFeelsTheQuadraticLaw) {
  const double b = 0.7, s = 0.1, m = 0.01;
  const int n = 5;
  for (const double w : {0.8, -1.3}) {
    SCOPED_TRACE(w);
    auto sys = model("cloth", {"n=5", "pin=none", "gravity=0", "perturbation=0", "drag=0.7"});
    const MassSpringNetwork& net = as_net(*sys);
    const Index nd = net.dofs();
    Vec x = sys->initial_state().head(nd), v = Vec::Zero(nd), a(nd);
    for (Index p = 0; p < net.num_points(); ++p) v[3 * p + 2] = w;
    net.acceleration(0.0, x, v, a);
    double total_z = 0.0, total_xy = 0.0;
    for (Index p = 0; p < net.num_points(); ++p) {
      total_z += m * a[3 * p + 2];
      total_xy += std::abs(a[3 * p]) + std::abs(a[3 * p + 1]);
    }
    const double side = (n - 1) * s;
    EXPECT_NEAR(total_z, -b * side * side * w * std::abs(w), 1e-13);
    EXPECT_EQ(total_xy, 0.0);
    const Index centre = 2 * n + 2;  // point (2, 2)
    EXPECT_NEAR(a[3 * centre + 2], -b * s * s * w * std::abs(w) / m, 1e-12);
  }
}

// dE/dt = ∇E·f equals the power of the dissipative forces. Independent computation: the power
// written from the geometry of each triangle, -b A |v̄·n|³ (A and n from the cross product of
// two edges), plus point damping's -γ Σ|v|² on the free points; ∇E by central differences of
// energy() (step 1e-6: error ~1e-10 of the terms, far inside the 1e-7 tolerance).
TEST(AirDrag, EnergyRateIsTheDissipatedPower) {
  const double b = 0.4, gamma = 0.03;
  auto sys = model("cloth", {"n=4", "pin=corners", "damping=0.03", "drag=0.4"});
  const MassSpringNetwork& net = as_net(*sys);
  const Index nd = net.dofs();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec y = sys->initial_state();
  for (Index p = 0; p < net.num_points(); ++p)
    if (!net.points()[static_cast<std::size_t>(p)].pinned)
      for (int c = 0; c < 3; ++c) {
        y[3 * p + c] += 0.02 * u(rng);
        y[nd + 3 * p + c] = 0.7 * u(rng);
      }
  Vec grad(2 * nd), f(2 * nd);
  for (Index i = 0; i < 2 * nd; ++i) {
    Vec yp = y, ym = y;
    yp[i] += 1e-6;
    ym[i] -= 1e-6;
    grad[i] = (net.energy(yp) - net.energy(ym)) / 2e-6;
  }
  sys->rhs(0, y, f);
  double power = 0.0;
  for (Index p = 0; p < net.num_points(); ++p)
    if (!net.points()[static_cast<std::size_t>(p)].pinned)
      power -= gamma * y.segment(nd + 3 * p, 3).squaredNorm();
  ASSERT_EQ(net.triangles().size(), 2u * 3u * 3u);
  for (const Triangle& t : net.triangles()) {
    const Eigen::Vector3d xa = y.segment<3>(3 * t.a), xb = y.segment<3>(3 * t.b),
                          xc = y.segment<3>(3 * t.c);
    const Eigen::Vector3d cross = (xb - xa).cross(xc - xa);
    const Eigen::Vector3d vbar =
        (y.segment<3>(nd + 3 * t.a) + y.segment<3>(nd + 3 * t.b) + y.segment<3>(nd + 3 * t.c)) /
        3.0;
    const double area = 0.5 * cross.norm(), normal_speed = vbar.dot(cross.normalized());
    power -= b * area * std::pow(std::abs(normal_speed), 3);
  }
  EXPECT_LT(power, 0.0);
  EXPECT_NEAR(grad.dot(f), power, 1e-7 * std::abs(power));
}

// With split=springs, f_E = [0; g - γv/m + drag/m] and J_E = J - J_I = [[0, 0], [K_E, D_E]]: its
// eigenvalues are 0 and those of D_E, real and <= 0 (D_E is M⁻¹ times a symmetric negative
// semi-definite matrix at equal masses). The estimate bounds D_E's norm row by row, so it is at
// least the largest |eigenvalue| (dense EigenSolver) at a random state. On a flat cloth moving
// uniformly along its normal every triangle has the same rate c, D_E = -(c/(9m)) Σ_t 1_t 1_tᵀ ⊗
// e_z e_zᵀ, and the bound is the largest row sum (6 triangles at an interior point) while the
// Rayleigh quotient of the all-ones vector is the mean row sum (3 × 32 / 25 triangles on 5 × 5):
// the bound is within 6/3.84 = 1.5625 of the largest eigenvalue.
TEST(AirDrag, ExplicitPartSpectrumBoundsTheDragRates) {
  auto sys = model("cloth", {"n=5", "pin=none", "gravity=0", "perturbation=0", "drag=0.6",
                             "damping=0.01", "split=springs"});
  const Index nd = sys->as_mechanical()->dofs();
  const auto largest = [&](const Vec& y) {
    SparseMat j, ji;
    sys->jacobian(0.0, y, j);
    sys->implicit_part_jacobian(0.0, y, ji);
    const Eigen::VectorXcd ev = Eigen::EigenSolver<Mat>(Mat(j) - Mat(ji)).eigenvalues();
    EXPECT_LE(ev.imag().cwiseAbs().maxCoeff(), 1e-9 * ev.cwiseAbs().maxCoeff());
    EXPECT_LE(ev.real().maxCoeff(), 1e-9 * ev.cwiseAbs().maxCoeff());
    return ev.cwiseAbs().maxCoeff();
  };
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec y = sys->initial_state();
  for (Index i = 0; i < nd; ++i) {
    y[i] += 0.02 * u(rng);
    y[nd + i] = 0.8 * u(rng);
  }
  auto spec = sys->explicit_part_spectrum(0.0, y);
  ASSERT_TRUE(spec.has_value());
  EXPECT_EQ(spec->ray, SpectrumEstimate::Ray::negative_real);
  const double random_largest = largest(y);
  EXPECT_GT(random_largest, 1.0);  // the drag, not the point damping's 1.0, sets it
  EXPECT_GE(spec->radius, random_largest * (1 - 1e-12));

  // Uniform motion along the normal; point damping adds γ/m = 1 to every row and eigenvalue.
  Vec flat = sys->initial_state();
  for (Index p = 0; p < nd / 3; ++p) flat[nd + 3 * p + 2] = 1.5;
  spec = sys->explicit_part_spectrum(0.0, flat);
  const double flat_largest = largest(flat);
  EXPECT_GE(spec->radius, flat_largest * (1 - 1e-12));
  EXPECT_LE(spec->radius - 1.0, 1.5625 * (flat_largest - 1.0) * (1 + 1e-12));
}

// The Verlet family needs a velocity-independent acceleration; XPBD and projective dynamics work
// on the springs, gravity and point damping alone: all refuse the model with drag, naming it.
TEST(AirDrag, MethodsThatCannotTakeTheForceRefuseTheModel) {
  auto with = model("cloth", {"n=4", "drag=0.5"});
  auto without = model("cloth", {"n=4"});
  for (const std::string name : {"velocity_verlet", "xpbd", "projective_dynamics"}) {
    SCOPED_TRACE(name);
    auto integ = make(name);
    EXPECT_NO_THROW(check_compatible(integ->info(), *without));
    EXPECT_THROW(check_compatible(integ->info(), *with), BadInput);
  }
  try {
    check_compatible(make("xpbd")->info(), *with);
    ADD_FAILURE() << "xpbd accepted a model with air drag";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("air drag"), std::string::npos) << e.what();
  }
  EXPECT_THROW(model("cloth", {"n=4", "drag=-1"}), BadInput);
}

}  // namespace
}  // namespace stiffbench
