#include "experiments/support/step_study.hpp"

#include <cmath>
#include <string>

#include "core/types.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

double StepStudySpec::ladder_span() const { return std::pow(refine, levels - 1); }

ReferenceRequest StepStudySpec::reference_request(const StudyInputs* in,
                                                  const std::string& cache_dir) const {
  return {in, model, params, reference, reference_rtol, reference_atol, cache_dir};
}

std::vector<double> StepStudySpec::step_ladder(double h0) const {
  std::vector<double> hs;
  for (int k = 0; k < levels; ++k) hs.push_back(h0 / std::pow(refine, k));
  return hs;
}

void StepStudySpec::validate_step_study() const {
  require_input(std::isnan(h) || (std::isfinite(h) && h >= 0),
                "--h must be > 0 (got " + format_full(h) + ")");
  require_input(levels >= 2, "--levels must be >= 2 (got " + std::to_string(levels) + ")");
  require_input(std::isfinite(refine) && refine > 1,
                "--refine must be > 1 (got " + format_full(refine) + ")");
  require_input(!integrators.empty(), "--integrators: no integrator given");
  if (reference_rtol)
    require_input(std::isfinite(*reference_rtol) && *reference_rtol > 0,
                  "--reference-rtol must be > 0 (got " + format_full(*reference_rtol) + ")");
  if (reference_atol)
    require_input(std::isfinite(*reference_atol) && *reference_atol > 0,
                  "--reference-atol must be > 0 (got " + format_full(*reference_atol) + ")");
}

nlohmann::json StepStudySpec::step_study_json() const {
  return {{"model", model},
          {"params", params.values()},
          {"integrators", integrators},
          {"t_end", t_end},
          {"h", h},
          {"levels", levels},
          {"refine", refine},
          {"reference", reference},
          {"reference_rtol", reference_rtol ? nlohmann::json(*reference_rtol) : nlohmann::json()},
          {"reference_atol", reference_atol ? nlohmann::json(*reference_atol) : nlohmann::json()}};
}

std::vector<std::string> StepStudySpec::reference_integrators() const { return {reference}; }

void StepStudySpec::apply_defaults(const StepStudyDefaults& d) {
  levels = std::stoi(d.ladder_levels);
  if (!d.ref_rtol.empty()) reference_rtol = std::stod(d.ref_rtol);
  if (!d.ref_atol.empty()) reference_atol = std::stod(d.ref_atol);
}

void add_step_study_metadata(nlohmann::json& meta, double h_used, const std::string& h_source,
                             const std::string& reference) {
  meta["h_used"] = h_used;
  meta["h_source"] = h_source;
  meta["reference"] = reference;
}

std::vector<ParamSpec> step_study_options(const StepStudyDefaults& d) {
  using P = ParamType;
  return {
      {"t_end", P::real, "", d.t_end_help, Bounds::positive()},
      {"h", P::real, "", d.h_help, Bounds::positive()},
      {"levels", P::integer, d.ladder_levels, "number of step sizes", Bounds::at_least(2)},
      {"refine", P::real, "2", "ratio between consecutive step sizes", Bounds::above(1)},
      {"reference", P::text, "auto", d.ref_help},
      {"reference_rtol", P::real, d.ref_rtol,
       "relative tolerance of an adaptive reference run" + d.ref_rtol_note, Bounds::positive()},
      {"reference_atol", P::real, d.ref_atol,
       "absolute tolerance of an adaptive reference run" + d.ref_atol_note, Bounds::positive()},
  };
}

void read_step_study_options(const Params& o, StepStudySpec& spec) {
  if (o.contains("t_end")) spec.t_end = o.real("t_end");
  spec.h = optional_real(o, "h");
  spec.levels = static_cast<int>(o.integer("levels"));
  spec.refine = o.real("refine");
  // A method file or a variant named as the reference is registered here, once, like the
  // studied integrators; the spec holds its label.
  spec.reference = o.text("reference");
  if (is_method_file_token(spec.reference) || is_variant_token(spec.reference))
    spec.reference = resolve_integrator_tokens({spec.reference}).front();
  if (o.contains("reference_rtol")) spec.reference_rtol = o.real("reference_rtol");
  if (o.contains("reference_atol")) spec.reference_atol = o.real("reference_atol");
}

}  // namespace stiffbench
