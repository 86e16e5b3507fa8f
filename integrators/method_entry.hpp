// One entry per coefficient-defined method: its coefficients, description, kind, literature
// reference and step modes, side by side. Each family keeps one table of these entries
// (integrators/explicit/tableaux.cpp, implicit/dirk.cpp, implicit/linearly_implicit.cpp,
// symplectic/kick_drift.cpp, symplectic/composition.cpp); registration (integrators/register.cpp),
// the MethodInfo kind and reference, and the tableau lookups the tests use are all derived from
// those tables.
//
// Every field is required at compile time: `Text` and `Required<T>` have no default constructor,
// so an entry that leaves one out does not compile, and a `Text` is built from a string literal
// by a consteval constructor that rejects the empty string. A method therefore cannot reach the
// registry without its description, kind or reference.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <utility>

#include "core/integrator.hpp"

namespace stiffbench {

// Non-empty text known at compile time: a string literal, or literals joined by cite().
class Text {
 public:
  // NOLINTNEXTLINE(google-explicit-constructor): entries are written as string literals.
  consteval Text(const char* s) : parts_{std::string_view(s), {}, {}} {
    if (parts_[0].empty()) throw "a method's description, kind and reference must not be empty";
  }
  std::string str() const {
    std::string s;
    for (const std::string_view p : parts_) s += p;
    return s;
  }
  friend consteval Text cite(Text book, Text where);

 private:
  consteval Text(std::string_view a, std::string_view sep, std::string_view b)
      : parts_{a, sep, b} {}
  std::array<std::string_view, 3> parts_;
};

// "book, where": a textbook cited by section.
consteval Text cite(Text book, Text where) { return Text(book.parts_[0], ", ", where.parts_[0]); }

// A field that must be given: no default constructor.
template <class T>
struct Required {
  // NOLINTNEXTLINE(google-explicit-constructor): entries are written as plain values.
  Required(T v) : value(std::move(v)) {}
  T value;
  const T& operator*() const { return value; }
  const T* operator->() const { return &value; }
};

// Which runs the method supports: fixed steps only (`--h`), or also adaptive ones (rtol/atol:
// the coefficients carry an embedded error estimate). Registration chooses the parameters and
// the constructor from it; tests/test_method_notes.cpp checks it against the integrator.
enum class StepModes { fixed, fixed_and_adaptive };

// What `list integrators` and `describe NAME` print about a method.
struct MethodText {
  Text description;
  Text kind;       // the method class within its family, e.g. "embedded RK pair"
  Text reference;  // authors, venue, year (and section where it is a textbook)
};

// One method of a family: Coefficients carries the name (ButcherTableau, RosenbrockTableau,
// KickDriftScheme, CompositionMethod).
template <class Coefficients>
struct MethodEntry {
  Required<Coefficients> coefficients;
  MethodText text;
  Required<StepModes> steps;

  const std::string& name() const {
    if constexpr (requires { coefficients->name(); })
      return coefficients->name();
    else
      return coefficients->name;
  }
  bool adaptive() const { return *steps == StepModes::fixed_and_adaptive; }
};

// `info` with the entry's kind and reference (the description is passed to the integrator's
// constructor, which builds the rest of the MethodInfo from the coefficients).
inline MethodInfo with_text(MethodInfo info, const MethodText& text) {
  info.kind = text.kind.str();
  info.reference = text.reference.str();
  return info;
}

// The textbooks cited by section.
inline constexpr const char* kHairerNorsettWanner =
    "E. Hairer, S. P. Norsett & G. Wanner, Solving Ordinary Differential Equations I, "
    "2nd ed., Springer 1993";
inline constexpr const char* kHairerWanner =
    "E. Hairer & G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer 1996";
inline constexpr const char* kGeometricIntegration =
    "E. Hairer, C. Lubich & G. Wanner, Geometric Numerical Integration, 2nd ed., Springer 2006";

}  // namespace stiffbench
