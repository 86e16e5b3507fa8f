// The process-wide registries of models and integrators, and creation of a model plus a set of
// integrators from one Params bag with the unknown-key check.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/registry_types.hpp"

namespace stiffbench {

const ModelRegistry& model_registry();
const IntegratorRegistry& integrator_registry();

// Adds a model or an integrator defined outside the library (a user's own right-hand side) to
// the process-wide registries, so that every experiment, `describe` and `solve` (through
// cli_main) find it by name. Call before using it, from one thread (the registries are not
// locked). A name already registered is a std::logic_error. The entry's factory receives the
// declared parameters with their defaults filled in, exactly as the built-in models do:
//
//   register_model({ModelInfo{"my_brusselator", "1D Brusselator (Hairer-Wanner II)"},
//                   {{"n", ParamType::integer, "32", "grid points"}},
//                   [](const Params& p) { return std::make_unique<Brusselator>(p.integer("n"));
//                   }});
void register_model(ModelRegistry::Entry entry);
void register_integrator(IntegratorRegistry::Entry entry);

// A user's system object for a study (StudyObjects in experiments/framework/resolve.hpp): makes a
// fresh copy for every run.
using SystemFactory = std::function<std::unique_ptr<OdeSystem>()>;
// A user's integrator object for a study (StudyObjects): a fresh one per use.
using IntegratorFactory = std::function<std::unique_ptr<Integrator>()>;

// ---- Sizes and memory -------------------------------------------------------------------------
// A run is checked before anything is allocated: the model's ModelSize (from its parameters)
// plus what the integrators add is compared with a size limit (kMaxDimension: Eigen's sparse
// matrices index with int) and with the memory limit: --max-memory, else the memory the machine
// has available now (MemAvailable of /proc/meminfo).
inline constexpr double kMaxDimension = 2147483647.0;

struct RunMemory {
  ModelSize model;
  double state_bytes = 0;        // state and work vectors (integrator stages, outputs)
  double jacobian_bytes = 0;     // sparse Jacobian, iteration matrix and its factors
  double dense_bytes = 0;        // dense matrices of integrators that use dense linear algebra
  std::string dense_integrator;  // the first such integrator (for the message)
  double total() const { return model.model_bytes + state_bytes + jacobian_bytes + dense_bytes; }
};

// --max-memory: bytes, or a number with K/M/G/T (powers of 1024), e.g. 512M, 8G. 0 (default):
// the available memory. BadInput naming the flag for anything else.
double parse_memory_size(const std::string& text, const std::string& flag = "--max-memory");
void set_memory_limit(double bytes);
// The limit in force (bytes) and where it comes from ("--max-memory" or "available memory").
double memory_limit(std::string* source = nullptr);
// "1.5 GiB" for messages.
std::string format_bytes(double bytes);

// ---- Methods as files (integrators/method_file.hpp) ---------------------------------------------
// Wherever an integrator name is taken (--integrators, solve --integrator, spec files, sweeps), a
// token that ends in ".toml" or contains '/' is the path of a method file: it is loaded, checked,
// registered process-wide under the file's `name` and replaced by that name before anything
// runs. The same file given again (or a file with the same text) is registered once; a file whose
// name is already taken by another method (built in, registered, or another file) is BadInput
// naming both.
bool is_method_file_token(const std::string& token);
// Loads and registers `path` (relative paths from `base` when given, else from the working
// folder); returns the method's name.
std::string register_method_file(const std::string& path, const std::string& base = "");
// `tokens` with every method-file token replaced by its method's name (registering the file) and
// every variant by its label (registering it, below); names pass unchanged.
std::vector<std::string> resolve_integrator_tokens(std::vector<std::string> tokens,
                                                   const std::string& base = "");
// The search path: every *.toml (sorted by name) in each folder of STIFFBENCH_METHOD_PATH
// (colon-separated; empty entries skipped) and in each of `dirs` (--methods DIR), registered as
// above. A folder that does not exist, or a bad file in one, is BadInput naming it.
void load_method_search_path(const std::vector<std::string>& dirs = {});
// The method file an integrator was registered from (its path as loaded; a built-in method's
// "methods/<file>.toml (built in)"), "" for the others.
std::string method_file_source(const std::string& name);
// `spec` (a study's or a run's spec JSON) with "method_files": {name: {"file": path, "fnv1a64":
// hash of its text}} for the integrators it names ("integrators" or "integrator") that came from
// method files, so that results record the file and a changed file is a different spec; `spec`
// unchanged when it names none.
nlohmann::json with_method_files(nlohmann::json spec);
// run_metadata (experiments/output/output.hpp) of a study's or a command's spec: the method files
// and variants it names recorded (with_method_files), and the model it names described when it
// is a registered one (also one registered from outside the library, register_model).
nlohmann::json run_metadata(const std::string& experiment, const nlohmann::json& spec);

// ---- Integrator variants -----------------------------------------------------------------------
// Wherever an integrator name is taken, `METHOD{key=value,...}` is METHOD (a name or a method-file
// path) with some of its parameters fixed: `radau5{linear_solver=dense_lu}`,
// `my_esdirk.toml{newton=full}`. The variant is registered process-wide under its label, which
// tables and plots show: `label=TEXT` among the assignments, else the canonical text
// `NAME{k=v,...}` (keys sorted, the method file replaced by its method's name). Its values are
// checked against METHOD's declarations when it is registered (BadInput naming the variant);
// the fixed keys are not offered to --param (a variant's own value wins). The same variant given
// again is registered once; a label already taken by another method is BadInput.
bool is_variant_token(const std::string& token);
// Registers the variant (relative method-file paths from `base`) and returns its label.
std::string register_variant(const std::string& token, const std::string& base = "");
// The method a variant label stands for and its fixed parameters; nullopt for other names.
struct VariantOf {
  std::string base;  // the registered method it is a variant of
  Params fixed;
};
std::optional<VariantOf> variant_of(const std::string& name);

// Splits "a,b,c" (empty items are BadInput naming the flag); a comma inside braces (a variant's
// assignments) does not split.
std::vector<std::string> split_list(const std::string& s, const std::string& flag);

// The whole of `text` as a finite number, else BadInput "FLAG: 'text' is not a finite number"
// (`flag` names the option, and where it helps the item's place, e.g. "--sweep h").
double parse_real(const std::string& text, const std::string& flag);
// "a,b,c" of finite numbers (split_list, then parse_real on each).
std::vector<double> parse_real_list(const std::string& text, const std::string& flag);

}  // namespace stiffbench
