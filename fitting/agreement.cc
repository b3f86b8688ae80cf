#include "fitting/agreement.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "fitting/student_t.h"

namespace bosfuse::fitting {
namespace {

std::string format_number(const char* pattern, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, a, b, c, d);
  return text;
}

KAgreement compare_k(const Estimate& a, const Estimate& b, double critical) {
  KAgreement k;
  k.difference_per_s = a.value - b.value;
  k.std_error_per_s = std::hypot(a.std_error, b.std_error);
  k.z = k.std_error_per_s > 0 ? k.difference_per_s / k.std_error_per_s
                              : (k.difference_per_s == 0 ? 0.0 : std::copysign(INFINITY, k.difference_per_s));
  k.relative_difference = k.difference_per_s / (0.5 * (a.value + b.value));
  k.agree = std::abs(k.z) <= critical;
  return k;
}

std::string k_sentence(const KAgreement& k, const NewtonFit& a, const NewtonFit& b, const AgreementOptions& o) {
  const std::string values = o.label_a + format_number(" k = %.4g ± %.2g 1/s, ", a.k_per_s.value, a.k_per_s.std_error) +
                             o.label_b + format_number(" k = %.4g ± %.2g 1/s", b.k_per_s.value, b.k_per_s.std_error);
  if (k.agree) {
    return "k agree within uncertainty (" + values +
           format_number("; difference %.2g ± %.2g 1/s, z = %.2f). ", k.difference_per_s, k.std_error_per_s, k.z);
  }
  return format_number("k differ by %.2g 1/s (%.1f%% of their mean, z = %.1f), more than their uncertainties explain (",
                       k.difference_per_s, 100.0 * k.relative_difference, k.z) +
         values + "). ";
}

std::string series_sentence(const SeriesAgreement& s, const AgreementOptions& o) {
  return format_number("On %.0f common times the temperatures differ by %.3g °C RMS; bias %.3g °C, ",
                       static_cast<double>(s.common_points), s.rms_difference_c, s.bias_c) +
         format_number("%.0f%% limits of agreement [%.3g, %.3g] °C.", 100.0 * o.confidence, s.limits_of_agreement_low_c,
                       s.limits_of_agreement_high_c);
}

std::string failed_fit_sentence(const NewtonFit& a, const NewtonFit& b, const AgreementOptions& o) {
  std::string text = "k cannot be compared:";
  if (!a.ok()) text += " the " + o.label_a + " fit failed (" + a.summary.message + ")";
  if (!a.ok() && !b.ok()) text += ";";
  if (!b.ok()) text += " the " + o.label_b + " fit failed (" + b.summary.message + ")";
  return text + ". ";
}

}  // namespace

std::string AgreementOptions::invalid_reason() const {
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must lie strictly between 0 and 1";
  if (min_common_points < 2) return "at least 2 common points are needed for a spread";
  return {};
}

std::optional<SeriesAgreement> compare_series(const CleanSeries& a, const CleanSeries& b, double confidence,
                                              std::size_t min_common_points) {
  if (a.size() == 0 || b.size() == 0) return std::nullopt;
  const double shift_s = a.origin_s - b.origin_s;  // a's relative time + shift = b's relative time
  std::vector<double> differences;
  SeriesAgreement s;
  s.overlap_start_s = std::max(a.time_s.front(), b.time_s.front() - shift_s);
  s.overlap_end_s = std::min(a.time_s.back(), b.time_s.back() - shift_s);
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (const auto other = interpolate(b, a.time_s[i] + shift_s)) differences.push_back(a.temperature_c[i] - *other);
  }
  const std::size_t n = differences.size();
  if (n < std::max<std::size_t>(2, min_common_points)) return std::nullopt;
  double sum = 0, sum_squares = 0;
  for (double d : differences) {
    sum += d;
    sum_squares += d * d;
  }
  s.common_points = n;
  s.bias_c = sum / static_cast<double>(n);
  s.rms_difference_c = std::sqrt(sum_squares / static_cast<double>(n));
  double spread = 0;
  for (double d : differences) spread += (d - s.bias_c) * (d - s.bias_c);
  s.difference_std_c = std::sqrt(spread / static_cast<double>(n - 1));
  const double z = normal_critical(confidence);
  s.limits_of_agreement_low_c = s.bias_c - z * s.difference_std_c;
  s.limits_of_agreement_high_c = s.bias_c + z * s.difference_std_c;
  return s;
}

Agreement compare_fits(const NewtonFit& a, const NewtonFit& b, const CleanSeries& a_series, const CleanSeries& b_series,
                       const AgreementOptions& options) {
  if (auto reason = options.invalid_reason(); !reason.empty()) throw std::invalid_argument(reason);
  Agreement result;
  if (a.ok() && b.ok()) {
    result.k = compare_k(a.k_per_s, b.k_per_s, normal_critical(options.confidence));
    result.verdict = k_sentence(*result.k, a, b, options);
  } else {
    result.verdict = failed_fit_sentence(a, b, options);
  }
  result.series = compare_series(a_series, b_series, options.confidence, options.min_common_points);
  result.verdict.append(result.series ? series_sentence(*result.series, options)
                                      : "The temperature series share too few common times to compare them directly.");
  return result;
}

std::string Agreement::brief_report() const {
  std::string text = verdict + "\n";
  if (k) {
    text += format_number("  Δk = %.4g ± %.2g 1/s, z = %.2f", k->difference_per_s, k->std_error_per_s, k->z) +
            (k->agree ? " (agree)\n" : " (differ)\n");
  }
  if (series) {
    text += format_number("  RMS difference %.3g °C on %.0f common times, bias %.3g °C, sd %.3g °C\n",
                          series->rms_difference_c, static_cast<double>(series->common_points), series->bias_c,
                          series->difference_std_c);
  }
  return text;
}

}  // namespace bosfuse::fitting
