// What the step-size studies (convergence, local-error, work-precision) share: the spec of the
// system, the ladder of steps h_k = h / refine^k and the reference; its options, declared and
// read once; the metadata the three record; and the floor constants their rows are checked with.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/params.hpp"
#include "experiments/support/reference.hpp"

namespace stiffbench {

// What the step-size studies (convergence, local-error, work-precision) share: the system, the
// ladder of steps h_k = h / refine^k and the reference the errors are measured against. Its
// options are declared once (step_study_options) and read once (read_step_study_options).
struct StepStudyDefaults;
struct StepStudySpec {
  std::string model;
  Params params;
  std::vector<std::string> integrators;
  double t_end = 1.0;
  // Coarsest step; NaN: the model's suggested step (SuggestedStep), an error if it has none.
  double h = 0.1;
  int levels = 5;
  double refine = 2.0;
  std::string reference = "auto";  // auto | exact | METHOD
  // Tolerances of an adaptive reference (--reference-rtol, --reference-atol); unset: the
  // study's defaults. Set with an exact or fixed-step reference: BadInput naming the flag.
  std::optional<double> reference_rtol, reference_atol;

  // h_k = h0 / refine^k for k < levels.
  std::vector<double> step_ladder(double h0) const;
  // h0 / h_finest = refine^(levels - 1).
  double ladder_span() const;
  // The reference the spec names (method and tolerances), looked up in `in` (null: the
  // process-wide registries), cached in `cache_dir` (empty: not cached).
  ReferenceRequest reference_request(const StudyInputs* in,
                                     const std::string& cache_dir = "") const;
  // BadInput naming the flag for a bad ladder or tolerance.
  void validate_step_study() const;
  // The keys above as JSON (the recorded spec of the three studies).
  nlohmann::json step_study_json() const;
  // The reference method (an integrator whose parameters the study consumes, when it is one).
  std::vector<std::string> reference_integrators() const;
  // The ladder length and reference tolerances of a study's declared defaults.
  void apply_defaults(const StepStudyDefaults& d);
};

// The options of StepStudySpec for the study registry (which of them a study requires is its
// StudyKind::required); the help texts and the defaults of the ladder and of the reference
// tolerances differ between the studies.
struct StepStudyDefaults {
  std::string t_end_help, h_help;
  std::string ladder_levels = "5", ref_rtol, ref_atol, ref_help;
  // Appended to the help of the reference tolerances (a default the study computes).
  std::string ref_rtol_note, ref_atol_note;
};
// The flags of the options above as messages name them.
struct StepStudyFlags {
  const char *reference, *reference_rtol, *reference_atol, *refine;
};
// The key the reference option is recorded under (the spec's JSON, the reference cache's key).
inline constexpr const char* kReferenceKey = "reference";
inline constexpr StepStudyFlags kStepFlags{"--reference", "--reference-rtol", "--reference-atol",
                                           "--refine"};
std::vector<ParamSpec> step_study_options(const StepStudyDefaults& d);
void read_step_study_options(const Params& options, StepStudySpec& spec);
// The metadata of the three studies' NAME.json: the step used and where it came from, the
// reference's description.
void add_step_study_metadata(nlohmann::json& meta, double h_used, const std::string& h_source,
                             const std::string& reference);

// The unit round-off u = 2^-53 of the round-off floors.
constexpr double kUnitRoundoff = 0x1p-53;
// A row within this factor of a floor (round-off or the reference's accuracy) is at the floor.
constexpr double kFloorFactor = 10;

}  // namespace stiffbench
