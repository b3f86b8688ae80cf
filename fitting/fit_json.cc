#include "fitting/fit_json.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "fitting/student_t.h"

namespace bosfuse::fitting {
namespace {

using nlohmann::ordered_json;

using nlohmann::json;

double number_or_nan(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

Estimate estimate_from_json(const json& j) {
  Estimate e;
  e.value = e.std_error = e.low = e.high = std::numeric_limits<double>::quiet_NaN();
  if (!j.is_object()) return e;
  e.value = number_or_nan(j, "value");
  e.std_error = number_or_nan(j, "std_error");
  e.fixed = j.value("fixed", false);
  if (const auto it = j.find("interval"); it != j.end() && it->is_object()) {
    e.low = number_or_nan(*it, "low");
    e.high = number_or_nan(*it, "high");
  }
  return e;
}

FitStatus status_from_json(const json& j) {
  const std::string status = j.value("status", std::string());
  for (int i = 0; i <= static_cast<int>(FitStatus::kNotConverged); ++i) {
    if (status == to_string(static_cast<FitStatus>(i))) return static_cast<FitStatus>(i);
  }
  return FitStatus::kNotConverged;
}

constexpr std::array<const char*, 3> kCovarianceParameters{"log_tau", "delta_c", "ambient_c"};

bool all_finite(const ParameterCovariance& c) {
  return std::all_of(c.begin(), c.end(), [](const auto& row) {
    return std::all_of(row.begin(), row.end(), [](double v) { return std::isfinite(v); });
  });
}

// Absent rather than null when there is none (a failed fit), so a reader
// never meets a null where a number belongs.
void write_covariance(const NewtonFit& fit, ordered_json& j) {
  if (!fit.ok() || !fit.covariance || !all_finite(*fit.covariance)) return;
  ordered_json matrix = ordered_json::array();
  for (const auto& row : *fit.covariance) matrix.push_back(row);
  j["covariance"] = {{"parameters", kCovarianceParameters}, {"matrix", std::move(matrix)}};
}

// nullopt when absent (a fit stored before the covariance was) or not a
// 3 × 3 matrix of numbers in the written parameter order.
std::optional<ParameterCovariance> covariance_from_json(const json& j) {
  const auto it = j.find("covariance");
  if (it == j.end() || !it->is_object()) return std::nullopt;
  if (it->value("parameters", json()) != json(kCovarianceParameters)) return std::nullopt;
  const json& m = it->value("matrix", json());
  if (!m.is_array() || m.size() != 3) return std::nullopt;
  ParameterCovariance c{};
  for (std::size_t r = 0; r < 3; ++r) {
    if (!m[r].is_array() || m[r].size() != 3) return std::nullopt;
    for (std::size_t k = 0; k < 3; ++k) {
      if (!m[r][k].is_number()) return std::nullopt;
      c[r][k] = m[r][k].get<double>();
    }
  }
  return c;
}

// A fit stored before t_critical was written: the same value from what was.
double t_critical_from(const NewtonFitSummary& s) {
  if (!s.ok() || !(s.dof > 0) || !(s.confidence > 0 && s.confidence < 1)) return 0.0;
  if (s.absolute_sigma && s.interval_dof) return student_t_critical(*s.interval_dof, s.confidence);
  return s.absolute_sigma ? normal_critical(s.confidence) : student_t_critical(s.dof, s.confidence);
}

void read_diagnostics(const json& d, NewtonFit& fit) {
  auto& s = fit.summary;
  s.points_used = d.value("points_used", std::size_t{0});
  s.rejected_non_finite = d.value("rejected_non_finite", std::size_t{0});
  s.duplicate_times = d.value("duplicate_times_kept", std::size_t{0});
  s.parameters = d.value("parameters", 0);
  s.dof = d.value("dof", 0.0);
  s.iterations = d.value("iterations", 0);
  fit.duration_s = number_or_nan(d, "duration_s");
  s.residual_rms_c = number_or_nan(d, "residual_rms_c");
  s.residual_std_c = number_or_nan(d, "residual_std_c");
  if (const double chi = number_or_nan(d, "reduced_chi_square"); std::isfinite(chi)) s.reduced_chi_square = chi;
  s.lag1_autocorrelation = number_or_nan(d, "lag1_autocorrelation");
  s.record_time_constants = number_or_nan(d, "record_time_constants");
  s.outliers = d.value("outliers", std::size_t{0});
  s.t_critical = number_or_nan(d, "t_critical");
  if (const double dof = number_or_nan(d, "interval_dof"); std::isfinite(dof)) s.interval_dof = dof;
}

}  // namespace

ordered_json number_or_null(double value) { return std::isfinite(value) ? ordered_json(value) : ordered_json(nullptr); }

NewtonFit fit_from_json(const json& j) {
  NewtonFit fit;
  fit.origin_s = number_or_nan(j, "origin_s");
  // Absent from a fit stored before T0 could be given anywhere but at the origin.
  if (const double t = number_or_nan(j, "t0_reference_s"); std::isfinite(t)) fit.t0_reference_s = t;
  const json& p = j.at("parameters");
  fit.k_per_s = estimate_from_json(p.value("k_per_s", json()));
  fit.tau_s = estimate_from_json(p.value("tau_s", json()));
  fit.t0_c = estimate_from_json(p.value("T0_c", json()));
  fit.ambient_c = estimate_from_json(p.value("T_amb_c", json()));
  auto& s = fit.summary;
  s.status = status_from_json(j);
  s.message = j.value("error", std::string());
  s.absolute_sigma = j.value("uncertainty", std::string()).rfind("absolute", 0) == 0;
  if (const auto k = p.find("k_per_s"); k != p.end() && k->is_object() && k->contains("interval")) {
    s.confidence = k->at("interval").value("confidence", 0.95);
  }
  if (const auto d = j.find("diagnostics"); d != j.end() && d->is_object()) read_diagnostics(*d, fit);
  if (const auto w = j.find("warnings"); w != j.end() && w->is_array()) s.warnings = w->get<std::vector<std::string>>();
  if (!std::isfinite(s.t_critical)) s.t_critical = t_critical_from(s);
  fit.covariance = covariance_from_json(j);
  return fit;
}

namespace {

Verdict verdict_from_json(const json& j) {
  const std::string text = j.is_string() ? j.get<std::string>() : std::string();
  for (Verdict v : {Verdict::kAgree, Verdict::kDiffer, Verdict::kInconclusive}) {
    if (text == to_string(v)) return v;
  }
  throw json::type_error::create(302, "unknown verdict \"" + text + "\"", &j);
}

CurveAgreement curve_from_json(const json& j) {
  CurveAgreement c;
  c.verdict = verdict_from_json(j.at("verdict"));
  c.deciding_parameter = j.value("deciding_parameter", std::string());
  // Stored before the test was TOST: two-sided intervals at the stated confidence, α = (1 − confidence) / 2.
  c.confidence = j.contains("confidence") ? number_or_nan(j, "confidence") : 0.95;
  c.alpha = j.contains("alpha") ? number_or_nan(j, "alpha") : 0.5 * (1.0 - c.confidence);
  for (const json& p : j.at("parameters")) {
    ParameterAgreement pa;
    pa.name = p.at("name").get<std::string>();
    pa.difference = number_or_nan(p, "difference");
    pa.std_error = number_or_nan(p, "std_error");
    // Stored before the systematic part existed: all of it was random.
    pa.random_std_error = p.contains("random_std_error") ? number_or_nan(p, "random_std_error") : pa.std_error;
    pa.systematic_std_error = p.contains("systematic_std_error") ? number_or_nan(p, "systematic_std_error") : 0.0;
    pa.z = number_or_nan(p, "z");
    pa.margin = number_or_nan(p, "margin");
    pa.critical = number_or_nan(p, "critical");
    pa.interval_low = number_or_nan(p, "interval_low");
    pa.interval_high = number_or_nan(p, "interval_high");
    pa.verdict = verdict_from_json(p.at("verdict"));
    pa.in_verdict = p.value("in_verdict", true);
    c.parameters.push_back(pa);
  }
  return c;
}

ordered_json to_json(const CurveAgreement& c) {
  ordered_json parameters = ordered_json::array();
  for (const auto& p : c.parameters) {
    parameters.push_back({{"name", p.name},
                          {"difference", number_or_null(p.difference)},
                          {"std_error", number_or_null(p.std_error)},
                          {"random_std_error", number_or_null(p.random_std_error)},
                          {"systematic_std_error", number_or_null(p.systematic_std_error)},
                          {"z", number_or_null(p.z)},
                          {"margin", number_or_null(p.margin)},
                          {"critical", number_or_null(p.critical)},
                          {"interval_low", number_or_null(p.interval_low)},
                          {"interval_high", number_or_null(p.interval_high)},
                          {"verdict", to_string(p.verdict)},
                          {"in_verdict", p.in_verdict}});
  }
  return {{"verdict", to_string(c.verdict)},
          {"deciding_parameter", c.deciding_parameter},
          {"confidence", c.confidence},
          {"alpha", c.alpha},
          {"test", "two one-sided tests (TOST, Schuirmann 1987) at alpha: the difference's 1 - 2 alpha interval inside "
                   "+-margin: agree; wholly outside: differ; else inconclusive"},
          {"combination", "the worst of the parameters in the verdict (differ over inconclusive over agree)"},
          {"parameters", parameters}};
}

}  // namespace

Agreement agreement_from_json(const json& j) {
  Agreement a;
  a.verdict = j.value("verdict", std::string());
  if (const auto k = j.find("k"); k != j.end() && k->is_object()) {
    KAgreement ka;
    ka.difference_per_s = number_or_nan(*k, "difference_per_s");
    ka.std_error_per_s = number_or_nan(*k, "std_error_per_s");
    ka.z = number_or_nan(*k, "z");
    ka.relative_difference = number_or_nan(*k, "relative_difference");
    ka.agree = k->value("agree", false);
    a.k = ka;
  }
  if (const auto s = j.find("series"); s != j.end() && s->is_object()) {
    SeriesAgreement sa;
    sa.common_points = s->value("common_points", std::size_t{0});
    sa.overlap_start_s = number_or_nan(*s, "overlap_start_s");
    sa.overlap_end_s = number_or_nan(*s, "overlap_end_s");
    sa.rms_difference_c = number_or_nan(*s, "rms_difference_c");
    sa.bias_c = number_or_nan(*s, "bias_c");
    sa.difference_std_c = number_or_nan(*s, "difference_std_c");
    sa.limits_of_agreement_low_c = number_or_nan(*s, "limits_of_agreement_low_c");
    sa.limits_of_agreement_high_c = number_or_nan(*s, "limits_of_agreement_high_c");
    // Written before the lag was modelled: as read is all there was.
    sa.rms_difference_as_read_c =
        s->contains("rms_difference_as_read_c") ? number_or_nan(*s, "rms_difference_as_read_c") : sa.rms_difference_c;
    sa.bias_as_read_c = s->contains("bias_as_read_c") ? number_or_nan(*s, "bias_as_read_c") : sa.bias_c;
    a.series = sa;
  }
  a.confidence = j.contains("confidence") ? number_or_nan(j, "confidence") : 0.95;
  if (const auto e = j.find("equivalence"); e != j.end() && e->is_object()) a.curve = curve_from_json(*e);
  if (const auto l = j.find("lag"); l != j.end() && l->is_object()) {
    a.lag.source = l->value("source", std::string("none"));
    a.lag.time_constant_s = number_or_nan(*l, "time_constant_s");
    if (const auto it = l->find("estimated_s"); it != l->end() && it->is_number())
      a.lag.estimated_s = it->get<double>();
    a.lag.std_error_s = number_or_nan(*l, "std_error_s");
  }
  return a;
}

ordered_json to_json(const Estimate& e, double confidence) {
  if (!std::isfinite(e.value)) return nullptr;
  ordered_json j = {{"value", e.value}, {"std_error", number_or_null(e.std_error)}, {"fixed", e.fixed}};
  j["interval"] = {{"confidence", confidence}, {"low", number_or_null(e.low)}, {"high", number_or_null(e.high)}};
  return j;
}

ordered_json to_json(const NewtonFit& fit) {
  const auto& s = fit.summary;
  const bool ok = fit.ok();
  ordered_json j;
  j["model"] =
      "T(t) = T_amb + (T0 - T_amb) * exp(-k * (t - t0_reference_s)), t in s from the origin, T0 at t0_reference_s";
  j["origin_s"] = number_or_null(fit.origin_s);
  // Where T0 (and the covariance's delta_c) is: 0, the origin, unless the origin lies too far from the data.
  j["t0_reference_s"] = number_or_null(fit.t0_reference_s);
  j["t0_at_origin"] = fit.t0_at_origin();
  j["ok"] = ok;
  j["status"] = to_string(s.status);
  if (!ok) j["error"] = s.message;
  j["parameters"] = {{"k_per_s", to_json(fit.k_per_s, s.confidence)},
                     {"tau_s", to_json(fit.tau_s, s.confidence)},
                     {"T0_c", to_json(fit.t0_c, s.confidence)},
                     {"T_amb_c", to_json(fit.ambient_c, s.confidence)}};
  j["uncertainty"] = s.absolute_sigma ? "absolute, from the given measurement sigma"
                                      : "scaled by the residual variance s^2 = SSR/dof (scipy curve_fit default)";
  j["diagnostics"] = {{"points_used", s.points_used},
                      {"rejected_non_finite", s.rejected_non_finite},
                      {"duplicate_times_kept", s.duplicate_times},
                      {"parameters", s.parameters},
                      {"dof", s.dof},
                      {"iterations", s.iterations},
                      {"duration_s", number_or_null(fit.duration_s)},
                      {"residual_rms_c", number_or_null(ok ? s.residual_rms_c : NAN)},
                      {"residual_std_c", number_or_null(ok ? s.residual_std_c : NAN)},
                      {"lag1_autocorrelation", number_or_null(ok ? s.lag1_autocorrelation : NAN)},
                      {"record_time_constants", number_or_null(ok ? s.record_time_constants : NAN)},
                      {"outliers", s.outliers}};
  if (ok) j["diagnostics"]["t_critical"] = number_or_null(s.t_critical);
  if (ok && s.interval_dof) j["diagnostics"]["interval_dof"] = number_or_null(*s.interval_dof);
  // Only a fit with a known measurement σ has one; absent, not null, otherwise.
  if (s.reduced_chi_square) j["diagnostics"]["reduced_chi_square"] = number_or_null(*s.reduced_chi_square);
  write_covariance(fit, j);
  j["warnings"] = s.warnings;
  return j;
}

ordered_json to_json(const Agreement& a) {
  ordered_json j = {{"verdict", a.verdict}};
  j["k"] = nullptr;
  if (a.k) {
    j["k"] = {{"difference_per_s", number_or_null(a.k->difference_per_s)},
              {"std_error_per_s", number_or_null(a.k->std_error_per_s)},
              {"z", number_or_null(a.k->z)},
              {"relative_difference", number_or_null(a.k->relative_difference)},
              {"agree", a.k->agree}};
  }
  j["series"] = nullptr;
  if (a.series) {
    const auto& s = *a.series;
    j["series"] = {{"common_points", s.common_points},
                   {"overlap_start_s", number_or_null(s.overlap_start_s)},
                   {"overlap_end_s", number_or_null(s.overlap_end_s)},
                   {"rms_difference_c", number_or_null(s.rms_difference_c)},
                   {"bias_c", number_or_null(s.bias_c)},
                   {"difference_std_c", number_or_null(s.difference_std_c)},
                   {"limits_of_agreement_low_c", number_or_null(s.limits_of_agreement_low_c)},
                   {"limits_of_agreement_high_c", number_or_null(s.limits_of_agreement_high_c)},
                   {"rms_difference_as_read_c", number_or_null(s.rms_difference_as_read_c)},
                   {"bias_as_read_c", number_or_null(s.bias_as_read_c)},
                   {"paired_at", "the BOS frame times, the thermocouple interpolated there"}};
  }
  j["confidence"] = a.confidence;
  j["equivalence"] = a.curve ? to_json(*a.curve) : ordered_json(nullptr);
  j["lag"] = {{"source", a.lag.source},
              {"time_constant_s", number_or_null(a.lag.time_constant_s)},
              {"estimated_s", a.lag.estimated_s ? number_or_null(*a.lag.estimated_s) : ordered_json(nullptr)},
              {"std_error_s", number_or_null(a.lag.std_error_s)},
              {"model", "first order: the thermocouple compared as T + tau * dT/dt, dT/dt from its fit"}};
  return j;
}

}  // namespace bosfuse::fitting
