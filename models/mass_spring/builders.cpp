#include "models/mass_spring/builders.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include "models/problems/harmonic_oscillator.hpp"

namespace stiffbench {

namespace {

// BadInput "<model>: parameter '<key>' must be <what>" unless cond.
void check(bool cond, const char* model, const char* key, const char* what) {
  require_input(cond, std::string(model) + ": parameter '" + key + "' must be " + what);
}

bool positive(double x) { return std::isfinite(x) && x > 0; }
bool non_negative(double x) { return std::isfinite(x) && x >= 0; }

// Mode shape of the chain at mass i (1..n).
double chain_mode_shape(const SpringChainOptions& o, long j, long i) {
  const double pi = std::numbers::pi;
  const auto n = static_cast<double>(o.n);
  return o.fixed_free ? std::sin((2.0 * j - 1.0) * pi * i / (2.0 * n + 1.0))
                      : std::sin(j * pi * i / (n + 1.0));
}

}  // namespace

double spring_chain_frequency(const SpringChainOptions& o, long j) {
  const double pi = std::numbers::pi;
  const auto n = static_cast<double>(o.n);
  const double s = o.fixed_free ? std::sin((2.0 * j - 1.0) * pi / (2.0 * (2.0 * n + 1.0)))
                                : std::sin(j * pi / (2.0 * (n + 1.0)));
  return 2.0 * std::sqrt(o.k / o.mass) * s;
}

std::unique_ptr<MassSpringNetwork> make_spring_chain(const SpringChainOptions& o) {
  const char* model = "spring_chain";
  check(o.n >= 1, model, "n", ">= 1");
  check(positive(o.k), model, "k", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(positive(o.rest_length), model, "rest_length", "> 0");
  check(o.mode >= 0 && o.mode <= o.n, model, "mode", "between 0 and n");
  check(std::isfinite(o.amplitude) && std::abs(o.amplitude) < 0.5 * o.rest_length, model,
        "amplitude", "smaller than rest_length/2 in magnitude (neighbours must not meet)");
  check(non_negative(o.perturbation) && o.perturbation < 0.5 * o.rest_length, model, "perturbation",
        ">= 0 and < rest_length/2");
  check(non_negative(o.point_damping), model, "gamma", ">= 0");
  check(non_negative(o.dashpot), model, "dashpot", ">= 0");

  const long n_points = o.n + (o.fixed_free ? 1 : 2);
  std::vector<MassPoint> points(static_cast<std::size_t>(n_points));
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (long i = 0; i < n_points; ++i) {
    MassPoint& p = points[static_cast<std::size_t>(i)];
    p.mass = o.mass;
    p.x[0] = static_cast<double>(i) * o.rest_length;
    p.pinned = i == 0 || i == o.n + 1;
    if (!p.pinned) {
      if (o.mode > 0) p.x[0] += o.amplitude * chain_mode_shape(o, o.mode, i);
      if (o.perturbation > 0) p.x[0] += o.perturbation * uniform(rng);
    }
  }
  std::vector<Spring> springs;
  for (long i = 0; i + 1 < n_points; ++i)
    springs.push_back({i, i + 1, o.k, o.rest_length, o.dashpot, SpringKind::structural});
  NetworkOptions net;
  net.point_damping = o.point_damping;
  net.split = o.split;
  auto sys =
      std::make_unique<MassSpringNetwork>(model, 1, std::move(points), std::move(springs), net);
  if (o.perturbation == 0) {
    // Mode j as the damped oscillator q'' + (γ/m + cω²/k) q' + ω² q = 0, q(0) = 1, q'(0) = 0
    // (header comment), solved in closed form by HarmonicOscillator.
    const double omega = o.mode > 0 ? spring_chain_frequency(o, o.mode) : 1.0;
    const double damping = o.point_damping / o.mass + o.dashpot * omega * omega / o.k;
    const HarmonicOscillator mode(1.0, omega * omega, damping, 1.0, 0.0);
    const SpringChainOptions opt = o;
    sys->set_exact([opt, mode, n_points](double t, VecRef y) {
      Vec q(2);
      mode.exact(t, q);
      for (long i = 0; i < n_points; ++i) {
        const bool pinned = i == 0 || i == opt.n + 1;
        const double shape =
            (pinned || opt.mode == 0) ? 0.0 : opt.amplitude * chain_mode_shape(opt, opt.mode, i);
        y[i] = static_cast<double>(i) * opt.rest_length + shape * q[0];
        y[n_points + i] = shape * q[1];
      }
    });
  }
  return sys;
}

std::unique_ptr<MassSpringNetwork> make_cloth(const ClothOptions& o) {
  const char* model = "cloth";
  check(o.n >= 2, model, "n", ">= 2");
  check(o.m >= 2, model, "m", ">= 2 (or 0: same as n)");
  check(positive(o.spacing), model, "spacing", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(non_negative(o.k_struct), model, "k_struct", ">= 0");
  check(non_negative(o.k_shear), model, "k_shear", ">= 0");
  check(non_negative(o.k_bend), model, "k_bend", ">= 0");
  check(non_negative(o.gravity), model, "gravity", ">= 0");
  check(positive(o.prestretch), model, "prestretch", "> 0");
  check(non_negative(o.perturbation) && o.perturbation < 0.25 * o.spacing, model, "perturbation",
        ">= 0 and < spacing/4");
  check(non_negative(o.point_damping), model, "damping", ">= 0");
  check(non_negative(o.dashpot), model, "dashpot", ">= 0");
  check(non_negative(o.air_drag), model, "drag", ">= 0");
  check(o.parallel_threshold >= 1, model, "parallel_threshold", ">= 1");

  const long nx = o.n, ny = o.m;
  auto id = [nx](long i, long j) { return static_cast<Index>(j * nx + i); };
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<MassPoint> points(static_cast<std::size_t>(nx * ny));
  for (long j = 0; j < ny; ++j) {
    for (long i = 0; i < nx; ++i) {
      MassPoint& p = points[static_cast<std::size_t>(id(i, j))];
      p.mass = o.mass;
      p.x = {(static_cast<double>(i) - 0.5 * static_cast<double>(nx - 1)) * o.spacing,
             (static_cast<double>(j) - 0.5 * static_cast<double>(ny - 1)) * o.spacing, 0.0};
      const bool top = j == ny - 1;
      p.pinned = (o.pin == ClothOptions::Pin::top_edge && top) ||
                 (o.pin == ClothOptions::Pin::corners && top && (i == 0 || i == nx - 1));
      if (!p.pinned && o.perturbation > 0)
        for (double& c : p.x) c += o.perturbation * uniform(rng);
    }
  }
  std::vector<Spring> springs;
  springs.reserve(static_cast<std::size_t>(6 * nx * ny));  // at most 6 per point
  const double rest = o.spacing / o.prestretch;
  const double diag = std::sqrt(2.0) * rest;
  auto add = [&](long i0, long j0, long i1, long j1, double k, double len, SpringKind kind) {
    if (i1 < 0 || i1 >= nx || j1 >= ny) return;
    springs.push_back({id(i0, j0), id(i1, j1), k, len, o.dashpot, kind});
  };
  for (long j = 0; j < ny; ++j) {
    for (long i = 0; i < nx; ++i) {
      add(i, j, i + 1, j, o.k_struct, rest, SpringKind::structural);
      add(i, j, i, j + 1, o.k_struct, rest, SpringKind::structural);
      add(i, j, i + 1, j + 1, o.k_shear, diag, SpringKind::shear);
      add(i, j, i - 1, j + 1, o.k_shear, diag, SpringKind::shear);
      add(i, j, i + 2, j, o.k_bend, 2 * rest, SpringKind::bend);
      add(i, j, i, j + 2, o.k_bend, 2 * rest, SpringKind::bend);
    }
  }
  NetworkOptions net;
  net.gravity = {0.0, 0.0, -o.gravity};
  net.point_damping = o.point_damping;
  net.compressed_dd_only = o.compressed_dd_only;
  net.parallel_threshold = o.parallel_threshold;
  net.split = o.split;
  net.air_drag = o.air_drag;
  // Air drag's triangles: each cell cut along its shear spring (i, j)-(i+1, j+1), both halves
  // with normal +z in the initial plane.
  std::vector<Triangle> triangles;
  if (o.air_drag > 0.0) {
    triangles.reserve(static_cast<std::size_t>(2 * (nx - 1) * (ny - 1)));
    for (long j = 0; j + 1 < ny; ++j)
      for (long i = 0; i + 1 < nx; ++i) {
        triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      }
  }
  return std::make_unique<MassSpringNetwork>(model, 3, std::move(points), std::move(springs), net,
                                             std::vector<DistanceConstraint>{},
                                             std::move(triangles));
}

std::unique_ptr<MassSpringNetwork> make_soft_cube(const SoftCubeOptions& o) {
  const char* model = "soft_cube";
  check(o.n >= 2, model, "n", ">= 2");
  check(positive(o.spacing), model, "spacing", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(non_negative(o.k_edge), model, "k_edge", ">= 0");
  check(non_negative(o.k_face), model, "k_face", ">= 0");
  check(non_negative(o.k_body), model, "k_body", ">= 0");
  check(std::isfinite(o.height), model, "height", "finite");
  check(std::isfinite(o.spin), model, "spin", "finite");
  check(positive(o.factor), model, "factor", "> 0");
  check(non_negative(o.gravity), model, "gravity", ">= 0");
  check(non_negative(o.point_damping), model, "damping", ">= 0");
  check(non_negative(o.dashpot), model, "dashpot", ">= 0");
  check(o.parallel_threshold >= 1, model, "parallel_threshold", ">= 1");

  const long n = o.n;
  auto id = [n](long i, long j, long k) { return static_cast<Index>((k * n + j) * n + i); };
  const double s = o.spacing;
  const double half = 0.5 * s * static_cast<double>(n - 1);
  const bool drop = o.scenario == SoftCubeOptions::Scenario::drop;
  // Rigid rotation ω × r about the axis (1, 2, 3)/√14 through the centre (drop scenario).
  const double norm = std::sqrt(14.0);
  const double wx = (drop ? o.spin : 0.0) / norm, wy = 2 * wx, wz = 3 * wx;
  std::vector<MassPoint> points(static_cast<std::size_t>(n * n * n));
  for (long k = 0; k < n; ++k)
    for (long j = 0; j < n; ++j)
      for (long i = 0; i < n; ++i) {
        MassPoint& p = points[static_cast<std::size_t>(id(i, j, k))];
        p.mass = o.mass;
        const double scale = drop ? 1.0 : o.factor;
        const double rx = scale * (static_cast<double>(i) * s - half);
        const double ry = scale * (static_cast<double>(j) * s - half);
        const double rz = scale * (static_cast<double>(k) * s - half);
        p.x = {rx, ry, rz + half * scale + o.height};
        p.v = {wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx};
      }
  std::vector<Spring> springs;
  auto add = [&](long i, long j, long k, long di, long dj, long dk, double stiffness,
                 SpringKind kind) {
    const long i1 = i + di, j1 = j + dj, k1 = k + dk;
    if (i1 < 0 || i1 >= n || j1 < 0 || j1 >= n || k1 < 0 || k1 >= n) return;
    const double len = s * std::sqrt(static_cast<double>(di * di + dj * dj + dk * dk));
    springs.push_back({id(i, j, k), id(i1, j1, k1), stiffness, len, o.dashpot, kind});
  };
  // Each unordered pair once: offsets with a positive first non-zero component.
  for (long k = 0; k < n; ++k)
    for (long j = 0; j < n; ++j)
      for (long i = 0; i < n; ++i) {
        add(i, j, k, 1, 0, 0, o.k_edge, SpringKind::structural);
        add(i, j, k, 0, 1, 0, o.k_edge, SpringKind::structural);
        add(i, j, k, 0, 0, 1, o.k_edge, SpringKind::structural);
        for (long a : {1L, -1L}) {
          add(i, j, k, 1, a, 0, o.k_face, SpringKind::shear);
          add(i, j, k, 1, 0, a, o.k_face, SpringKind::shear);
          add(i, j, k, 0, 1, a, o.k_face, SpringKind::shear);
          for (long b : {1L, -1L}) add(i, j, k, 1, a, b, o.k_body, SpringKind::shear);
        }
      }
  NetworkOptions net;
  net.gravity = {0.0, 0.0, -o.gravity};
  net.point_damping = o.point_damping;
  net.compressed_dd_only = o.compressed_dd_only;
  net.parallel_threshold = o.parallel_threshold;
  net.split = o.split;
  return std::make_unique<MassSpringNetwork>(model, 3, std::move(points), std::move(springs), net);
}

std::unique_ptr<MassSpringNetwork> make_pendulum_chain(const PendulumChainOptions& o) {
  const char* model = "pendulum_chain";
  check(o.n >= 1, model, "n", ">= 1");
  check(positive(o.length), model, "length", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(non_negative(o.gravity), model, "gravity", ">= 0");
  check(positive(o.k), model, "k", "> 0");
  check(std::isfinite(o.angle), model, "angle", "finite");

  std::vector<MassPoint> points(static_cast<std::size_t>(o.n + 1));
  for (long i = 0; i <= o.n; ++i) {
    MassPoint& p = points[static_cast<std::size_t>(i)];
    p.mass = o.mass;
    const double r = static_cast<double>(i) * o.length;
    p.x = {r * std::sin(o.angle), -r * std::cos(o.angle), 0.0};
    p.pinned = i == 0;
  }
  std::vector<Spring> springs;
  std::vector<DistanceConstraint> constraints;
  for (long i = 0; i < o.n; ++i) {
    if (o.constrained)
      constraints.push_back({i, i + 1, o.length});
    else
      springs.push_back({i, i + 1, o.k, o.length, 0.0, SpringKind::structural});
  }
  NetworkOptions net;
  net.gravity = {0.0, -o.gravity, 0.0};
  return std::make_unique<MassSpringNetwork>(model, 2, std::move(points), std::move(springs), net,
                                             std::move(constraints));
}

}  // namespace stiffbench
