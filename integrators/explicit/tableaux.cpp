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
  return t;
}

}  // namespace

const std::vector<ButcherTableau>& explicit_tableaux() {
  static const std::vector<ButcherTableau> all = {
      make("euler", 1, {{}}, {1.0}),
      make("heun", 2, {{}, {1.0}}, {0.5, 0.5}),
      make("midpoint", 2, {{}, {0.5}}, {0.0, 1.0}),
      make("ralston", 2, {{}, {2.0 / 3.0}}, {0.25, 0.75}),
      make("kutta3", 3, {{}, {0.5}, {-1.0, 2.0}}, {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0}),
      make("ssprk3", 3, {{}, {1.0}, {0.25, 0.25}}, {1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0}),
      make("rk4", 4, {{}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
           {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}),
      make("rk38", 4, {{}, {1.0 / 3.0}, {-1.0 / 3.0, 1.0}, {1.0, -1.0, 1.0}},
           {1.0 / 8.0, 3.0 / 8.0, 3.0 / 8.0, 1.0 / 8.0}),
  };
  return all;
}

}  // namespace stiffbench
