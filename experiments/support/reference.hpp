// The reference solution of the step-size studies (convergence, local-error, work-precision) and
// of recommend: what a --reference resolves to (plan_reference, choose_reference), its values at
// given times (compute_reference) through the on-disk cache (reference_values), and the state at
// the end time (reference_at_end). The rules — which reference, its tolerances, the check run
// tighter by kReferenceTightening, the cache's key and file format — are stated in
// experiments/studies/convergence.hpp and experiments/studies/work_precision.hpp.
//
// A ReferenceRequest carries what the reference needs: the study's resolved inputs (the model's
// entry and every integrator a user named are looked up there, a fixed method the caller picks
// falls back to the process-wide registry), the parameters, the method, its tolerances and the
// cache folder.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "core/ode_system.hpp"
#include "core/params.hpp"
#include "experiments/framework/resolve.hpp"

namespace stiffbench {

// The second reference run: tolerances / kReferenceTightening, or half the step.
constexpr double kReferenceTightening = 10;
// The step-size studies' adaptive reference: rtol 1e-12, atol = rtol / kReferenceAtolDivisor.
constexpr double kStepReferenceRtol = 1e-12;
constexpr double kStepReferenceAtolDivisor = 100;

struct ReferenceRequest {
  // Where names are looked up (a study's inputs); null: the process-wide registries (a spec
  // checked by its names alone, before its inputs are resolved).
  const StudyInputs* inputs = nullptr;
  std::string model;  // the model's name (recorded in the cache key)
  Params params;      // the user's parameters: the reference integrator takes those it declares
  std::string method = "auto";       // auto | exact | published | METHOD (a label of inputs)
  std::optional<double> rtol, atol;  // of an adaptive reference; unset: the caller's default
  std::string cache_dir;             // the cache is DIR/reference/; empty: no cache
};

enum class RefKind { exact, adaptive, fixed_step };

// What a request resolves to for one model.
struct ReferencePlan {
  RefKind kind = RefKind::exact;
  std::string method;
  Params params;  // the reference integrator's effective parameters (defaults filled in)
  double h = 0;   // step of a fixed-step reference
  std::string description;
};

// The convergence and local-error reference: exact (auto where the model has one), an adaptive
// method at rtol (default kStepReferenceRtol) and atol (default rtol/kStepReferenceAtolDivisor),
// or a fixed-step method at h_finest/16. BadInput naming the flag for an unknown or unsuitable
// method, a missing exact solution, or tolerances that would do nothing.
ReferencePlan plan_reference(const ReferenceRequest& req, const OdeSystem& sys, double h_finest);
// The second reference run: tolerances / kReferenceTightening for an adaptive reference, half
// the step for a fixed-step one.
ReferencePlan tighter_plan(const ReferencePlan& plan);
// y_ref at `times` (increasing, after t0), from the model's initial state (uncached).
// std::runtime_error when the reference run fails.
std::vector<Vec> compute_reference(const ReferenceRequest& req, const ReferencePlan& plan,
                                   const OdeSystem& sys, const std::vector<double>& times);

struct ReferenceValues {
  std::vector<Vec> values;  // at the requested times, in their order
  std::string cache;        // the cache file read or written; empty without a cache
  bool from_cache = false;
};
// The reference at `times` (any order, duplicates allowed), through the cache when the request
// has a cache_dir and the reference is not exact (progress lines to `progress` when non-null).
ReferenceValues reference_values(const ReferenceRequest& req, const OdeSystem& sys,
                                 const ReferencePlan& plan, std::vector<double> times,
                                 std::ostream* progress);

// The reference state at t_end: the exact solution (`auto` where the model has one), else
// `method` (auto: cvode_bdf) adaptively at rtol/atol (default 1e-14, 1e-16), or a fixed-step
// method at h_fine/16; `description` says which.
Vec reference_at_end(const ReferenceRequest& req, const OdeSystem& sys, double t_end, double h_fine,
                     std::string* description);

// Work-precision's reference (experiments/studies/work_precision.hpp, "The reference"), chosen
// from req.method before anything runs. BadInput for an unknown METHOD, a METHOD that is also one
// of `studied` (by name; a method file by the name it registers), `exact` on a model without an
// exact solution, `published` without a published solution at t_end; with sys null only the
// names are checked. `numerical` is the request of the numerical reference for reference_at_end
// (METHOD, or cvode_bdf for auto and published), `check` the same tighter by
// kReferenceTightening: rtol and atol / 10, or for a fixed-step method h_fine / 2
// (check_h_factor).
struct ReferenceChoice {
  std::string kind;    // "exact", "published", "auto" or "method"
  std::string method;  // the numerical reference's integrator
  ReferenceRequest numerical, check;
  double check_h_factor = 1;
  std::string check_description;  // of the check run (reference_at_end's, or the halved step)
};
ReferenceChoice choose_reference(const ReferenceRequest& req,
                                 const std::vector<std::string>& studied, const OdeSystem* sys,
                                 double t_end, double h_fine);

}  // namespace stiffbench
