#include "experiments/studies/region.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <ostream>
#include <set>
#include <sstream>

#include "core/driver.hpp"
#include "core/run_control.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/support/coefficients.hpp"

namespace stiffbench {

namespace {

using cd = std::complex<double>;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string join_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// The stability data of a registered integrator (created with its defaults: no parameter of
// the registered methods changes their coefficients).
std::optional<LinearStability> stability_of(const std::string& name) {
  return integrator_registry().create(name, Params{})->linear_stability();
}

// The curves of an integrator of `in` (created with its defaults): its own region, or for an
// additive (IMEX) pair, which has none, the regions of its two tables alone (NAME:explicit,
// NAME:implicit; what `analyze` shows of them), or for an operator splitting (lie, strang), whose
// R is not a function of one hλ either, its explicit sub-integrator's region over one step
// (NAME:explicit: R(z) for lie, R(z/2)² for strang; the default sub-integrators, what
// `stability` predicts from). Empty when it has none of these.
std::vector<std::pair<std::string, LinearStability>> region_curves(const StudyInputs& in,
                                                                   const std::string& name) {
  const auto integ = in.create_integrator(name, Params{});
  if (auto s = integ->linear_stability()) return {{name, std::move(*s)}};
  if (const AdditiveTableau* t = integ->additive_tableau())
    return {{additive_part_name(name, "explicit"), tableau_stability(t->explicit_table)},
            {additive_part_name(name, "implicit"), tableau_stability(t->implicit_table)}};
  if (auto e = integ->explicit_part_stability())
    return {{additive_part_name(name, "explicit"), std::move(*e)}};
  return {};
}

std::string no_region_reason(const StudyInputs& in, const std::string& name) {
  const auto& info = in.integrator_entry(name).info;
  std::string why = info.family == Family::reference
                        ? "a library integrator: its coefficients are not known to stiffbench"
                        : "no stability data";
  if (info.order == 0) why += ", variable order";
  return "--integrators: '" + name + "' has no fixed stability region (" + why +
         "); integrators with one: " + join_names(region_integrators()) +
         ", the IMEX pairs (the regions of their two tables) and lie and strang (their explicit "
         "sub-integrator's region over one step)";
}

std::vector<std::string> chosen_integrators(const RegionSpec& spec) {
  return spec.integrators.empty() ? region_integrators() : spec.integrators;
}

// `spec` with `in`'s integrators, checked: BadInput for a bad spec or an integrator without a
// region.
RegionSpec checked_spec(const StudyInputs& in, const RegionSpec& given) {
  RegionSpec spec = with_inputs(given, in);
  spec.validate();
  for (const auto& name : spec.integrators)
    require_input(!region_curves(in, name).empty(), no_region_reason(in, name));
  return spec;
}

}  // namespace

std::vector<std::string> region_integrators() {
  std::vector<std::string> out;
  for (const auto& name : integrator_registry().names())
    if (stability_of(name)) out.push_back(name);
  return out;
}

void RegionSpec::validate() const {
  std::set<std::string> seen;
  for (const auto& name : integrators)
    require_input(seen.insert(name).second, "--integrators: '" + name + "' is listed twice");
  if (box) {
    const RegionBox& b = *box;
    const std::string got = " (got " + format_full(b.re_min) + "," + format_full(b.re_max) + "," +
                            format_full(b.im_min) + "," + format_full(b.im_max) + ")";
    require_input(std::isfinite(b.re_min) && std::isfinite(b.re_max) && std::isfinite(b.im_min) &&
                      std::isfinite(b.im_max),
                  "--box: every bound must be finite" + got);
    require_input(b.re_min < b.re_max && b.im_min < b.im_max,
                  "--box: need re_min < re_max and im_min < im_max" + got);
  }
  require_input(
      resolution >= 10 && resolution <= 4000,
      "--resolution must be between 10 and 4000 (got " + std::to_string(resolution) + ")");
}

nlohmann::json RegionSpec::to_json() const {
  nlohmann::json j = {{"integrators", chosen_integrators(*this)}, {"resolution", resolution}};
  if (box) {
    j["box"] = {box->re_min, box->re_max, box->im_min, box->im_max};
  } else {
    j["box"] = "fitted";
  }
  return j;
}

RegionBox parse_region_box(const std::string& arg) {
  const std::string usage =
      "--box: expected re_min,re_max,im_min,im_max (four numbers), got '" + arg + "'";
  std::vector<double> v;
  try {
    v = parse_real_list(arg, "--box");
  } catch (const BadInput&) {
    throw BadInput(usage);
  }
  require_input(v.size() == 4, usage);
  return {v[0], v[1], v[2], v[3]};
}

RegionBox fitted_region_box(const std::vector<LinearStability>& methods) {
  // Coarse search box; a polyline that comes within about a cell of its edge runs off to
  // infinity (or is too large to show next to the others) and does not widen the box.
  constexpr double L = 12.0;
  constexpr int n = 120;
  const double edge = 1.5 * 2.0 * L / n;
  double xmin = -1.0, xmax = 1.0, ymax = 1.0;  // always show the unit neighbourhood of 0
  for (const auto& s : methods) {
    if (!s.amplification) continue;
    for (const auto& line : region_boundary(s, -L, L, -L, L, n)) {
      const bool bounded = std::all_of(line.begin(), line.end(), [&](cd z) {
        return std::abs(z.real()) < L - edge && std::abs(z.imag()) < L - edge;
      });
      if (!bounded) continue;
      for (cd z : line) {
        xmin = std::min(xmin, z.real());
        xmax = std::max(xmax, z.real());
        ymax = std::max(ymax, std::abs(z.imag()));
      }
    }
    const AxisLimit re = real_axis_limit(s, L);
    if (!re.unbounded) xmin = std::min(xmin, -re.limit);
    const AxisLimit im = imaginary_axis_limit(s, L);
    if (!im.unbounded) ymax = std::max(ymax, im.limit);
  }
  const double pad = 0.1 * std::max(xmax - xmin, 2.0 * ymax);
  RegionBox b;
  b.re_min = std::floor(2.0 * (xmin - pad)) / 2.0;
  b.re_max = std::ceil(2.0 * (xmax + pad)) / 2.0;
  b.im_max = std::ceil(2.0 * (ymax + pad)) / 2.0;
  b.im_min = -b.im_max;
  return b;
}

RegionResult run_region(const StudyInputs& in, const RegionSpec& given, std::ostream*) {
  const RegionSpec spec = checked_spec(in, given);
  std::vector<std::string> names, family;
  std::vector<LinearStability> stab;
  for (const auto& name : chosen_integrators(spec))
    for (auto& [row, s] : region_curves(in, name)) {
      names.push_back(row);
      family.push_back(to_string(in.integrator_entry(name).info.family));
      stab.push_back(std::move(s));
    }

  RegionResult res;
  res.resolution = spec.resolution;
  res.box_fitted = !spec.box.has_value();
  res.box = spec.box ? *spec.box : fitted_region_box(stab);
  res.methods.resize(names.size());
  const RegionBox b = res.box;
  std::vector<std::exception_ptr> failed(names.size());
  // Methods are independent; each evaluates only its own coefficients. Each method is a row
  // for --max-wall: one over it keeps what it had and says where it stopped.
#pragma omp parallel for schedule(dynamic)
  for (std::size_t k = 0; k < names.size(); ++k) {
    const LinearStability& s = stab[k];
    RegionMethod& m = res.methods[k];
    m.integrator = names[k];
    m.family = family[k];
    m.kind = s.kind;
    m.has_region = static_cast<bool>(s.amplification);
    try {
      const RowClock clock;
      if (m.has_region) {
        m.boundary = region_boundary(s, b.re_min, b.re_max, b.im_min, b.im_max, spec.resolution);
        m.real_axis = real_axis_limit(s);
        m.imaginary_axis = imaginary_axis_limit(s);
        const std::optional<bool> exact = a_stable_exact(s);
        m.a_stable = exact ? *exact : a_stable_on_samples(s);
      }
      m.oscillator = oscillator_limit(s);
    } catch (const WallLimitExceeded& e) {
      m.boundary.clear();
      m.stopped = e.what();
      count_row_timeout();
    } catch (...) {
      failed[k] = std::current_exception();  // an interrupt or an error leaves the loop after it
    }
  }
  for (const auto& e : failed)
    if (e) std::rethrow_exception(e);
  for (const auto& m : res.methods)
    if (!m.stopped.empty())
      std::cerr << "warning: region of " << m.integrator << " stopped: " << m.stopped << "\n";
  // Methods with the same stability function (heun, midpoint and ralston share R(z) = 1 + z +
  // z²/2) are told apart in the Markdown table, since their curves coincide in the plot.
  std::vector<std::vector<double>> samples(names.size());
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!stab[k].amplification) continue;
    for (int i = 0; i < 24; ++i)
      samples[k].push_back(stab[k].amplification(std::polar(0.3 + 0.25 * i, 0.7 + 0.23 * i)));
    for (std::size_t e = 0; e < k && res.methods[k].same_as.empty(); ++e) {
      if (samples[e].size() != samples[k].size()) continue;
      bool same = true;
      for (std::size_t i = 0; i < samples[k].size(); ++i)
        same = same && std::abs(samples[k][i] - samples[e][i]) <=
                           1e-12 * std::max(1.0, std::abs(samples[k][i]));
      if (same) res.methods[k].same_as = names[e];
    }
  }
  return res;
}

Table region_table(const RegionResult& r) {
  Table t{{"integrator", "re", "im"}, {}};
  for (const auto& m : r.methods) {
    for (std::size_t k = 0; k < m.boundary.size(); ++k) {
      if (k > 0) t.rows.push_back({m.integrator, "nan", "nan"});  // pen up between polylines
      for (cd z : m.boundary[k])
        t.rows.push_back({m.integrator, format_full(z.real()), format_full(z.imag())});
    }
  }
  return t;
}

namespace {

// A limit along a ray as a signed number: the boundary point on the negative real axis (−r),
// on the positive imaginary axis (r), or the hω limit; ±inf when unbounded.
double signed_limit(const AxisLimit& a, double sign) {
  return sign * (a.unbounded ? kInf : a.limit);
}

std::string limit_md(const std::optional<AxisLimit>& a, double sign) {
  if (!a) return "-";
  if (a->unbounded) return std::string(sign < 0 ? "-inf" : "inf") + " (unbounded)";
  if (a->limit == 0.0) return "0 (unstable near 0)";
  return format_fixed(sign * a->limit, 10);
}

}  // namespace

// "exact" when every limit of the row came from polynomial roots, else "sampled".
std::string limits_how(const RegionMethod& m) {
  if (!m.stopped.empty()) return "stopped";
  bool exact = m.oscillator.exact;
  if (m.real_axis) exact = exact && m.real_axis->exact;
  if (m.imaginary_axis) exact = exact && m.imaginary_axis->exact;
  return exact ? "exact" : "sampled";
}

namespace {

std::string kind_md(const RegionMethod& m) {
  return m.has_region ? m.kind : m.kind + " (mechanical systems only: no region)";
}

}  // namespace

Table region_limits_table(const RegionResult& r) {
  Table t{{"integrator", "family", "kind", "real_axis_limit", "imaginary_axis_limit",
           "oscillator_limit", "a_stable", "limits"},
          {}};
  for (const auto& m : r.methods) {
    t.rows.push_back({m.integrator, m.family, m.kind,
                      m.real_axis ? format_full(signed_limit(*m.real_axis, -1.0)) : "",
                      m.imaginary_axis ? format_full(signed_limit(*m.imaginary_axis, 1.0)) : "",
                      m.stopped.empty() ? format_full(signed_limit(m.oscillator, 1.0)) : "",
                      m.a_stable ? (*m.a_stable ? "yes" : "no") : "", limits_how(m)});
  }
  return t;
}

Table region_limits_markdown_table(const RegionResult& r) {
  Table t{{"integrator", "kind", "real-axis limit", "imaginary-axis limit",
           "oscillator limit h*omega", "A-stable", "limits"},
          {}};
  for (const auto& m : r.methods) {
    t.rows.push_back({m.integrator, kind_md(m), limit_md(m.real_axis, -1.0),
                      limit_md(m.imaginary_axis, 1.0),
                      m.stopped.empty() ? limit_md(m.oscillator, 1.0) : "-",
                      m.a_stable ? (*m.a_stable ? "yes" : "no") : "-", limits_how(m)});
  }
  return t;
}

namespace {

std::string markdown_report(const RegionResult& r) {
  std::ostringstream os;
  os << "# Linear stability regions\n\n"
     << "From the coefficients of each method (no runs): the boundary |R(z)| = 1 in the plane "
        "z = h*lambda is in `region.csv` (drawn in `region.png`), box Re z in ["
     << format_full(r.box.re_min) << ", " << format_full(r.box.re_max) << "], Im z in ["
     << format_full(r.box.im_min) << ", " << format_full(r.box.im_max) << "]"
     << (r.box_fitted ? " (fitted to the methods)" : "") << ", grid " << r.resolution << " x "
     << r.resolution << ". The stable side of a boundary is the one holding z = -0 (just left "
     << "of the origin): inside for explicit methods, outside for the implicit ones.\n\n"
     << "Limits: the real-axis limit is the first z = -r on the negative real axis where the "
        "method becomes unstable, the imaginary-axis limit the first z = i*r; the oscillator "
        "limit is the largest h*omega stable on x'' = -omega^2 x (the only limit of the "
        "methods that need a mechanical system); A-stable: |R| <= 1 on samples of the left "
        "half-plane (|z| up to 1e3).\n\n";
  os << region_limits_markdown_table(r).to_markdown();
  std::string same;
  for (const auto& m : r.methods)
    if (!m.same_as.empty()) same += (same.empty() ? "" : ", ") + m.integrator + " = " + m.same_as;
  if (!same.empty())
    os << "\nSame stability function |R(z)|, hence the same region and coinciding curves in the "
          "plot: "
       << same << ".\n";
  const bool parts = std::any_of(r.methods.begin(), r.methods.end(), [](const RegionMethod& m) {
    return m.integrator.find(':') != std::string::npos;
  });
  if (parts)
    os << "\nNAME:explicit and NAME:implicit are parts, not the method: an IMEX pair's two tables "
          "alone, and for lie and strang their explicit sub-integrator over one step h (one "
          "step for lie, two of h/2 for strang; the default sub-integrators). The combined "
          "method's amplification is not a function of one h*lambda when the parts do not "
          "commute; `stability` measures its limit on a split model.\n";
  for (const auto& m : r.methods)
    if (!m.stopped.empty())
      os << "\n**" << m.integrator << " stopped** (" << m.stopped
         << "): no boundary and no limits for it.\n";
  os << "\nFull-precision limits: `region_limits.csv`; metadata: `region.json`.\n";
  return os.str();
}

}  // namespace

void write_region_outputs(const std::filesystem::path& dir, const RegionSpec& spec,
                          const RegionResult& r) {
  write_file_atomic(dir / "region.csv", region_table(r).to_csv());
  write_file_atomic(dir / "region_limits.csv", region_limits_table(r).to_csv());
  write_file_atomic(dir / "region.md", markdown_report(r));
  nlohmann::json meta = run_metadata("region", spec.to_json());
  meta["box"] = {{"re_min", r.box.re_min},
                 {"re_max", r.box.re_max},
                 {"im_min", r.box.im_min},
                 {"im_max", r.box.im_max},
                 {"fitted", r.box_fitted}};
  meta["boundary"] =
      "|R(z)| = 1: marching squares on the grid, each crossing bisected on |R| - 1 (one-step "
      "methods); the boundary locus rho/sigma on the unit circle clipped to the box (multistep)";
  meta["polyline_break"] = "a row 'integrator,nan,nan' between two polylines of one integrator";
  meta["a_stable_samples"] =
      "left half-plane box [-1e3, 0] x [-1e3, 1e3], 201 x 201, and a "
      "log-polar grid from |z| = 1e-3";
  write_file_atomic(dir / "region.json", meta.dump(2) + "\n");
}

namespace {

// The boundary points of each integrator in a region.csv (break rows skipped).
std::map<std::string, std::vector<cd>> read_region_points(const std::filesystem::path& csv) {
  std::map<std::string, std::vector<cd>> points;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    const auto c1 = line.find(',');
    const auto c2 = line.find(',', c1 == std::string::npos ? c1 : c1 + 1);
    if (c1 == std::string::npos || c2 == std::string::npos) continue;
    try {
      const double re = std::stod(line.substr(c1 + 1, c2 - c1 - 1));
      const double im = std::stod(line.substr(c2 + 1));
      if (std::isfinite(re) && std::isfinite(im)) points[line.substr(0, c1)].emplace_back(re, im);
    } catch (const std::exception&) {
    }
  }
  return points;
}

// Two curves coincide when every point of each lies within `tol` of a point of the other
// (symmetric Hausdorff distance of the point sets; brute force, a few thousand points each).
bool coincide(const std::vector<cd>& a, const std::vector<cd>& b, double tol) {
  if (a.empty() || b.empty()) return false;
  auto covered = [tol](const std::vector<cd>& p, const std::vector<cd>& q) {
    for (cd z : p) {
      bool near = false;
      for (std::size_t i = 0; i < q.size() && !near; ++i) near = std::abs(z - q[i]) <= tol;
      if (!near) return false;
    }
    return true;
  };
  return covered(a, b) && covered(b, a);
}

}  // namespace

bool plot_region(const std::filesystem::path& csv, const std::string& title, const PlotOptions& opt,
                 std::ostream& err) {
  const std::vector<std::string> drawn = csv_column_values(csv, "integrator");
  if (drawn.empty()) {
    err << "note: " << csv.string()
        << " has no boundary to draw (methods of mechanical systems only have an oscillator "
           "limit): no plot\n";
    return false;
  }
  // Line styles per panel: a curve that coincides with an earlier one of its panel (same
  // stability function: heun, midpoint, ralston) is drawn thinner and dashed on top of it, so
  // both colours stay visible; the others solid.
  const auto points = read_region_points(csv);
  double span = 0.0;
  for (const auto& [name, pts] : points)
    for (cd z : pts) span = std::max({span, std::abs(z.real()), std::abs(z.imag())});
  // Coinciding on the drawing: within 0.2% of the extent (about a pixel). Not 1e-12: curves
  // along |R| = 1 on a whole line (the imaginary axis of implicit midpoint and trapezoidal) are
  // traced through round-off and differ between two tableaux with the same R.
  const double tol = 2e-3 * std::max(span, 1.0);
  const std::vector<PlotPanel> panels = family_panels(drawn, opt.family);
  PlotVars vars = {{"csvfile", csv.string()}, {"ttl", title}};
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const auto& names = panels[k].methods;
    std::string widths, dashes;
    int dashed = 0;
    for (std::size_t j = 0; j < names.size(); ++j) {
      int rank = 0;  // earlier methods of the panel with the same curve
      for (std::size_t e = 0; e < j; ++e)
        if (points.count(names[e]) && points.count(names[j]) &&
            coincide(points.at(names[e]), points.at(names[j]), tol))
          ++rank;
      const double lw = rank == 0 ? 2.5 : std::max(2.5 - 0.8 * rank, 0.9);
      const int dt = rank == 0 ? 1 : 2 + (dashed++ % 4);
      widths += (j ? " " : "") + format_fixed(lw, 1);
      dashes += (j ? " " : "") + std::to_string(dt);
    }
    vars.emplace_back("plw" + std::to_string(k + 1), widths);
    vars.emplace_back("pdt" + std::to_string(k + 1), dashes);
  }
  std::filesystem::path stem = csv;
  stem.replace_extension();
  return run_plot("region.gp", stem, vars, panels, opt, err);
}

namespace {

const StudyFunctions<RegionSpec, RegionResult> kRegion{
    .run = [](const StudyInputs& in, const RegionSpec& s,
              std::ostream* progress) { return run_region(in, s, progress); },
    .unit_table = [](const RegionSpec&, const RegionResult& r) { return region_limits_table(r); },
    .write =
        [](const std::filesystem::path& dir, const RegionSpec& s, const RegionResult& r,
           const std::string& title, const PlotOptions& plot, std::ostream& err) {
          write_region_outputs(dir, s, r);
          return plot_region(dir / "region.csv", title, plot, err);
        },
    .print_summary =
        [](const RegionSpec&, const RegionResult& r, std::ostream& out) {
          out << region_limits_markdown_table(r).to_markdown();
        },
    .report_markdown =
        [](const RegionSpec&, const RegionResult& r, const std::string& note) {
          return note + "\n\n" + region_limits_markdown_table(r).to_markdown() + "\n";
        },
    .default_title = [](const RegionSpec&) { return "Stability regions: boundary |R(z)| = 1"; },
    .helpers = {}};

using RegionJob = TypedStudyJob<RegionSpec, RegionResult>;

}  // namespace

StudyKind region_study_kind() {
  StudyKind k;
  k.name = "region";
  k.stem = "region";
  k.summary =
      "linear stability regions from the coefficients: the boundary |R(z)| = 1 of each "
      "integrator in the complex plane z = h*lambda, and its real-axis, imaginary-axis and "
      "oscillator limits; writes region.{csv,md,json,png} and region_limits.csv";
  k.takes_model = false;
  k.takes_params = false;
  k.integrators_required = false;
  k.unit_per_integrator = false;
  k.options = {{"box", ParamType::text, "",
                "the part of the complex plane drawn: re_min,re_max,im_min,im_max (default: "
                "fitted to the chosen methods' boundaries)"},
               {"resolution", ParamType::integer, "400", "grid cells per side of the box",
                Bounds::in(10, 4000)}};
  k.extra_files = {"region_limits.csv"};
  k.unit_columns = region_limits_table(RegionResult{}).columns;
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    RegionSpec s;
    if (o.contains("box")) s.box = parse_region_box(o.text("box"));
    s.resolution = static_cast<int>(o.integer("resolution"));
    return std::make_unique<RegionJob>(kRegion, t, checked_spec(t, s));
  };
  return k;
}

const RegionResult& region_result(const StudyJob& job) {
  return typed_result<RegionSpec, RegionResult>(job);
}

RegionResult run_region(const RegionSpec& spec, std::ostream* progress) {
  return run_region(inputs_of(spec), spec, progress);
}

RegionResult region_study(const StudyInputs& in, RegionSpec spec, const std::filesystem::path& dir,
                          const StudyContext& ctx) {
  RegionJob job(kRegion, in, checked_spec(in, spec));
  run_study_job(study_kind("region"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
