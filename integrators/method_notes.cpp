#include "integrators/method_notes.hpp"

#include "integrators/method_entry.hpp"

namespace stiffbench {

namespace {

// Textbooks cited by section (integrators/method_entry.hpp).
constexpr const char* kHW = kHairerWanner;
constexpr const char* kGNI = kGeometricIntegration;
constexpr const char* kSundials =
    "A. C. Hindmarsh et al., SUNDIALS: suite of nonlinear and differential/algebraic equation "
    "solvers, ACM Trans. Math. Softw. 31 (2005) 363-396";
constexpr const char* kArkode =
    "D. R. Reynolds, D. J. Gardner, C. S. Woodward & R. Chinomona, ARKODE: a flexible IVP "
    "solver infrastructure for one-step methods, ACM Trans. Math. Softw. 49 (2023) 19";
constexpr const char* kGsl = "M. Galassi et al., GNU Scientific Library Reference Manual, odeiv2";

std::string cite_section(const char* book, const std::string& where) {
  return std::string(book) + ", " + where;
}

}  // namespace

const std::map<std::string, MethodNote>& method_notes() {
  static const std::map<std::string, MethodNote> table = {
      // The coefficient-defined methods (explicit RK, DIRK, Rosenbrock, kick/drift and
      // composition methods) carry their kind and reference in their own table entries
      // (integrators/method_entry.hpp); these are the methods implemented as classes.
      // Splitting methods.
      {"verlet", {"two-step (Stormer-Verlet)", "L. Verlet, Phys. Rev. 159 (1967) 98-103"}},
      {"leapfrog",
       {"splitting (staggered)",
        "R. W. Hockney & J. W. Eastwood, Computer Simulation Using Particles, McGraw-Hill 1981"}},
      {"rattle",
       {"constrained splitting (RATTLE)",
        "H. C. Andersen, Rattle: a \"velocity\" version of the Shake algorithm for molecular "
        "dynamics calculations, J. Comput. Phys. 52 (1983) 24-34; " +
            cite_section(kGNI, "Sect. VII.1")}},
      // Implicit one-step and multistep methods.
      {"bdf2", {"multistep (BDF)", cite_section(kHW, "Sect. V.1 (Curtiss & Hirschfelder 1952)")}},
      {"semi_implicit_euler", {"linearly implicit", cite_section(kHW, "Sect. IV.9")}},
      {"radau5", {"Radau IIA collocation", cite_section(kHW, "Sect. IV.8 (RADAU5)")}},
      {"gauss4",
       {"Gauss collocation (2 stages)",
        "J. C. Butcher, Implicit Runge-Kutta processes, Math. Comp. 18 (1964) 50-64; " +
            cite_section(kGNI, "Sect. II.1.3, VI.4")}},
      {"gauss6",
       {"Gauss collocation (3 stages)",
        "J. C. Butcher, Implicit Runge-Kutta processes, Math. Comp. 18 (1964) 50-64; " +
            cite_section(kGNI, "Sect. II.1.3, VI.4")}},
      {"baraff_witkin",
       {"linearly implicit (velocity form)",
        "D. Baraff & A. Witkin, Large steps in cloth simulation, SIGGRAPH 1998, 43-54"}},
      // Graphics solvers for stiff springs.
      {"xpbd",
       {"position-based (compliant constraints)",
        "M. Macklin, M. Mueller & N. Chentanez, XPBD: position-based simulation of compliant "
        "constrained dynamics, Motion in Games (MIG) 2016, 49-54; substeps: M. Macklin et al., "
        "Small steps in physics simulation, SCA 2019"}},
      {"projective_dynamics",
       {"local/global backward Euler",
        "T. Liu, A. W. Bargteil, J. F. O'Brien & L. Kavan, Fast simulation of mass-spring "
        "systems, ACM Trans. Graph. 32(6) (SIGGRAPH Asia 2013) 214"}},
      {"stable_fluids",
       {"operator splitting (semi-Lagrangian)", "J. Stam, Stable fluids, SIGGRAPH 1999, 121-128"}},
      // Library references.
      {"cvode_bdf", {"library: CVODE", kSundials}},
      {"cvode_adams", {"library: CVODE", kSundials}},
      {"arkode_erk", {"library: ARKODE", kArkode}},
      {"arkode_dirk", {"library: ARKODE", kArkode}},
      {"arkode_imex", {"library: ARKODE", kArkode}},
      {"gsl_rk4", {"library: GSL", kGsl}},
      {"gsl_rkf45", {"library: GSL", std::string(kGsl) + "; Fehlberg 1969"}},
      {"gsl_rkck", {"library: GSL", std::string(kGsl) + "; Cash & Karp 1990"}},
      {"gsl_rk8pd",
       {"library: GSL",
        std::string(kGsl) +
            "; P. J. Prince & J. R. Dormand, J. Comput. Appl. Math. 7 (1981) 67-75"}},
      {"gsl_rk2imp", {"library: GSL (Gauss collocation)", kGsl}},
      {"gsl_rk4imp", {"library: GSL (Gauss collocation)", kGsl}},
      {"gsl_bsimp",
       {"library: GSL",
        std::string(kGsl) + "; G. Bader & P. Deuflhard, Numer. Math. 41 (1983) 373-398"}},
      {"gsl_msadams", {"library: GSL", kGsl}},
      {"gsl_msbdf", {"library: GSL", kGsl}},
  };
  return table;
}

const MethodNote* method_note(const std::string& name) {
  const auto it = method_notes().find(name);
  return it == method_notes().end() ? nullptr : &it->second;
}

void annotate_built_in_integrators(IntegratorRegistry& reg) {
  for (const std::string& name : reg.names()) {
    const MethodNote* note = method_note(name);
    if (!note) continue;
    IntegratorRegistry::Entry e = *reg.find(name);
    if (!e.info.reference.empty()) continue;
    e.info.kind = note->kind;
    e.info.reference = note->reference;
    reg.add_or_replace(std::move(e));
  }
}

}  // namespace stiffbench
