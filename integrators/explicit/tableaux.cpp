#include "integrators/explicit/tableaux.hpp"

namespace stiffbench {

namespace {

ButcherTableau make(std::string name, int order, std::vector<std::vector<double>> a,
                    std::vector<double> b) {
  const auto s = static_cast<Index>(b.size());
  ButcherTableau t;
  t.name = std::move(name);
  t.order = order;
  t.a = Mat::Zero(s, s);
  t.b = Vec(s);
  for (Index i = 0; i < s; ++i) {
    t.b[i] = b[static_cast<std::size_t>(i)];
    const auto& row = a[static_cast<std::size_t>(i)];
    for (Index j = 0; j < static_cast<Index>(row.size()); ++j)
      t.a(i, j) = row[static_cast<std::size_t>(j)];
  }
  // Nodes are the row sums (c = A·1): stated once, not typed twice.
  t.c = t.a.rowwise().sum();
  // An explicit method's stage order is 1 (C(1) is c = A·1; C(2) fails at the second stage).
  t.stage_order = 1;
  return t;
}

ButcherTableau make_embedded(std::string name, int order, int embedded_order, bool fsal,
                             std::vector<std::vector<double>> a, std::vector<double> b,
                             std::vector<double> b_embedded) {
  ButcherTableau t = make(std::move(name), order, std::move(a), std::move(b));
  t.b_embedded = Eigen::Map<const Vec>(b_embedded.data(), static_cast<Index>(b_embedded.size()));
  t.embedded_order = embedded_order;
  t.fsal = fsal;
  return t;
}

}  // namespace

const std::vector<ExplicitRkMethod>& explicit_rk_methods() {
  constexpr const char* kKutta = "W. Kutta, Z. Math. Phys. 46 (1901) 435-453";
  static const std::vector<ExplicitRkMethod> all = {
      {make("euler", 1, {{}}, {1.0}),
       {"explicit (forward) Euler", "explicit RK",
        cite(kHairerNorsettWanner, "Sect. I.7 (Euler 1768)")},
       StepModes::fixed},
      {make("heun", 2, {{}, {1.0}}, {0.5, 0.5}),
       {"Heun's method (explicit trapezoidal rule)", "explicit RK",
        "K. Heun, Z. Math. Phys. 45 (1900) 23-38"},
       StepModes::fixed},
      {make("midpoint", 2, {{}, {0.5}}, {0.0, 1.0}),
       {"explicit midpoint rule", "explicit RK", "C. Runge, Math. Ann. 46 (1895) 167-178"},
       StepModes::fixed},
      {make("ralston", 2, {{}, {2.0 / 3.0}}, {0.25, 0.75}),
       {"Ralston's second-order method (minimum error bound)", "explicit RK",
        "A. Ralston, Math. Comp. 16 (1962) 431-437"},
       StepModes::fixed},
      {make("kutta3", 3, {{}, {0.5}, {-1.0, 2.0}}, {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0}),
       {"Kutta's third-order method", "explicit RK", kKutta},
       StepModes::fixed},
      {make("ssprk3", 3, {{}, {1.0}, {0.25, 0.25}}, {1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0}),
       {"strong-stability-preserving RK3 (Shu-Osher)", "explicit RK (SSP)",
        "C.-W. Shu & S. Osher, J. Comput. Phys. 77 (1988) 439-471"},
       StepModes::fixed},
      {make("rk4", 4, {{}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
            {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}),
       {"classic fourth-order Runge-Kutta", "explicit RK", kKutta},
       StepModes::fixed},
      {make("rk38", 4, {{}, {1.0 / 3.0}, {-1.0 / 3.0, 1.0}, {1.0, -1.0, 1.0}},
            {1.0 / 8.0, 3.0 / 8.0, 3.0 / 8.0, 1.0 / 8.0}),
       {"Kutta's 3/8-rule fourth-order method", "explicit RK", kKutta},
       StepModes::fixed},
      // Embedded pairs: fixed-step with --h, adaptive with rtol/atol (integrators/adaptive/).
      {make_embedded("bs3", 3, 2, true,
                     {{}, {1.0 / 2.0}, {0.0, 3.0 / 4.0}, {2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0}},
                     {2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0, 0.0},
                     {7.0 / 24.0, 1.0 / 4.0, 1.0 / 3.0, 1.0 / 8.0}),
       {"Bogacki-Shampine 3(2) embedded pair, FSAL; adaptive or fixed step", "embedded RK pair",
        "P. Bogacki & L. F. Shampine, Appl. Math. Lett. 2 (1989) 321-325"},
       StepModes::fixed_and_adaptive},
      {make_embedded(
           "dopri5", 5, 4, true,
           {{},
            {1.0 / 5.0},
            {3.0 / 40.0, 9.0 / 40.0},
            {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
            {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
            {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0},
            {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0}},
           {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0},
           {5179.0 / 57600.0, 0.0, 7571.0 / 16695.0, 393.0 / 640.0, -92097.0 / 339200.0,
            187.0 / 2100.0, 1.0 / 40.0}),
       {"Dormand-Prince 5(4) embedded pair, FSAL; adaptive or fixed step", "embedded RK pair",
        "J. R. Dormand & P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19-26"},
       StepModes::fixed_and_adaptive},
      {make_embedded(
           "cash_karp", 5, 4, false,
           {{},
            {1.0 / 5.0},
            {3.0 / 40.0, 9.0 / 40.0},
            {3.0 / 10.0, -9.0 / 10.0, 6.0 / 5.0},
            {-11.0 / 54.0, 5.0 / 2.0, -70.0 / 27.0, 35.0 / 27.0},
            {1631.0 / 55296.0, 175.0 / 512.0, 575.0 / 13824.0, 44275.0 / 110592.0, 253.0 / 4096.0}},
           {37.0 / 378.0, 0.0, 250.0 / 621.0, 125.0 / 594.0, 0.0, 512.0 / 1771.0},
           {2825.0 / 27648.0, 0.0, 18575.0 / 48384.0, 13525.0 / 55296.0, 277.0 / 14336.0,
            1.0 / 4.0}),
       {"Cash-Karp 5(4) embedded pair, fifth-order solution; adaptive or fixed step",
        "embedded RK pair", "J. R. Cash & A. H. Karp, ACM Trans. Math. Softw. 16 (1990) 201-222"},
       StepModes::fixed_and_adaptive},
      {make_embedded(
           "rkf45", 4, 5, false,
           {{},
            {1.0 / 4.0},
            {3.0 / 32.0, 9.0 / 32.0},
            {1932.0 / 2197.0, -7200.0 / 2197.0, 7296.0 / 2197.0},
            {439.0 / 216.0, -8.0, 3680.0 / 513.0, -845.0 / 4104.0},
            {-8.0 / 27.0, 2.0, -3544.0 / 2565.0, 1859.0 / 4104.0, -11.0 / 40.0}},
           {25.0 / 216.0, 0.0, 1408.0 / 2565.0, 2197.0 / 4104.0, -1.0 / 5.0, 0.0},
           {16.0 / 135.0, 0.0, 6656.0 / 12825.0, 28561.0 / 56430.0, -9.0 / 50.0, 2.0 / 55.0}),
       {"Runge-Kutta-Fehlberg 4(5), fourth-order solution; adaptive or fixed step",
        "embedded RK pair", "E. Fehlberg, NASA Technical Report R-315 (1969)"},
       StepModes::fixed_and_adaptive},
  };
  return all;
}

namespace {

std::vector<ButcherTableau> tableaux_of(StepModes steps) {
  std::vector<ButcherTableau> out;
  for (const ExplicitRkMethod& m : explicit_rk_methods())
    if (*m.steps == steps) out.push_back(*m.coefficients);
  return out;
}

}  // namespace

const std::vector<ButcherTableau>& explicit_tableaux() {
  static const std::vector<ButcherTableau> all = tableaux_of(StepModes::fixed);
  return all;
}

const std::vector<ButcherTableau>& embedded_tableaux() {
  static const std::vector<ButcherTableau> all = tableaux_of(StepModes::fixed_and_adaptive);
  return all;
}

}  // namespace stiffbench
