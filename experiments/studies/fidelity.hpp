// What an integrator does to vibrations at large steps (`stiffbench fidelity`): numerical
// damping and period error per mode, analytic from the method's coefficients and measured from
// runs.
//
// Undamped oscillator x'' = −ω²x at ν = hω. One step maps the mode by the step map's dominant
// eigenvalue μ = A e^{iθ} (core/theory/linear_stability.hpp:
// LinearStability::mechanical_multiplier; R(iν) for one-step methods, the largest root of ρ(ζ) −
// iνσ(ζ) for multistep ones, the 2×2 kick/drift matrix's eigenvalue for splittings); the exact flow
// has μ = e^{iν}. Reported per ν (Hilber, Hughes & Taylor 1977, definitions in OscillatorResponse):
// amplification A, damping ratio ξ̄ = −ln A/θ, period error ν/θ − 1 and frequency error θ/ν − 1.
//
//   analytic  from the coefficients, for every method with stability data, on a log grid of ν
//             from nu_min to nu_max;
//   measured  from one run per ν of `steps` steps on harmonic_oscillator (m = k = 1, x0 = 1,
//             v0 = 0, so h = ν), for every method that can run it at a fixed step (those
//             without stability data included), else on spring_chain with one free mass
//             (ω = √2; xpbd, projective dynamics); lie/strang and the IMEX pairs need a split
//             and are named as not measured. The run's samples (x_n, v_n) are iterates of
//             one linear map, so each sequence satisfies the linear recurrence of that map's
//             characteristic polynomial (Cayley–Hamilton): s_{n+p} = Σ_{j<p} c_j s_{n+j}.
//             fit_step_multiplier() fits it by least squares over both sequences (each equation
//             scaled to its largest term, the first `skip` samples dropped for multistep start-up)
//             with p = 2, then 4, then 6 until the fit is exact to 1e-8; the measured μ is the
//             root of largest modulus of ζ^p − Σ c_j ζ^j. For methods with stability data the
//             measured curve must lie on the analytic one: fidelity.md gives the largest
//             difference in amplification and phase per method.
//
// Per mode on a mechanical model (--model): the linearised modes at the rest state y0 = (x0, 0)
// (which must be an equilibrium: |a(x0, 0)| <= 1e-9 × the largest |K x0|-scale, else BadInput
// naming gravity or the offending setting), from the generalised eigenproblem −M K φ = ω² M φ
// (K = ∂a/∂x, M the masses; fixed dofs removed; dense, dimension <= 4000), the lowest `modes`
// with ω > 1e-6 ω_max (rigid and zero-stiffness modes skipped). A run from
// x(0) = x0 + ε Σ_k φ_k/‖φ_k‖∞ (ε = amplitude × the RMS spread of x0, so the motion is linear to
// O(amplitude)), v(0) = 0, of `mode_steps` steps per step size h; the trajectory projected on
// each mode (q_k = φ_kᵀ M (x − x0), p_k = φ_kᵀ M v with M-orthonormal φ) gives per mode the
// measured μ by the same recurrence fit, against the analytic μ at ν = hω_k. A linear method on
// a linear system commutes with the modal decomposition, so each q_k follows its own scalar
// recurrence exactly. Models with damping (D = ∂a/∂v ≠ 0 at rest) are refused: the curve is that
// of the undamped oscillator. Default steps: ν = 0.1 at the lowest and ν = 2 at the highest
// selected mode.
//
// Files: fidelity.csv (integrator, nu, amplification, damping_ratio, period_error,
// frequency_error, source = analytic | measured), modes.csv (integrator, h, mode, omega, nu, and
// measured and predicted amplification, damping ratio and period error, with the relative
// differences of damping ratio and frequency), fidelity.md (tables and checks), fidelity.json,
// fidelity.png (damping ratio and |period error| against ν, log–log, lines analytic, points
// measured) and, with a model, modes.png.
#pragma once

#include <complex>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "core/theory/linear_stability.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

// The dominant eigenvalue of the linear map whose iterates the sequences are (see above).
struct RecurrenceFit {
  bool ok = false;
  std::complex<double> multiplier;  // Im >= 0
  int order = 0;                    // p
  double residual = 0.0;            // largest scaled residual of the fitted equations
  std::string reason;               // why not ok
};
// `order` > 0: fit only that order and accept any residual (it is reported); 0: p = 2, 4, 6
// until the largest scaled residual is <= tolerance, using the equations whose largest term is
// at least `floor` × the series' largest (0: down to underflow).
RecurrenceFit fit_step_multiplier(const std::vector<std::vector<double>>& series, int skip,
                                  double tolerance = 1e-8, int order = 0, double floor = 0.0);

struct FidelitySpec {
  std::vector<std::string> integrators;
  std::string model;  // empty: the oscillator curves only
  Params params;
  double nu_min = 1e-2, nu_max = 1e2;
  int curve_points = 41;
  bool measure = true;
  long steps = 400;       // per measured oscillator run
  std::vector<double> h;  // per-mode step sizes (empty: the default above)
  int modes = 20;
  // 1e-7: the modes' nonlinear coupling adds O(amplitude) to each measured damping ratio (on the
  // 16 x 16 cloth, mode 1 of the trapezoidal rule, exact ξ̄ = 0: 6.0e-5 at 1e-4, 5.2e-7 at 1e-6,
  // about 5e-9 at 1e-8), which at 1e-4 put undamped and lightly damped methods outside 5%.
  double amplitude = 1e-7;
  long mode_steps = 400;
  void validate() const;  // BadInput naming the flag
  nlohmann::json to_json() const;
};

struct FidelityPoint {
  std::string integrator;
  std::string source;  // analytic | measured
  OscillatorResponse r;
};

struct ModePoint {
  std::string integrator;
  double h = 0.0;
  int mode = 0;  // 1-based, by ω
  double omega = 0.0;
  std::optional<OscillatorResponse> measured, predicted;
  std::string note;  // why measured or predicted is missing
};

struct FidelityResult {
  std::vector<FidelityPoint> curve;
  std::vector<ModePoint> modes;
  std::vector<std::pair<std::string, std::string>> skipped;  // integrator, why no measured curve
  std::vector<std::pair<std::string, std::string>> measured_on;  // integrator, test system
  struct Unfitted {
    std::string integrator;
    double nu = 0.0;
    std::string reason;
  };
  std::vector<Unfitted> unfitted;  // measured runs the recurrence did not fit (nonlinear method)
  std::vector<double> mode_steps_used;
  // Per integrator (in the spec's order), from its stability data with the run: the analytic
  // values shown at nu = 0.1, 1 and 10 (those in [nu_min, nu_max]) and the largest differences
  // |A_measured − A_analytic| / max(1, A_analytic) and |θ_measured − θ_analytic| over its
  // measured points.
  struct Analytic {
    std::string integrator;
    bool stability = false;  // the method has linear stability data
    bool curve = false;      // ... with a mechanical multiplier: an analytic curve
    long measured = 0;       // measured points
    double max_da = 0.0, max_dtheta = 0.0;
    std::vector<OscillatorResponse> glance;
  };
  std::vector<Analytic> analytic;
  // key=value of the model's rest state applied to parameters the user did not set.
  std::vector<std::string> rest_state_applied;
};

// The spec with the model's rest state (ModelInfo::rest_state of `in`'s model) applied to the
// parameters the user did not set, so that the per-mode analysis linearises at an equilibrium at
// rest (the defaults of cloth load it with gravity and a random perturbation). `applied` lists
// the key=value pairs added. run_fidelity applies it itself; the command records the result.
FidelitySpec with_rest_state(const StudyInputs& in, FidelitySpec spec,
                             std::vector<std::string>* applied = nullptr);
// The curves of every integrator of `in` and, when `in` has a model, its modes; the spec's
// model, params (with the rest state applied) and integrators are `in`'s. Every refusal of the
// model (not mechanical, not at rest, damped) comes before any run.
FidelityResult run_fidelity(const StudyInputs& in, const FidelitySpec& spec,
                            std::ostream* progress = nullptr);
// The same on the names the spec gives (resolve_inputs first).
FidelityResult run_fidelity(const FidelitySpec& spec, std::ostream* progress = nullptr);
// The one call: check DIR, run, write DIR/fidelity.{csv,md,json} and modes.csv, plot, print
// (ctx.out).
FidelityResult fidelity_study(const StudyInputs& in, FidelitySpec spec,
                              const std::filesystem::path& dir, const StudyContext& ctx = {});
Table fidelity_table(const FidelityResult& r);
Table modes_table(const FidelityResult& r);

StudyKind fidelity_study_kind();
const FidelityResult& fidelity_result(const StudyJob& job);

}  // namespace stiffbench
