#include "experiments/studies/audit.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <map>
#include <ostream>
#include <set>
#include <sstream>

#include "experiments/framework/catalog.hpp"

namespace stiffbench {

namespace {

std::atomic<long> g_failed_checks{0};

}  // namespace

long AuditResult::count(const std::string& status) const {
  return std::count_if(rows.begin(), rows.end(),
                       [&](const AuditRow& r) { return r.status == status; });
}

void AuditSpec::validate() const {
  std::set<std::string> seen;
  for (const auto& name : integrators)
    require_input(seen.insert(name).second, "--integrators: '" + name + "' is listed twice");
}

nlohmann::json AuditSpec::to_json() const {
  return {{"integrators", integrators.empty() ? integrator_registry().names() : integrators}};
}

AuditResult run_audit(const StudyInputs& in, const AuditSpec& given, std::ostream* progress) {
  const AuditSpec spec = with_inputs(given, in);
  spec.validate();
  const std::vector<std::string> names =
      spec.integrators.empty() ? integrator_registry().names() : spec.integrators;
  AuditResult res;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto start = std::chrono::steady_clock::now();
    auto rows = audit_integrator(
        names[k], [&in, &name = names[k]] { return in.create_integrator(name, Params{}); });
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    long failed = 0;
    for (const auto& r : rows) failed += r.status == "fail";
    if (progress)
      *progress << "audit " << names[k] << " (" << k + 1 << "/" << names.size()
                << "): " << (failed ? std::to_string(failed) + " failed" : std::string("ok"))
                << ", " << format_fixed(s, 2) << " s\n";
    res.rows.insert(res.rows.end(), rows.begin(), rows.end());
  }
  return res;
}

Table audit_table(const AuditResult& r) {
  Table t{{"integrator", "check", "system", "claimed", "measured", "status", "reason"}, {}};
  for (const auto& a : r.rows)
    t.rows.push_back({a.integrator, a.check, a.system, a.claimed, a.measured, a.status, a.reason});
  return t;
}

Table audit_summary_table(const AuditResult& r) {
  Table t{{"integrator", "ok", "fail", "skip", "failed checks"}, {}};
  std::vector<std::string> order;
  std::map<std::string, std::array<long, 3>> counts;
  std::map<std::string, std::string> failed;
  for (const auto& a : r.rows) {
    if (!counts.count(a.integrator)) {
      order.push_back(a.integrator);
      counts[a.integrator] = {0, 0, 0};
    }
    auto& c = counts[a.integrator];
    if (a.status == "ok") ++c[0];
    if (a.status == "fail") {
      ++c[1];
      std::string& f = failed[a.integrator];
      f += (f.empty() ? "" : ", ") + a.check + (a.system == "-" ? "" : " (" + a.system + ")");
    }
    if (a.status == "skip") ++c[2];
  }
  for (const auto& name : order) {
    const auto& c = counts[name];
    t.rows.push_back({name, std::to_string(c[0]), std::to_string(c[1]), std::to_string(c[2]),
                      failed.count(name) ? failed[name] : "-"});
  }
  return t;
}

namespace {

std::string markdown_report(const AuditResult& r) {
  std::ostringstream os;
  os << "# Audit of the methods' claims\n\n"
     << r.count("ok") << " checks passed, " << r.count("fail") << " failed, " << r.count("skip")
     << " did not apply (the reason says why). The checks and their tolerances are described in "
        "docs/commands/audit.md; every row is in `audit.csv`.\n\n"
     << "## Summary\n\n"
     << audit_summary_table(r).to_markdown() << "\n## Checks\n\n"
     << audit_table(r).to_markdown();
  return os.str();
}

void write_audit_outputs(const std::filesystem::path& dir, const AuditSpec& spec,
                         const AuditResult& r) {
  write_file_atomic(dir / "audit.csv", audit_table(r).to_csv());
  write_file_atomic(dir / "audit.md", markdown_report(r));
  nlohmann::json meta = run_metadata("audit", spec.to_json());
  meta["counts"] = {{"ok", r.count("ok")}, {"fail", r.count("fail")}, {"skip", r.count("skip")}};
  write_file_atomic(dir / "audit.json", meta.dump(2) + "\n");
}

// A job's run adds its failed checks to g_failed_checks (the command's exit code).
const StudyFunctions<AuditSpec, AuditResult> kAudit{
    .run =
        [](const StudyInputs& in, const AuditSpec& s, std::ostream* progress) {
          AuditResult r = run_audit(in, s, progress);
          g_failed_checks += r.count("fail");
          return r;
        },
    .unit_table = [](const AuditSpec&, const AuditResult& r) { return audit_table(r); },
    .write =
        [](const std::filesystem::path& dir, const AuditSpec& s, const AuditResult& r,
           const std::string&, const PlotOptions&, std::ostream&) {
          write_audit_outputs(dir, s, r);
          return false;  // no plot
        },
    .print_summary =
        [](const AuditSpec&, const AuditResult& r, std::ostream& out) {
          out << audit_summary_table(r).to_markdown() << "\n"
              << r.count("ok") << " checks ok, " << r.count("fail") << " failed, "
              << r.count("skip") << " skipped\n";
        },
    .report_markdown =
        [](const AuditSpec&, const AuditResult& r, const std::string& note) {
          return note + "\n\n" + audit_summary_table(r).to_markdown() + "\n";
        },
    .default_title = [](const AuditSpec&) { return "Audit of the methods' claims"; },
    .helpers = {}};

using AuditJob = TypedStudyJob<AuditSpec, AuditResult>;

}  // namespace

long audit_failed_checks() { return g_failed_checks.load(); }

StudyKind audit_study_kind() {
  StudyKind k;
  k.name = "audit";
  k.stem = "audit";
  k.summary =
      "checks every method's claims (evaluation counts against a counting wrapper, local-error "
      "slope, adaptive exactness on polynomials, tableau order, stage order and FSAL); writes "
      "audit.{csv,md,json}; exit code 3 when a check fails";
  k.takes_model = false;
  k.takes_params = false;
  k.integrators_required = false;
  k.unit_columns = audit_table(AuditResult{}).columns;
  k.make = [](const StudyInputs& t, const Params&, const StudyContext&) {
    AuditSpec s = with_inputs(AuditSpec{}, t);
    s.validate();
    return std::make_unique<AuditJob>(kAudit, t, std::move(s));
  };
  return k;
}

const AuditResult& audit_result(const StudyJob& job) {
  return typed_result<AuditSpec, AuditResult>(job);
}

AuditResult run_audit(const AuditSpec& spec, std::ostream* progress) {
  return run_audit(inputs_of(spec), spec, progress);
}

AuditResult audit_study(const StudyInputs& in, AuditSpec spec, const std::filesystem::path& dir,
                        const StudyContext& ctx) {
  spec = with_inputs(std::move(spec), in);
  spec.validate();
  AuditJob job(kAudit, in, std::move(spec));
  run_study_job(study_kind("audit"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
