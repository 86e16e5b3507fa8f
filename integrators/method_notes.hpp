// The method class ("kind") and the literature reference of the built-in integrators that are
// classes rather than coefficient tables (verlet, leapfrog, rattle, bdf2, radau5, gauss, the
// graphics and fluid solvers, the library references), which `list integrators` and
// `describe NAME` print. The coefficient-defined methods carry theirs in their own table
// entries (integrators/method_entry.hpp). tests/test_method_notes.cpp checks every built-in
// integrator has a kind and a reference.
#pragma once

#include <map>
#include <string>

#include "core/registry_types.hpp"

namespace stiffbench {

struct MethodNote {
  std::string kind;       // e.g. "embedded RK pair", "Rosenbrock", "Gauss collocation"
  std::string reference;  // authors, venue, year (and section where it is a textbook)
};

// The whole table, by integrator name.
const std::map<std::string, MethodNote>& method_notes();

// The note for a built-in integrator, or nullptr.
const MethodNote* method_note(const std::string& name);

// Fills MethodInfo::kind and ::reference of the registered built-in integrators from the table
// (entries that already carry a reference, such as the coefficient-defined methods, are left
// alone).
void annotate_built_in_integrators(IntegratorRegistry& reg);

}  // namespace stiffbench
