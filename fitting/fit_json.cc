#include "fitting/fit_json.h"

#include <cmath>

namespace bosfuse::fitting {
namespace {

using nlohmann::ordered_json;

ordered_json number_or_null(double value) { return std::isfinite(value) ? ordered_json(value) : ordered_json(nullptr); }

}  // namespace

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
  j["model"] = "T(t) = T_amb + (T0 - T_amb) * exp(-k * t), t in s from the origin";
  j["origin_s"] = number_or_null(fit.origin_s);
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
                      {"reduced_chi_square", number_or_null(s.reduced_chi_square.value_or(NAN))},
                      {"lag1_autocorrelation", number_or_null(ok ? s.lag1_autocorrelation : NAN)},
                      {"record_time_constants", number_or_null(ok ? s.record_time_constants : NAN)},
                      {"outliers", s.outliers}};
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
                   {"limits_of_agreement_high_c", number_or_null(s.limits_of_agreement_high_c)}};
  }
  return j;
}

}  // namespace bosfuse::fitting
