#include "integrators/reference/sundials/tables.hpp"

namespace stiffbench::sundials_detail {

int erk_order(const std::string& name) {
  ARKodeButcherTable t = ARKodeButcherTable_LoadERKByName(name.c_str());
  require_input(t != nullptr,
                "parameter 'explicit_table': unknown ARKODE explicit table '" + name + "'");
  const int q = t->q;
  ARKodeButcherTable_Free(t);
  return q;
}
int dirk_order(const std::string& name) {
  ARKodeButcherTable t = ARKodeButcherTable_LoadDIRKByName(name.c_str());
  require_input(t != nullptr,
                "parameter 'implicit_table': unknown ARKODE implicit table '" + name + "'");
  const int q = t->q;
  ARKodeButcherTable_Free(t);
  return q;
}

void read_ark_pair(const Params& p, Settings& s) {
  const std::string key = p.text("tables");
  s.explicit_table = p.text("explicit_table");
  s.implicit_table = p.text("implicit_table");
  if (key == "named") {
    require_input(!s.explicit_table.empty() && !s.implicit_table.empty(),
                  "tables=named needs both parameters 'explicit_table' and 'implicit_table'");
    return;
  }
  require_input(s.explicit_table.empty() && s.implicit_table.empty(),
                "parameters 'explicit_table' and 'implicit_table' need tables=named (tables=" +
                    key + " chooses both tables)");
  for (const ArkPair& a : kArkPairs)
    if (key == a.key) {
      s.erk_num = a.erk;
      s.dirk_num = a.dirk;
      s.explicit_table = a.erk_name;
      s.implicit_table = a.dirk_name;
      return;
    }
  throw BadInput("parameter 'tables': unknown ARK pair '" + key + "'");
}

}  // namespace stiffbench::sundials_detail
