#include "experiments/studies/analyze.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <iostream>
#include <limits>
#include <memory>
#include <ostream>
#include <set>
#include <sstream>

#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/option_table.hpp"
#include "experiments/support/coefficients.hpp"

namespace stiffbench {

namespace {

constexpr int kMaxOrder = 8;  // order conditions are analysed up to this order
constexpr const char* kNotCoefficientDefined = "not coefficient-defined";

// What a method without coefficients has: its stability data's limits (BDF2's sampled, the
// others' exact) and, with a rational R = P/Q, its dissipation and dispersion.
void stability_figures(AnalyzedMethod& m, const Integrator& integ, const MethodInfo& info,
                       int points) {
  m.analysis.kind = kNotCoefficientDefined;
  m.analysis.claimed_order = info.order;
  m.analysis.stages = info.stages;
  m.analysis.stage_order = -1;
  const std::optional<LinearStability> s = integ.linear_stability();
  if (!s) {
    m.analysis.notes.push_back(info.family == Family::reference
                                   ? "a library integrator: its coefficients are not known to "
                                     "stiffbench"
                                   : "no coefficients and no linear stability data");
    return;
  }
  m.stability_kind = s->kind;
  if (s->amplification) {
    m.real_axis = real_axis_limit(*s);
    m.imaginary_axis = imaginary_axis_limit(*s);
    const std::optional<bool> exact = a_stable_exact(*s);
    m.a_stable = exact ? *exact : a_stable_on_samples(*s);
  }
  m.oscillator = oscillator_limit(*s);
  m.limits_exact = m.oscillator->exact && (!m.real_axis || m.real_axis->exact) &&
                   (!m.imaginary_axis || m.imaginary_axis->exact);
  m.analysis.notes.push_back(s->kind + ": no coefficients to analyse; the figures are from its " +
                             "linear stability data" +
                             (m.limits_exact ? "" : " (limits from a sampled search)"));
  if (s->rational) m.dispersion = dissipation_dispersion(*s->rational, points);
}

std::vector<std::string> chosen(const AnalyzeSpec& spec) {
  return spec.integrators.empty() ? analyze_integrators() : spec.integrators;
}

}  // namespace

std::vector<std::string> analyze_integrators() {
  std::vector<std::string> out;
  for (const auto& name : integrator_registry().names()) {
    const auto integ = integrator_registry().create(name, Params{});
    if (coefficient_analysis(*integ) || integ->linear_stability()) out.push_back(name);
  }
  return out;
}

namespace {

// The options of `stiffbench analyze`, bound to AnalyzeSpec's fields (defaults: its initialisers).
const OptionTable<AnalyzeSpec>& analyze_options() {
  static const OptionTable<AnalyzeSpec> table = OptionTable<AnalyzeSpec>().add(
      "nu_points", &AnalyzeSpec::points,
      "samples of nu in [1e-2, 10] (log-spaced) for the dissipation and dispersion curves",
      Bounds::in(2, 10000));
  return table;
}

}  // namespace

void AnalyzeSpec::validate() const {
  std::set<std::string> seen;
  for (const auto& name : integrators)
    require_input(seen.insert(name).second, "--integrators: '" + name + "' is listed twice");
  analyze_options().check(*this);
}

nlohmann::json AnalyzeSpec::to_json() const {
  nlohmann::json j = {{"integrators", chosen(*this)}};
  analyze_options().to_json(*this, j);
  return j;
}

namespace {

// A row's stability function's dissipation and dispersion.
void add_dispersion(AnalyzedMethod& m, int points) {
  if (!m.analysis.p.empty())
    m.dispersion = dissipation_dispersion({m.analysis.p, m.analysis.q}, points);
}

// The analysis of an integrator object registered as `info`: one row, and for an additive pair
// two more, each table alone (NAME:explicit, NAME:implicit).
std::vector<AnalyzedMethod> analyze_object(const MethodInfo& info, const Integrator& integ,
                                           int points) {
  std::vector<AnalyzedMethod> rows(1);
  AnalyzedMethod& m = rows[0];
  m.integrator = info.name;
  m.family = to_string(info.family);
  if (auto a = coefficient_analysis(integ)) {
    m.coefficient_defined = true;
    m.analysis = std::move(*a);
    if (m.analysis.claimed_order == 0) m.analysis.claimed_order = info.order;
    add_dispersion(m, points);
  } else {
    stability_figures(m, integ, info, points);
  }
  m.analysis.name = info.name;
  if (const AdditiveTableau* t = integ.additive_tableau()) {
    const int order = m.analysis.claimed_order;
    for (const auto& [table, part] :
         {std::pair{&t->explicit_table, "explicit"}, std::pair{&t->implicit_table, "implicit"}}) {
      AnalyzedMethod r;
      r.integrator = additive_part_name(info.name, part);
      r.family = rows[0].family;
      r.coefficient_defined = true;
      r.analysis = analyze_runge_kutta(*table, tableau_kind(*table));
      r.analysis.name = r.integrator;
      // The tables carry the pair's order: each alone should have at least that order.
      r.analysis.claimed_order = order;
      r.analysis.notes.push_back(std::string("the ") + part + " table of " + info.name +
                                 " alone (its weights b, its own order conditions)");
      add_dispersion(r, points);
      rows.push_back(std::move(r));
    }
  }
  return rows;
}

}  // namespace

AnalyzedMethod analyze_integrator(const StudyInputs& in, const std::string& label, int points) {
  return analyze_object(in.integrator_entry(label).info, *in.create_integrator(label, Params{}),
                        points)
      .front();
}

AnalyzeResult run_analyze(const StudyInputs& in, const AnalyzeSpec& given, std::ostream*) {
  const AnalyzeSpec spec = with_inputs(given, in);
  spec.validate();
  const std::vector<std::string> names = chosen(spec);
  // Created before the parallel loop: a user's factories need not be thread-safe.
  std::vector<MethodInfo> infos;
  std::vector<std::unique_ptr<Integrator>> integs;
  for (const auto& name : names) {
    infos.push_back(in.integrator_entry(name).info);
    integs.push_back(in.create_integrator(name, Params{}));
  }
  std::vector<std::vector<AnalyzedMethod>> rows(names.size());
  std::vector<std::exception_ptr> failed(names.size());
  // Methods are independent; each reads only its own coefficients.
#pragma omp parallel for schedule(dynamic)
  for (std::size_t k = 0; k < names.size(); ++k) {
    try {
      const RowClock clock;  // each method is a row for --max-wall
      rows[k] = analyze_object(infos[k], *integs[k], spec.points);
    } catch (const WallLimitExceeded& e) {
      AnalyzedMethod m;
      m.integrator = infos[k].name;
      m.family = to_string(infos[k].family);
      m.stopped = true;
      count_row_timeout();
      m.analysis.name = infos[k].name;
      m.analysis.claimed_order = infos[k].order;
      m.analysis.notes.push_back(std::string("stopped: ") + e.what());
      rows[k] = {std::move(m)};
    } catch (...) {
      failed[k] = std::current_exception();
    }
  }
  for (const auto& e : failed)
    if (e) std::rethrow_exception(e);
  AnalyzeResult res;
  for (auto& r : rows)
    for (auto& m : r) {
      if (m.stopped)
        std::cerr << "warning: analysis of " << m.integrator
                  << " stopped: " << m.analysis.notes.back() << "\n";
      res.methods.push_back(std::move(m));
    }
  return res;
}

// ---- tables -------------------------------------------------------------------------------------

namespace {

std::string yes_no(bool b) { return b ? "yes" : "no"; }

// A limit r >= 0 at full precision, `unbounded` when stable along the whole ray.
std::string limit_text(double r, bool unbounded) {
  return unbounded || std::isinf(r) ? "unbounded" : format_full(r);
}
std::string limit_text(const std::optional<AxisLimit>& a) {
  return a ? limit_text(a->limit, a->unbounded) : "";
}

std::string polynomial_text(const Polynomial& p, const std::string& sep = ";") {
  std::string s;
  for (std::size_t k = 0; k < p.size(); ++k) s += (k ? sep : "") + format_full(p[k]);
  return s;
}

std::string order_text(int order) { return order > 0 ? std::to_string(order) : "none"; }

// The SSP coefficient with its precision: a positive finite value comes from a bisection
// (kSspRelativeTolerance); 0 (a negative entry of K, or a radius below 1e-12) is printed as is.
std::string ssp_text(double ssp) {
  if (ssp < 0) return "-";
  if (ssp == 0 || std::isinf(ssp)) return limit_text(ssp, false);
  return format_full(ssp) + " (bisection, relative +-" + format_full(kSspRelativeTolerance) + ")";
}

// A Rosenbrock method's W-order (">= 6" at the last order analysed, the claim when it differs);
// "-" for other kinds.
std::string w_order_text(const MethodAnalysis& a) {
  if (a.w_order < 0) return "-";
  std::string t = (a.w_order >= kMaxWOrder ? ">= " : "") + std::to_string(a.w_order);
  if (a.claimed_w_order && a.claimed_w_order != a.w_order)
    t += " (claimed " + std::to_string(a.claimed_w_order) + ")";
  return t;
}

std::string notes_text(const AnalyzedMethod& m) { return join(m.analysis.notes, "; "); }

bool has_stability_function(const AnalyzedMethod& m) {
  return m.coefficient_defined && !m.analysis.p.empty();
}

// Additive pairs have no error coefficients (analyze_additive).
bool has_error_norms(const MethodAnalysis& a) { return a.kind != "imex_ark"; }

// The highest order whose conditions were analysed: the achieved order reads ">= p" there.
int analysed_to(const MethodAnalysis& a) {
  return a.kind == "imex_ark" ? kMaxAdditiveOrder : kMaxOrder;
}

// The error norms of order p+1 and p+2 exist for p + 1 <= 8 and p + 2 <= 8.
std::vector<std::string> error_norms(const MethodAnalysis& a) {
  if (!has_error_norms(a)) return {"", "", "", ""};
  const bool next = a.order + 1 <= kMaxOrder, after = a.order + 2 <= kMaxOrder;
  return {next ? format_full(a.error_norm_2) : "", next ? format_full(a.error_norm_max) : "",
          after ? format_full(a.error_norm_2_next) : "",
          after ? format_full(a.error_norm_max_next) : ""};
}

// The row of a coefficient-defined method.
std::vector<std::string> coefficient_row(const AnalyzedMethod& m) {
  const MethodAnalysis& a = m.analysis;
  const bool rk = a.stage_order >= 0;
  std::vector<std::string> row = {m.integrator,
                                  a.kind,
                                  std::to_string(a.stages),
                                  a.claimed_order ? std::to_string(a.claimed_order) : "",
                                  std::to_string(a.order),
                                  rk ? std::to_string(a.stage_order) : "",
                                  a.embedded_order ? std::to_string(a.embedded_order) : "",
                                  a.w_order >= 0 ? std::to_string(a.w_order) : "",
                                  a.embedded_w_order > 0 ? std::to_string(a.embedded_w_order) : "",
                                  a.claimed_w_order ? std::to_string(a.claimed_w_order) : "",
                                  yes_no(a.fsal),
                                  yes_no(a.stiffly_accurate)};
  for (int k = 0; k < kMaxOrder; ++k)
    row.push_back(k < static_cast<int>(a.residual_by_order.size())
                      ? format_full(a.residual_by_order[static_cast<std::size_t>(k)])
                      : "");
  for (auto& e : error_norms(a)) row.push_back(std::move(e));
  row.push_back(format_full(a.max_coefficient));
  const bool r = has_stability_function(m);
  row.push_back(polynomial_text(a.p));
  row.push_back(polynomial_text(a.q));
  row.push_back(r ? format_full(a.r_infinity) : "");
  row.push_back(r ? yes_no(a.a_stable) : "");
  row.push_back(r ? yes_no(a.l_stable) : "");
  row.push_back(r ? limit_text(a.real_axis_limit, a.real_axis_unbounded) : "");
  row.push_back(r ? limit_text(a.imag_axis_limit, a.imag_axis_unbounded) : "");
  row.push_back(r ? format_full(a.internal_amplification_real) : "");
  row.push_back(r ? format_full(a.internal_amplification_imag) : "");
  row.push_back(a.ssp_coefficient >= 0 ? format_full(a.ssp_coefficient) : "");
  row.push_back(a.ssp_coefficient > 0 && std::isfinite(a.ssp_coefficient)
                    ? format_full(kSspRelativeTolerance)
                    : "");
  row.push_back(r ? order_text(a.dissipation_order) : "");
  row.push_back(r ? order_text(a.dispersion_order) : "");
  row.push_back(a.kind == "splitting" ? limit_text(a.oscillator_limit, false) : "");
  const auto& e = a.embedded_stability;
  row.push_back(e ? polynomial_text(e->p) : "");
  row.push_back(e ? polynomial_text(e->q) : "");
  row.push_back(e ? format_full(e->r_infinity) : "");
  row.push_back(e ? yes_no(e->a_stable) : "");
  row.push_back(e ? yes_no(e->l_stable) : "");
  row.push_back(e ? limit_text(e->real_axis_limit, e->real_axis_unbounded) : "");
  row.push_back(e ? limit_text(e->imag_axis_limit, e->imag_axis_unbounded) : "");
  row.push_back(notes_text(m));
  return row;
}

// The row of a method without coefficients: its stability figures only.
std::vector<std::string> stability_row(const AnalyzedMethod& m,
                                       const std::vector<std::string>& columns) {
  std::vector<std::string> row(columns.size());
  auto set = [&](const std::string& column, std::string value) {
    row[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), column) -
                                 columns.begin())] = std::move(value);
  };
  set("integrator", m.integrator);
  set("kind", m.stopped ? "stopped" : kNotCoefficientDefined);
  set("stages", m.analysis.stages ? std::to_string(m.analysis.stages) : "");
  set("claimed_order", m.analysis.claimed_order ? std::to_string(m.analysis.claimed_order) : "");
  set("a_stable", m.a_stable ? yes_no(*m.a_stable) : "");
  set("real_axis_limit", limit_text(m.real_axis));
  set("imaginary_axis_limit", limit_text(m.imaginary_axis));
  set("oscillator_limit", limit_text(m.oscillator));
  set("notes", notes_text(m));
  return row;
}

}  // namespace

Table analyze_table(const AnalyzeResult& r) {
  Table t{
      {"integrator", "kind", "stages", "claimed_order", "order", "stage_order", "embedded_order",
       "w_order", "embedded_w_order", "claimed_w_order", "fsal", "stiffly_accurate"},
      {}};
  for (int k = 1; k <= kMaxOrder; ++k) t.columns.push_back("residual_order_" + std::to_string(k));
  for (const char* c : {"error_norm_2",
                        "error_norm_max",
                        "error_norm_2_next",
                        "error_norm_max_next",
                        "max_coefficient",
                        "p_coefficients",
                        "q_coefficients",
                        "r_infinity",
                        "a_stable",
                        "l_stable",
                        "real_axis_limit",
                        "imaginary_axis_limit",
                        "internal_amplification_real",
                        "internal_amplification_imag",
                        "ssp_coefficient",
                        "ssp_relative_tolerance",
                        "dissipation_order",
                        "dispersion_order",
                        "oscillator_limit",
                        "embedded_p_coefficients",
                        "embedded_q_coefficients",
                        "embedded_r_infinity",
                        "embedded_a_stable",
                        "embedded_l_stable",
                        "embedded_real_axis_limit",
                        "embedded_imaginary_axis_limit",
                        "notes"})
    t.columns.push_back(c);
  for (const auto& m : r.methods)
    t.rows.push_back(m.coefficient_defined ? coefficient_row(m) : stability_row(m, t.columns));
  return t;
}

Table analyze_conditions_table(const AnalyzeResult& r) {
  Table t{{"integrator", "order", "tree", "residual", "error_coefficient", "set"}, {}};
  for (const auto& m : r.methods)
    for (const auto* set : {&m.analysis.conditions, &m.analysis.w_conditions})
      for (const auto& c : *set)
        t.rows.push_back({m.integrator, std::to_string(c.order), c.name, format_full(c.residual),
                          std::isnan(c.error_coefficient) ? "" : format_full(c.error_coefficient),
                          set == &m.analysis.conditions ? "order" : "W"});
  return t;
}

Table analyze_dispersion_table(const AnalyzeResult& r) {
  Table t{{"integrator", "nu", "amplification", "phase_error"}, {}};
  for (const auto& m : r.methods)
    for (const auto& p : m.dispersion)
      t.rows.push_back({m.integrator, format_full(p.nu), format_full(p.amplification),
                        format_full(p.phase_error)});
  return t;
}

namespace {

std::string stability_class(bool a_stable, bool l_stable) {
  return l_stable ? "A, L" : a_stable ? "A" : "no";
}

}  // namespace

Table analyze_summary_table(const AnalyzeResult& r) {
  Table t{{"integrator", "kind", "order", "W-order", "stage order", "error norm A(p+1)",
           "abs R(inf)", "A/L-stable", "embedded abs R(inf)", "embedded A/L-stable",
           "real-axis limit", "imaginary-axis limit", "SSP"},
          {}};
  for (const auto& m : r.methods) {
    const MethodAnalysis& a = m.analysis;
    if (!m.coefficient_defined) {
      t.rows.push_back({m.integrator, kNotCoefficientDefined, "-", "-", "-", "-", "-",
                        m.a_stable ? (*m.a_stable ? "A" : "no") : "-", "-", "-",
                        m.real_axis ? limit_text(m.real_axis) : "-",
                        m.imaginary_axis ? limit_text(m.imaginary_axis)
                        : m.oscillator   ? "oscillator h*omega < " + limit_text(m.oscillator)
                                         : "-",
                        "-"});
      continue;
    }
    const bool rf = has_stability_function(m);
    std::string order = std::to_string(a.order);
    if (a.order >= analysed_to(a)) order = ">= " + order;
    if (a.claimed_order && a.claimed_order != a.order)
      order += " (claimed " + std::to_string(a.claimed_order) + ")";
    const auto& e = a.embedded_stability;
    t.rows.push_back(
        {m.integrator, a.kind, order, w_order_text(a),
         a.stage_order >= 0 ? std::to_string(a.stage_order) : "-",
         a.order < kMaxOrder && has_error_norms(a) ? format_full(a.error_norm_2) : "-",
         rf ? format_full(a.r_infinity) : "-", rf ? stability_class(a.a_stable, a.l_stable) : "-",
         e ? format_full(e->r_infinity) : "-", e ? stability_class(e->a_stable, e->l_stable) : "-",
         rf ? limit_text(a.real_axis_limit, a.real_axis_unbounded) : "-",
         rf ? limit_text(a.imag_axis_limit, a.imag_axis_unbounded)
            : (a.kind == "splitting" ? "oscillator h*omega < " + format_full(a.oscillator_limit)
                                     : "-"),
         ssp_text(a.ssp_coefficient)});
  }
  return t;
}

// ---- analyze.md ---------------------------------------------------------------------------------

namespace {

Table order_markdown_table(const AnalyzeResult& r) {
  Table t{
      {"integrator", "kind", "stages", "claimed order", "order", "stage order", "embedded order",
       "W-order", "embedded W-order", "FSAL", "stiffly accurate", "2-norm tau(p+1)", "max tau(p+1)",
       "2-norm tau(p+2)", "max tau(p+2)", "max abs coefficient"},
      {}};
  for (const auto& m : r.methods) {
    if (!m.coefficient_defined) continue;
    const MethodAnalysis& a = m.analysis;
    std::vector<std::string> row = {
        m.integrator,
        a.kind,
        std::to_string(a.stages),
        a.claimed_order ? std::to_string(a.claimed_order) : "-",
        (a.order >= analysed_to(a) ? ">= " : "") + std::to_string(a.order),
        a.stage_order >= 0 ? std::to_string(a.stage_order) : "-",
        a.embedded_order ? std::to_string(a.embedded_order) : "-",
        w_order_text(a),
        a.embedded_w_order > 0 ? std::to_string(a.embedded_w_order) : "-",
        yes_no(a.fsal),
        yes_no(a.stiffly_accurate)};
    for (auto& e : error_norms(a)) row.push_back(e.empty() ? "-" : e);
    row.push_back(format_full(a.max_coefficient));
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table residual_markdown_table(const AnalyzeResult& r) {
  Table t{{"integrator"}, {}};
  for (int k = 1; k <= kMaxOrder; ++k) t.columns.push_back("order " + std::to_string(k));
  for (const auto& m : r.methods) {
    if (!m.coefficient_defined) continue;
    std::vector<std::string> row = {m.integrator};
    for (int k = 0; k < kMaxOrder; ++k) {
      const auto& res = m.analysis.residual_by_order;
      row.push_back(k < static_cast<int>(res.size()) ? format_full(res[static_cast<std::size_t>(k)])
                                                     : "-");
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table stability_markdown_table(const AnalyzeResult& r) {
  Table t{{"integrator", "P (ascending)", "Q (ascending)", "abs R(inf)", "A-stable", "L-stable",
           "real-axis limit", "imaginary-axis limit",
           "internal amplification (real, imag; largest of 2001 samples each)", "SSP",
           "dissipation order", "dispersion order"},
          {}};
  for (const auto& m : r.methods) {
    if (!has_stability_function(m)) continue;
    const MethodAnalysis& a = m.analysis;
    t.rows.push_back({m.integrator, polynomial_text(a.p, "; "), polynomial_text(a.q, "; "),
                      format_full(a.r_infinity), yes_no(a.a_stable), yes_no(a.l_stable),
                      limit_text(a.real_axis_limit, a.real_axis_unbounded),
                      limit_text(a.imag_axis_limit, a.imag_axis_unbounded),
                      format_full(a.internal_amplification_real) + ", " +
                          format_full(a.internal_amplification_imag),
                      ssp_text(a.ssp_coefficient), order_text(a.dissipation_order),
                      order_text(a.dispersion_order)});
  }
  return t;
}

// The embedded formulas of the pairs with a stability function: R̂ = P̂/Q̂ and its figures.
Table embedded_markdown_table(const AnalyzeResult& r) {
  Table t{{"integrator", "embedded order", "P (ascending)", "Q (ascending)", "abs R(inf)",
           "A-stable", "L-stable", "real-axis limit", "imaginary-axis limit"},
          {}};
  for (const auto& m : r.methods) {
    const auto& e = m.analysis.embedded_stability;
    if (!m.coefficient_defined || !e) continue;
    t.rows.push_back({m.integrator,
                      m.analysis.embedded_order ? std::to_string(m.analysis.embedded_order) : "-",
                      polynomial_text(e->p, "; "), polynomial_text(e->q, "; "),
                      format_full(e->r_infinity), yes_no(e->a_stable), yes_no(e->l_stable),
                      limit_text(e->real_axis_limit, e->real_axis_unbounded),
                      limit_text(e->imag_axis_limit, e->imag_axis_unbounded)});
  }
  return t;
}

// Splittings and the methods without coefficients: the figures they have.
Table other_markdown_table(const AnalyzeResult& r) {
  Table t{{"integrator", "kind", "order", "oscillator limit h*omega", "real-axis limit",
           "imaginary-axis limit", "A-stable", "notes"},
          {}};
  for (const auto& m : r.methods) {
    if (has_stability_function(m)) continue;
    const MethodAnalysis& a = m.analysis;
    if (m.coefficient_defined) {
      t.rows.push_back({m.integrator, a.kind, std::to_string(a.order),
                        a.kind == "splitting" ? limit_text(a.oscillator_limit, false) : "-", "-",
                        "-", "-", notes_text(m)});
    } else {
      t.rows.push_back({m.integrator, kNotCoefficientDefined,
                        a.claimed_order ? std::to_string(a.claimed_order) : "variable",
                        m.oscillator ? limit_text(m.oscillator) : "-",
                        m.real_axis ? limit_text(m.real_axis) : "-",
                        m.imaginary_axis ? limit_text(m.imaginary_axis) : "-",
                        m.a_stable ? yes_no(*m.a_stable) : "-", notes_text(m)});
    }
  }
  return t;
}

std::string markdown_report(const AnalyzeResult& r) {
  std::ostringstream os;
  os << "# Method analysis\n\n"
     << "From each method's coefficients, nothing is integrated. Order conditions by rooted "
        "trees up to order 8 (residual wᵀΦ(t) − 1/γ(t); the achieved order is the largest p "
        "with every residual up to p below 1e-12), stage order (C(q)), the embedded weights' "
        "order; for Rosenbrock methods the W-order (the order for an arbitrary matrix W in "
        "place of the Jacobian: bi-coloured trees to order 6; Steihaug & Wolfbrandt 1979, Hairer "
        "& Wanner II, IV.7); error coefficients τ(t) = residual/σ(t) and their 2- and max-norms "
        "over the "
        "trees of order p+1 and p+2 (Butcher, Numerical Methods for ODEs, 2016; Kennedy & "
        "Carpenter 2003). Every figure is the shortest decimal that reads back as the same double; "
        "the SSP coefficient, from a bisection, states its relative tolerance.\n\n"
     << "## Order and error coefficients\n\n"
     << order_markdown_table(r).to_markdown() << "\n## Largest residual per order\n\n"
     << residual_markdown_table(r).to_markdown() << "\n## Stability function R = P/Q\n\n"
     << "Limits r: stable on [−r, 0] (real axis) and on [−ir, ir] (imaginary axis), exact from "
        "the roots of |P|² − |Q|²; A-stability checked exactly (no pole in Re z < 0 and "
        "|Q(iy)|² − |P(iy)|² >= 0); internal amplification: the largest Σ_j |Q_j(z)| of the "
        "internal stability functions over the stability intervals (Ketcheson, Lóczi & Parsani "
        "2014); SSP: the radius of absolute monotonicity (Kraaijevanger 1991), explicit methods "
        "only; dissipation and dispersion orders: the lowest power of ν in 1 − |R(iν)| and in "
        "arg R(iν) − ν (`none`: none to the series' length). The curves are in "
        "`analyze_dispersion.csv` (drawn in `analyze.png`).\n\n"
     << stability_markdown_table(r).to_markdown();
  if (const Table emb = embedded_markdown_table(r); !emb.rows.empty())
    os << "\n## Embedded formulas\n\n"
       << "The stability function R̂ = P̂/Q̂ of each embedded pair's second formula (the weights b̂ "
          "in place of b), with the same figures as above: what the error estimate's formula "
          "does on stiff (|R̂(∞)|, A-/L-stability) and on oscillatory or dissipative (axis "
          "limits) modes.\n\n"
       << emb.to_markdown();
  const Table other = other_markdown_table(r);
  if (!other.rows.empty())
    os << "\n## Splittings, IMEX pairs and methods without coefficients\n\n"
       << "Kick/drift splittings have no scalar R(z): their oscillator limit is the largest hω "
          "stable on x'' = −ω²x. An IMEX pair (kind imex_ark) has no R(z) of its own: its order "
          "is that of the additive order conditions, the coupling ones included, and its two "
          "tables are analysed alone in the rows NAME:explicit and NAME:implicit above (the "
          "explicit table's axis limits bound hλ for the eigenvalues of f_E, the implicit "
          "table's |R(∞)| and A-/L-stability tell what the pair does with those of f_I). "
          "Methods that are not coefficient-defined show what their linear stability data "
          "give.\n\n"
       << other.to_markdown();
  std::string notes;
  for (const auto& m : r.methods)
    if (m.coefficient_defined && !m.analysis.notes.empty())
      notes += "- " + m.integrator + ": " + notes_text(m) + "\n";
  if (!notes.empty()) os << "\n## Notes\n\n" << notes;
  os << "\nEvery condition: `analyze_conditions.csv`; every figure at full precision: "
        "`analyze.csv`; metadata: `analyze.json`.\n";
  return os.str();
}

}  // namespace

void write_analyze_outputs(const std::filesystem::path& dir, const AnalyzeSpec& spec,
                           const AnalyzeResult& r) {
  write_file_atomic(dir / "analyze.csv", analyze_table(r).to_csv());
  write_file_atomic(dir / "analyze_conditions.csv", analyze_conditions_table(r).to_csv());
  write_file_atomic(dir / "analyze_dispersion.csv", analyze_dispersion_table(r).to_csv());
  write_file_atomic(dir / "analyze.md", markdown_report(r));
  nlohmann::json meta = run_metadata("analyze", spec.to_json());
  meta["nu"] = "10^(-2 + 3k/(points - 1)), k = 0..points-1";
  meta["order_tolerance"] = 1e-12;
  meta["max_order"] = kMaxOrder;
  meta["max_w_order"] = kMaxWOrder;
  meta["ssp_relative_tolerance"] = kSspRelativeTolerance;
  write_file_atomic(dir / "analyze.json", meta.dump(2) + "\n");
}

bool plot_analyze(const std::filesystem::path& dispersion_csv, const std::string& title,
                  const PlotOptions& opt, std::ostream& err) {
  const std::vector<std::string> drawn = csv_column_values(dispersion_csv, "integrator");
  if (drawn.empty()) {
    err << "note: " << dispersion_csv.string()
        << " has no curve to draw (no method with a stability function R = P/Q): no plot\n";
    return false;
  }
  // Two panels per family: |R(iν)| (odd K) and |arg R(iν) − ν| (even K), side by side.
  std::vector<PlotPanel> panels;
  for (const auto& p : family_panels(drawn, opt.family)) {
    panels.push_back({p.title + ": |R(i nu)|", p.methods});
    panels.push_back({p.title + ": |arg R(i nu) - nu|", p.methods});
  }
  std::filesystem::path stem = dispersion_csv.parent_path() / "analyze";
  return run_plot("analyze.gp", stem, {{"csvfile", dispersion_csv.string()}, {"ttl", title}},
                  panels, opt, err);
}

// ---- the study ---------------------------------------------------------------------------------

namespace {

const StudyFunctions<AnalyzeSpec, AnalyzeResult> kAnalyze{
    .run = [](const StudyInputs& in, const AnalyzeSpec& s,
              std::ostream* progress) { return run_analyze(in, s, progress); },
    .unit_table = [](const AnalyzeSpec&, const AnalyzeResult& r) { return analyze_table(r); },
    .write =
        [](const std::filesystem::path& dir, const AnalyzeSpec& s, const AnalyzeResult& r,
           const std::string& title, const PlotOptions& plot, std::ostream& err) {
          write_analyze_outputs(dir, s, r);
          return plot_analyze(dir / "analyze_dispersion.csv", title, plot, err);
        },
    .print_summary = [](const AnalyzeSpec&, const AnalyzeResult& r,
                        std::ostream& out) { out << analyze_summary_table(r).to_markdown(); },
    .report_markdown =
        [](const AnalyzeSpec&, const AnalyzeResult& r, const std::string& note) {
          return note + "\n\n" + analyze_summary_table(r).to_markdown() + "\n";
        },
    .default_title =
        [](const AnalyzeSpec&) { return "Dissipation |R(i nu)| and dispersion arg R(i nu) - nu"; },
    .helpers = {}};

using AnalyzeJob = TypedStudyJob<AnalyzeSpec, AnalyzeResult>;

}  // namespace

StudyKind analyze_study_kind() {
  StudyKind k;
  k.name = "analyze";
  k.stem = "analyze";
  k.summary =
      "what each method's coefficients say, without running it: order conditions by rooted "
      "trees to order 8, stage and embedded order, a Rosenbrock method's W-order, error norms, "
      "R = P/Q, |R(inf)|, A-/L-stability, exact axis limits (of the embedded formula too), "
      "internal stability, SSP coefficient, dissipation and dispersion; writes "
      "analyze.{csv,md,json,png}, analyze_conditions.csv and "
      "analyze_dispersion.csv";
  k.takes_model = false;
  k.takes_params = false;
  k.integrators_required = false;
  k.unit_per_integrator = false;
  k.positional_integrators = true;
  k.options = analyze_options().declarations();
  k.extra_files = {"analyze_conditions.csv", "analyze_dispersion.csv"};
  k.unit_columns = analyze_table(AnalyzeResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    AnalyzeSpec s = with_inputs(AnalyzeSpec{}, t);
    analyze_options().read(o, s);
    s.validate();
    return std::make_unique<AnalyzeJob>(kAnalyze, t, std::move(s));
  };
  return k;
}

const AnalyzeResult& analyze_result(const StudyJob& job) {
  return typed_result<AnalyzeSpec, AnalyzeResult>(job);
}

AnalyzeResult run_analyze(const AnalyzeSpec& spec, std::ostream* progress) {
  return run_analyze(inputs_of(spec), spec, progress);
}

AnalyzeResult analyze_study(const StudyInputs& in, AnalyzeSpec spec,
                            const std::filesystem::path& dir, const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  spec.validate();
  AnalyzeJob job(kAnalyze, in, std::move(spec));
  run_study_job(study_kind("analyze"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
