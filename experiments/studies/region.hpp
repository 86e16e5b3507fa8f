// Linear stability regions (`stiffbench region`): the boundary |R(z)| = 1 of each integrator in
// the complex plane z = hλ, and its stability limits as numbers, all computed from the method's
// coefficients (core/theory/linear_stability.hpp), never from a run.
//
//   Runge–Kutta (explicit and DIRK) and Rosenbrock: the contour |R(z)| = 1 of
//     R(z) = 1 + z bᵀ(I − zA)⁻¹1, traced by marching squares on a resolution × resolution grid
//     of the box, each crossing refined by bisection (so every point has |R| = 1 to ~1e-12);
//   BDF2 (linear multistep): the boundary locus z(θ) = ρ(e^{iθ})/σ(e^{iθ}) clipped to the box;
//   kick/drift splittings, Verlet, leapfrog: no region in the z-plane (they need a mechanical
//     system); only the stable interval of hω on the undamped oscillator x'' = −ω²x;
//   IMEX pairs (named; not in the default set): no region of their own, so the regions of their
//     two tables alone, as rows NAME:explicit and NAME:implicit (the explicit table's on f_E's
//     eigenvalues, the implicit table's on f_I's; `analyze` gives their exact figures).
//
// Limits per integrator: the real-axis limit (the first z = −r where the method becomes
// unstable, as that negative number; −inf when stable on the whole negative axis), the
// imaginary-axis limit (the first z = i·r; 0 when unstable arbitrarily close to 0, as explicit
// Euler, heun, cash_karp and rkf45; inf when stable on the whole axis), the oscillator limit on
// hω (inf: unconditionally stable), and A-stability (exact for R = P/Q, a_stable_exact; BDF2 on
// samples of the left half-plane, a_stable_on_samples). The limits are exact for every method with
// R = P/Q (the roots of |P|² − |Q|² along the axis, core/theory/linear_stability.hpp) and for the
// splittings' oscillator limit (their half-trace polynomial); BDF2's are from the sampled search.
// Column `limits` says which (exact | sampled).
//
// The default box (no --box) is fitted to the chosen methods: their boundaries are traced on a
// coarse grid of [−12, 12]², every closed (bounded) boundary and the finite axis limits are
// enclosed, 10% margin, rounded outward to 0.5 and symmetric in Im z. Boundaries running off to
// infinity (implicit midpoint's imaginary axis) do not widen it.
#pragma once

#include <complex>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/theory/linear_stability.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"

namespace stiffbench {

struct RegionBox {
  double re_min = -6, re_max = 3, im_min = -4.5, im_max = 4.5;
};

struct RegionSpec {
  // The integrators' labels (StudyInputs::integrators). Empty: every registered integrator that
  // has stability data (region_integrators()).
  std::vector<std::string> integrators;
  std::optional<RegionBox> box;  // empty: fitted to the chosen methods (see above)
  int resolution = 400;          // grid cells per side of the box

  // BadInput naming the flag: an integrator listed twice, an empty or non-finite box, a
  // resolution outside [10, 4000]. (run_region also refuses an integrator without stability
  // data: "cvode_bdf has no fixed stability region ...".)
  void validate() const;
  nlohmann::json to_json() const;
};

// The registered integrators whose linear_stability() is set, in registry order.
std::vector<std::string> region_integrators();

struct RegionMethod {
  std::string integrator;
  std::string family;  // registry family (explicit, symplectic, implicit)
  std::string kind;    // LinearStability::kind
  // The boundary as polylines in the box; empty for mechanical-only methods.
  std::vector<std::vector<std::complex<double>>> boundary;
  bool has_region = false;  // the method has a scalar amplification R(z)
  // Unset for mechanical-only methods.
  std::optional<AxisLimit> real_axis, imaginary_axis;
  std::optional<bool> a_stable;
  AxisLimit oscillator;  // limit on hω of x'' = −ω²x
  // The first earlier method of the run with the same |R(z)| (to 1e-12 on a fixed set of
  // sample points, so the same region); empty when none.
  std::string same_as;
  // Empty when complete; otherwise why the method stopped (over --max-wall): its boundary is
  // then empty and its limits unset.
  std::string stopped;
};

struct RegionResult {
  RegionBox box;  // the box used
  bool box_fitted = false;
  int resolution = 0;
  std::vector<RegionMethod> methods;  // in the order of the spec
};

// Parses --box "re_min,re_max,im_min,im_max"; BadInput naming --box when malformed.
RegionBox parse_region_box(const std::string& arg);

// Computes the regions of `in`'s integrators (the spec's integrators are `in`'s; a user's own
// methods, given as objects to resolve_inputs, need linear_stability()). BadInput before
// anything is computed for an integrator without stability data or a bad spec. Nothing is
// written to `progress` (the methods are computed in parallel).
RegionResult run_region(const StudyInputs& in, const RegionSpec& spec,
                        std::ostream* progress = nullptr);
// The same on the names the spec gives (resolve_inputs first).
RegionResult run_region(const RegionSpec& spec, std::ostream* progress = nullptr);
// The one call: check DIR, compute, write DIR/region.{csv,md,json} and region_limits.csv, plot,
// print (ctx.out).
RegionResult region_study(const StudyInputs& in, RegionSpec spec, const std::filesystem::path& dir,
                          const StudyContext& ctx = {});
const RegionResult& region_result(const StudyJob& job);

// The box enclosing the bounded boundaries and finite axis limits of `methods` (see above).
RegionBox fitted_region_box(const std::vector<LinearStability>& methods);

// region.csv: integrator, re, im. The rows of one polyline are consecutive and in order; between
// two polylines of one integrator a row `rk4,nan,nan` marks the break: gnuplot 5.4 lifts the
// pen at a NaN point `with lines` (an empty field, `rk4,,`, is a missing point and gnuplot draws
// straight through it), and CSV readers (pandas, std::stod) read nan as NaN. Mechanical-only
// methods have no rows.
Table region_table(const RegionResult& r);
// region_limits.csv: integrator, family, kind, real_axis_limit, imaginary_axis_limit,
// oscillator_limit, a_stable, limits. Limits at full precision; -inf / inf when unbounded; empty
// where not applicable (mechanical-only methods have only the oscillator limit); a_stable yes/no;
// limits exact (every limit of the row from polynomial roots) or sampled.
Table region_limits_table(const RegionResult& r);
// "exact" or "sampled", as in the limits column above.
std::string limits_how(const RegionMethod& m);
// The Markdown limits table printed by the command: integrator, kind, real-axis limit,
// imaginary-axis limit, oscillator limit hω (10 decimals), A-stable, limits.
Table region_limits_markdown_table(const RegionResult& r);

// Writes DIR/region.csv, DIR/region_limits.csv, DIR/region.md and DIR/region.json.
void write_region_outputs(const std::filesystem::path& dir, const RegionSpec& spec,
                          const RegionResult& r);

// The plot of DIR/region.csv (→ DIR/region.png): the complex plane with equal aspect, one panel
// per integrator family, each method's boundary in its own colour; the range encloses every
// boundary point of the CSV.
bool plot_region(const std::filesystem::path& csv, const std::string& title, const PlotOptions& opt,
                 std::ostream& err);

}  // namespace stiffbench
