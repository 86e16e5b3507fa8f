// stiffbench's public API: everything a program needs to study time integrators on its own
// ODE system. Include this one header (<stiffbench/stiffbench.hpp>) and link
// stiffbench::stiffbench (find_package(stiffbench) after `cmake --install`, or add_subdirectory).
//
// Stable (kept source-compatible within a minor version):
//   core/types.hpp, core/params.hpp        Vec/Index, Params (typed: Params{{"rtol", 1e-8}}),
//                                           ParamSpec (with Bounds), BadInput
//   core/ode_system.hpp                     OdeSystem (y' = f(t, y)) and MechanicalSystem,
//                                           with the optional additive split f = f_E + f_I
//   core/split_views.hpp                    explicit_part_view / implicit_part_view: one part
//                                           of a split as an OdeSystem of its own
//   core/theory/tableau.hpp, core/theory/additive_conditions.hpp
//                                           Butcher and additive (IMEX) tables; the additive
//                                           Runge-Kutta order conditions (the old paths
//                                           core/tableau.hpp, core/additive_conditions.hpp
//                                           forward there for one version)
//   core/integrator.hpp, core/solve_stats.hpp, core/driver.hpp
//                                           the integrator face, counters, fixed-step and
//                                           adaptive drivers
//   core/run_control.hpp                    wall-clock limit per row (timeout status) and
//                                           interrupt requests
//   integrators/method_file.hpp            methods as files: load_method_file(path),
//                                           parse_method_file, make_integrator(method),
//                                           method_registry_entry (register_integrator)
//   core/registry.hpp, core/registry_types.hpp, experiments/framework/catalog.hpp
//                                           the registries, register_model and
//                                           register_integrator for a user's own entries
//   experiments/framework/resolve.hpp       StudyTarget, StudyObjects (a user's own system and
//                                           integrator objects, nothing registered),
//                                           resolve_inputs -> StudyInputs, make_setup
//   experiments/framework/study.hpp         the study registry and pipeline: StudyContext,
//                                           TypedStudyJob, run_study
//   experiments/studies/convergence.hpp (local error too), work_precision.hpp, stability.hpp,
//   energy.hpp, region.hpp, audit.hpp, analyze.hpp
//                                           the studies: spec in, records out, CSV/Markdown/JSON
//                                           writers
//   experiments/commands/profile.hpp        performance and data profiles over a suite of
//                                           work-precision specs (run_profile, make_profile_suite)
//   experiments/commands/compare.hpp        two runs compared (compare_runs): run records, rows
//                                           by key, tolerances, wall-time verdicts
//   experiments/output/output.hpp, experiments/output/plotting.hpp
//                                           tables, atomic files, run metadata, gnuplot plots
//   experiments/commands/plot.hpp           an output folder's plots redrawn (replot_directory)
//   cli/cli_main.hpp                        the whole command line as cli_main(argc, argv)
// The headers' paths before experiments/ was split by job (experiments/NAME.hpp) still work
// for this version: each forwards to its new place.
// Every other installed header (the models' and integrators' own classes,
// experiments/commands/list_describe.hpp) is public but may change between versions.
#pragma once

#include "cli/cli_main.hpp"
#include "core/driver.hpp"
#include "core/integrator.hpp"
#include "core/ode_system.hpp"
#include "core/params.hpp"
#include "core/registry.hpp"
#include "core/registry_types.hpp"
#include "core/run_control.hpp"
#include "core/solve_stats.hpp"
#include "core/split_views.hpp"
#include "core/theory/additive_conditions.hpp"
#include "core/theory/tableau.hpp"
#include "core/types.hpp"
#include "experiments/commands/compare.hpp"
#include "experiments/commands/plot.hpp"
#include "experiments/commands/profile.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/resolve.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"
#include "experiments/output/plotting.hpp"
#include "experiments/studies/analyze.hpp"
#include "experiments/studies/audit.hpp"
#include "experiments/studies/convergence.hpp"
#include "experiments/studies/energy.hpp"
#include "experiments/studies/region.hpp"
#include "experiments/studies/stability.hpp"
#include "experiments/studies/work_precision.hpp"
#include "integrators/method_file.hpp"
