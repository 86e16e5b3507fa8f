// The text of a method implemented as a class: its description, kind and literature reference.
//
// Coefficient-defined methods (explicit RK, DIRK/ESDIRK, fully implicit RK, Rosenbrock,
// kick/drift and Verlet compositions) are files, methods/*.toml, compiled into the library
// (integrators/embedded_methods.hpp) and read by built_in_methods() (integrators/method_file.hpp):
// each file holds the coefficients, description, kind, reference and claims side by side, and
// registration (integrators/register.cpp) and the family lookups (explicit_tableaux(),
// implicit_tableau(name), rodas4_tableau(), ...) are derived from them.
//
// Methods implemented as classes (verlet, leapfrog, rattle, bdf2, semi_implicit_euler,
// baraff_witkin, xpbd, projective_dynamics, stable_fluids, the library references): a MethodText
// sits next to the constructor (or the registration) that builds the method's MethodInfo with
// method_info(), which takes it as an argument. add_built_in_integrator() refuses, naming the
// method, a registration without a description, kind or reference.
//
// Every field of a MethodText is required at compile time: `Text` has no default constructor,
// so a MethodText that leaves one out does not compile, and a `Text` is built from a string
// literal by a consteval constructor that rejects the empty string.
#pragma once

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "core/integrator.hpp"
#include "core/registry_types.hpp"

namespace stiffbench {

// Non-empty text known at compile time: a string literal, or literals joined by cite() and
// join_text().
class Text {
 public:
  // NOLINTNEXTLINE(google-explicit-constructor): entries are written as string literals.
  consteval Text(const char* s) : parts_{std::string_view(s)}, size_(1) {
    if (parts_[0].empty()) throw "a method's description, kind and reference must not be empty";
  }
  std::string str() const {
    std::string s;
    for (std::size_t i = 0; i < size_; ++i) s += parts_[i];
    return s;
  }
  friend consteval Text join_text(Text a, std::string_view sep, Text b);

 private:
  static constexpr std::size_t kMaxParts = 8;
  std::array<std::string_view, kMaxParts> parts_;
  std::size_t size_;
};

// "a" + sep + "b", e.g. a paper and a textbook section: join_text(paper, "; ", cite(book, where)).
consteval Text join_text(Text a, std::string_view sep, Text b) {
  if (a.size_ + 1 + b.size_ > Text::kMaxParts) throw "a method's text joins too many parts";
  Text t = a;
  t.parts_[t.size_++] = sep;
  for (std::size_t i = 0; i < b.size_; ++i) t.parts_[t.size_++] = b.parts_[i];
  return t;
}

// "book, where": a textbook cited by section.
consteval Text cite(Text book, Text where) { return join_text(book, ", ", where); }

// What `list integrators` and `describe NAME` print about a method.
struct MethodText {
  Text description;
  Text kind;       // the method class within its family, e.g. "multistep (BDF)"
  Text reference;  // authors, venue, year (and section where it is a textbook)
};

// The MethodInfo of a method implemented as a class, built next to its constructor (or its
// registration): every field is an argument, so a class without its text does not compile.
inline MethodInfo method_info(std::string name, Family family, int order, int stages,
                              Requirements needs, const MethodText& text) {
  MethodInfo info{std::move(name), family, order, stages, needs, text.description.str()};
  info.kind = text.kind.str();
  info.reference = text.reference.str();
  return info;
}

// Registers a built-in integrator; a logic_error naming the method when its MethodInfo has no
// description, kind or reference (it was built without its MethodText).
inline void add_built_in_integrator(IntegratorRegistry& reg, IntegratorRegistry::Entry entry) {
  const MethodInfo& i = entry.info;
  for (const auto& [field, value] :
       {std::pair<const char*, const std::string*>{"description", &i.description},
        {"kind", &i.kind},
        {"reference", &i.reference}})
    if (value->empty())
      throw std::logic_error("integrator '" + i.name + "' is registered without a " + field +
                             " (build its MethodInfo with method_info(), "
                             "integrators/method_entry.hpp)");
  reg.add(std::move(entry));
}

// The textbooks cited by section.
inline constexpr const char* kHairerWanner =
    "E. Hairer & G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer 1996";
inline constexpr const char* kGeometricIntegration =
    "E. Hairer, C. Lubich & G. Wanner, Geometric Numerical Integration, 2nd ed., Springer 2006";

}  // namespace stiffbench
