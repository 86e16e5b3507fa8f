#include "integrators/method_notes.hpp"

namespace stiffbench {

namespace {

// Textbooks cited by section.
constexpr const char* kHNW =
    "E. Hairer, S. P. Norsett & G. Wanner, Solving Ordinary Differential Equations I, "
    "2nd ed., Springer 1993";
constexpr const char* kHW =
    "E. Hairer & G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer 1996";
constexpr const char* kGNI =
    "E. Hairer, C. Lubich & G. Wanner, Geometric Numerical Integration, 2nd ed., Springer 2006";
constexpr const char* kKutta = "W. Kutta, Z. Math. Phys. 46 (1901) 435-453";
constexpr const char* kSundials =
    "A. C. Hindmarsh et al., SUNDIALS: suite of nonlinear and differential/algebraic equation "
    "solvers, ACM Trans. Math. Softw. 31 (2005) 363-396";
constexpr const char* kArkode =
    "D. R. Reynolds, D. J. Gardner, C. S. Woodward & R. Chinomona, ARKODE: a flexible IVP "
    "solver infrastructure for one-step methods, ACM Trans. Math. Softw. 49 (2023) 19";
constexpr const char* kGsl = "M. Galassi et al., GNU Scientific Library Reference Manual, odeiv2";

std::string cite(const char* book, const std::string& where) {
  return std::string(book) + ", " + where;
}

}  // namespace

const std::map<std::string, MethodNote>& method_notes() {
  static const std::map<std::string, MethodNote> table = {
      // Explicit Runge-Kutta (Butcher tableaux).
      {"euler", {"explicit RK", cite(kHNW, "Sect. I.7 (Euler 1768)")}},
      {"heun", {"explicit RK", "K. Heun, Z. Math. Phys. 45 (1900) 23-38"}},
      {"midpoint", {"explicit RK", "C. Runge, Math. Ann. 46 (1895) 167-178"}},
      {"ralston", {"explicit RK", "A. Ralston, Math. Comp. 16 (1962) 431-437"}},
      {"kutta3", {"explicit RK", kKutta}},
      {"ssprk3", {"explicit RK (SSP)", "C.-W. Shu & S. Osher, J. Comput. Phys. 77 (1988) 439-471"}},
      {"rk4", {"explicit RK", kKutta}},
      {"rk38", {"explicit RK", kKutta}},
      // Embedded explicit pairs.
      {"bs3",
       {"embedded RK pair", "P. Bogacki & L. F. Shampine, Appl. Math. Lett. 2 (1989) 321-325"}},
      {"dopri5",
       {"embedded RK pair", "J. R. Dormand & P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19-26"}},
      {"cash_karp",
       {"embedded RK pair", "J. R. Cash & A. H. Karp, ACM Trans. Math. Softw. 16 (1990) 201-222"}},
      {"rkf45", {"embedded RK pair", "E. Fehlberg, NASA Technical Report R-315 (1969)"}},
      // Splitting and composition methods.
      {"symplectic_euler", {"splitting", cite(kGNI, "Sect. I.1.2")}},
      {"symplectic_euler_x", {"splitting", cite(kGNI, "Sect. I.1.2")}},
      {"velocity_verlet",
       {"splitting",
        "W. C. Swope, H. C. Andersen, P. H. Berens & K. R. Wilson, J. Chem. Phys. 76 (1982) "
        "637-649"}},
      {"verlet", {"two-step (Stormer-Verlet)", "L. Verlet, Phys. Rev. 159 (1967) 98-103"}},
      {"leapfrog",
       {"splitting (staggered)",
        "R. W. Hockney & J. W. Eastwood, Computer Simulation Using Particles, McGraw-Hill 1981"}},
      {"yoshida4",
       {"Verlet composition",
        "E. Forest & R. D. Ruth, Physica D 43 (1990) 105-117; H. Yoshida, Phys. Lett. A 150 "
        "(1990) 262-268"}},
      {"yoshida6",
       {"Verlet composition", "H. Yoshida, Phys. Lett. A 150 (1990) 262-268 (solution A)"}},
      {"blanes_moan",
       {"optimised splitting",
        "S. Blanes & P. C. Moan, J. Comput. Appl. Math. 142 (2002) 313-330 (SRKN_6^b)"}},
      {"rattle",
       {"constrained splitting (RATTLE)",
        "H. C. Andersen, Rattle: a \"velocity\" version of the Shake algorithm for molecular "
        "dynamics calculations, J. Comput. Phys. 52 (1983) 24-34; " +
            cite(kGNI, "Sect. VII.1")}},
      // Implicit one-step and multistep methods.
      {"backward_euler", {"implicit RK", cite(kHW, "Sect. IV.3")}},
      {"implicit_midpoint", {"Gauss collocation (1 stage)", cite(kGNI, "Sect. II.1")}},
      {"trapezoidal",
       {"implicit RK", "J. Crank & P. Nicolson, Proc. Cambridge Philos. Soc. 43 (1947) 50-67"}},
      {"sdirk2", {"SDIRK", "R. Alexander, SIAM J. Numer. Anal. 14 (1977) 1006-1021"}},
      {"sdirk3", {"SDIRK", "R. Alexander, SIAM J. Numer. Anal. 14 (1977) 1006-1021"}},
      {"bdf2", {"multistep (BDF)", cite(kHW, "Sect. V.1 (Curtiss & Hirschfelder 1952)")}},
      {"semi_implicit_euler", {"linearly implicit", cite(kHW, "Sect. IV.9")}},
      {"rosenbrock2",
       {"Rosenbrock",
        "J. G. Verwer, E. J. Spee, J. G. Blom & W. Hundsdorfer, SIAM J. Sci. Comput. 20 (1999) "
        "1456-1480"}},
      {"ros3p",
       {"Rosenbrock (embedded pair)",
        "J. Lang & J. G. Verwer, ROS3P - an accurate third-order Rosenbrock solver designed for "
        "parabolic problems, BIT Numer. Math. 41 (2001) 731-738"}},
      {"rodas4", {"Rosenbrock (embedded pair)", cite(kHW, "Sect. VI.4 (RODAS)")}},
      {"radau5", {"Radau IIA collocation", cite(kHW, "Sect. IV.8 (RADAU5)")}},
      {"trbdf2",
       {"ESDIRK (embedded pair)",
        "R. E. Bank, W. M. Coughran, W. Fichtner, E. H. Grosse, D. J. Rose & R. K. Smith, "
        "Transient simulation of silicon devices and circuits, IEEE Trans. Computer-Aided Design "
        "4 (1985) 436-451; as an ESDIRK pair: M. E. Hosea & L. F. Shampine, Analysis and "
        "implementation of TR-BDF2, Appl. Numer. Math. 20 (1996) 21-37"}},
      {"esdirk43",
       {"ESDIRK (embedded pair)",
        "C. A. Kennedy & M. H. Carpenter, Additive Runge-Kutta schemes for "
        "convection-diffusion-reaction equations, Appl. Numer. Math. 44 (2003) 139-181 "
        "(ESDIRK4(3)6L[2]SA, the implicit part of ARK4(3)6L[2]SA)"}},
      {"gauss4",
       {"Gauss collocation (2 stages)",
        "J. C. Butcher, Implicit Runge-Kutta processes, Math. Comp. 18 (1964) 50-64; " +
            cite(kGNI, "Sect. II.1.3, VI.4")}},
      {"gauss6",
       {"Gauss collocation (3 stages)",
        "J. C. Butcher, Implicit Runge-Kutta processes, Math. Comp. 18 (1964) 50-64; " +
            cite(kGNI, "Sect. II.1.3, VI.4")}},
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
