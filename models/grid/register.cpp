// Registration of the Eulerian grid models (models/grid/) with their parameters.
#include <algorithm>
#include <cmath>

#include "models/grid/fluid_2d.hpp"
#include "models/grid/heat_2d.hpp"
#include "models/register.hpp"

namespace stiffbench {

namespace {

using P = ParamType;
using B = Bounds;

int grid_int(const Params& p, const std::string& key, const std::string& model, long lo, long hi) {
  const long v = p.integer(key);
  require_input(v >= lo && v <= hi, model + ": parameter '" + key + "' must be in [" +
                                        std::to_string(lo) + ", " + std::to_string(hi) + "] (got " +
                                        std::to_string(v) + ")");
  return static_cast<int>(v);
}

void add_heat(ModelRegistry& reg) {
  reg.add(
      {.info =
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
       }});
}

void add_fluid(ModelRegistry& reg) {
  reg.add(
      {.info =
           {.name = "fluid_2d",
            .description =
                "incompressible Navier-Stokes on a MAC grid, u' = P[-(u.grad)u + nu Laplace(u) + "
                "g] "
                "(pressure projection); scenes taylor_green (periodic) and cavity (lid-driven); "
                "observables kinetic_energy, max_divergence; split=diffusion: advection explicit, "
                "diffusion implicit",
            .source =
                "Taylor-Green: kinetic energy decays as exp(-16 pi^2 t/Re) (Taylor & Green 1937); "
                "cavity: Ghia, Ghia & Shin 1982 centreline profiles",
            // fluid_2d: about 2 n^2 face velocities; the pressure Laplacian on n^2 cells and its
            // sparse Cholesky factor (nested-dissection fill of a 2D grid, about n^2 (6 + 2 log2 n)
            // entries of 12 bytes), work vectors; f has no analytic Jacobian.
            .size =
                [](const Params& p) {
                  const double n = std::max(static_cast<double>(p.integer("n")), 1.0);
                  const double cells = n * n;
                  const double factor = cells * (6.0 + 2.0 * std::log2(n)) + 5.0 * cells;
                  return ModelSize{2.0 * cells + 2.0 * n, 12.0 * factor + 96.0 * cells, 0.0,
                                   "n=" + std::to_string(p.integer("n"))};
                }},
       .params =
           {{"scene",
             P::text,
             "taylor_green",
             "taylor_green (periodic unit box, u = sin 2pi x cos 2pi y) or cavity (walls, lid "
             "at y = 1, starting at rest)",
             {"taylor_green", "cavity"}},
            {"n", P::integer, "32", "cells per direction (unknowns about 2 n^2)", B::in(4, 2048)},
            {"re", P::real, "100", "Reynolds number U L / nu (U = 1 or the lid speed, L = 1)",
             B::positive()},
            {"lid", P::real, "1", "cavity lid speed U along x", B::positive()},
            {"gravity", P::real, "0", "body force along -y", B::any()},
            {"solver",
             P::text,
             "cholesky",
             "pressure Poisson solver: cholesky (sparse LDLT factorised once per grid) or cg",
             {"cholesky", "cg"}},
            {"advection",
             P::text,
             "linear",
             "interpolation of the semi-Lagrangian advection (stable_fluids only): linear "
             "(Stam 1999) or cubic (Catmull-Rom)",
             {"linear", "cubic"}},
            {"split",
             P::text,
             "none",
             "additive split f = f_E + f_I: none (f is not divided) or diffusion (f_E = "
             "P[-(u.grad)u + g] explicit, f_I = P[nu Laplace(u) + nu b] implicit, no analytic "
             "J_I)",
             {"none", "diffusion"}}},
       .make = [](const Params& p) {
         Fluid2dOptions o;
         o.scene = p.text("scene") == "cavity" ? Fluid2dOptions::Scene::cavity
                                               : Fluid2dOptions::Scene::taylor_green;
         o.n = grid_int(p, "n", "fluid_2d", 4, 2048);
         o.re = p.real("re");
         o.lid = p.real("lid");
         o.gravity = p.real("gravity");
         o.solver = p.text("solver") == "cg" ? Fluid2dOptions::Solver::cg
                                             : Fluid2dOptions::Solver::cholesky;
         o.advection = p.text("advection") == "cubic" ? Fluid2dOptions::Advection::cubic
                                                      : Fluid2dOptions::Advection::linear;
         o.split = p.text("split") == "diffusion" ? Fluid2dOptions::Split::diffusion
                                                  : Fluid2dOptions::Split::none;
         return std::make_unique<Fluid2d>(o);
       }});
}

}  // namespace

void register_grid_models(ModelRegistry& reg) {
  add_heat(reg);
  add_fluid(reg);
}

}  // namespace stiffbench
