// The ARKODE tables the registry entries name: the order of a Butcher table by name, the ARK
// pairs of arkode_imex and the slow coupling tables of arkode_mri. Internal to
// integrators/reference/sundials/.
#pragma once

#include <arkode/arkode_arkstep.h>  // first: it includes <stdio.h>, which arkode_butcher.h needs
#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>
#include <arkode/arkode_mristep.h>

#include <string>

#include "core/params.hpp"
#include "integrators/reference/sundials/adapter.hpp"

namespace stiffbench::sundials_detail {

// Order of an ARKODE table by name (BadInput for an unknown name).
int erk_order(const std::string& name);
int dirk_order(const std::string& name);

// The ARK pairs of ARKODE 5.4 (SUNDIALS 6.4) by the `tables` key of arkode_imex: explicit and
// implicit tables of C. A. Kennedy & M. H. Carpenter, Additive Runge-Kutta schemes for
// convection-diffusion-reaction equations, Appl. Numer. Math. 44 (2003) 139-181 (ark324l2sa,
// ark436l2sa, ark548l2sa) and Higher-order additive Runge-Kutta schemes for ordinary
// differential equations, Appl. Numer. Math. 136 (2019) 183-205 (ark437l2sa, ark548l2sab).
struct ArkPair {
  const char* key;
  ARKODE_ERKTableID erk;
  ARKODE_DIRKTableID dirk;
  const char* erk_name;
  const char* dirk_name;
};
inline constexpr ArkPair kArkPairs[] = {
    {"ark324l2sa", ARKODE_ARK324L2SA_ERK_4_2_3, ARKODE_ARK324L2SA_DIRK_4_2_3,
     "ARKODE_ARK324L2SA_ERK_4_2_3", "ARKODE_ARK324L2SA_DIRK_4_2_3"},
    {"ark436l2sa", ARKODE_ARK436L2SA_ERK_6_3_4, ARKODE_ARK436L2SA_DIRK_6_3_4,
     "ARKODE_ARK436L2SA_ERK_6_3_4", "ARKODE_ARK436L2SA_DIRK_6_3_4"},
    {"ark437l2sa", ARKODE_ARK437L2SA_ERK_7_3_4, ARKODE_ARK437L2SA_DIRK_7_3_4,
     "ARKODE_ARK437L2SA_ERK_7_3_4", "ARKODE_ARK437L2SA_DIRK_7_3_4"},
    {"ark548l2sa", ARKODE_ARK548L2SA_ERK_8_4_5, ARKODE_ARK548L2SA_DIRK_8_4_5,
     "ARKODE_ARK548L2SA_ERK_8_4_5", "ARKODE_ARK548L2SA_DIRK_8_4_5"},
    {"ark548l2sab", ARKODE_ARK548L2SAb_ERK_8_4_5, ARKODE_ARK548L2SAb_DIRK_8_4_5,
     "ARKODE_ARK548L2SAb_ERK_8_4_5", "ARKODE_ARK548L2SAb_DIRK_8_4_5"},
};

// arkode_imex's `tables`: a pair by number, or (named) the two tables by name.
void read_ark_pair(const Params& p, Settings& s);

// arkode_mri's slow coupling tables: explicit slow part (f_E) only.
struct MriTable {
  const char* key;
  ARKODE_MRITableID id;
  int order;
};
inline constexpr MriTable kMriTables[] = {
    {"mri_gark_erk33a", ARKODE_MRI_GARK_ERK33a, 3},
    {"mis_kw3", ARKODE_MIS_KW3, 3},
    {"mri_gark_erk45a", ARKODE_MRI_GARK_ERK45a, 4},
};

}  // namespace stiffbench::sundials_detail
