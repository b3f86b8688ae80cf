#include "fitting/agreement.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include "fitting/sensor_lag.h"
#include "fitting/student_t.h"

namespace bosfuse::fitting {
namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

template <typename... Numbers>
std::string format_number(const char* pattern, Numbers... numbers) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, static_cast<double>(numbers)...);
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

// The degrees of freedom of a fit's variances: infinite when they are
// absolute (from a known σ) or the fit states none; a known σ whose scale
// was estimated from the residuals has the dof of that estimate.
double variance_dof(const NewtonFit& fit) {
  if (fit.summary.absolute_sigma && fit.summary.interval_dof) return *fit.summary.interval_dof;
  return fit.summary.absolute_sigma || !(fit.summary.dof > 0) ? INFINITY : fit.summary.dof;
}

// Welch–Satterthwaite: the dof of va + vb + vs, each with its own dof (vs,
// a Type-B variance, with infinite dof).
double critical_of_sum(double va, double dof_a, double vb, double dof_b, double vs, double confidence) {
  const double denominator =
      (std::isfinite(dof_a) ? va * va / dof_a : 0.0) + (std::isfinite(dof_b) ? vb * vb / dof_b : 0.0);
  if (!(denominator > 0)) return normal_critical(confidence);
  return student_t_critical((va + vb + vs) * (va + vb + vs) / denominator, confidence);
}

// One parameter of a and b, its value and random standard error from each fit.
struct Measured {
  double value, std_error, dof;
};

Verdict equivalence(double low, double high, double margin) {
  if (!(std::isfinite(low) && std::isfinite(high))) return Verdict::kInconclusive;
  if (low >= -margin && high <= margin) return Verdict::kAgree;
  if (low > margin || high < -margin) return Verdict::kDiffer;
  return Verdict::kInconclusive;
}

ParameterAgreement test_parameter(std::string name, Measured a, Measured b, double systematic, double margin,
                                  double confidence) {
  ParameterAgreement p;
  p.name = std::move(name);
  p.difference = a.value - b.value;
  p.random_std_error = std::hypot(a.std_error, b.std_error);
  p.systematic_std_error = systematic;
  p.std_error = std::hypot(p.random_std_error, systematic);
  p.margin = margin;
  p.z =
      p.std_error > 0 ? p.difference / p.std_error : (p.difference == 0 ? 0.0 : std::copysign(INFINITY, p.difference));
  p.critical = critical_of_sum(a.std_error * a.std_error, a.dof, b.std_error * b.std_error, b.dof,
                               systematic * systematic, confidence);
  p.interval_low = p.difference - p.critical * p.std_error;
  p.interval_high = p.difference + p.critical * p.std_error;
  p.verdict = equivalence(p.interval_low, p.interval_high, margin);
  return p;
}

// b's T0 where a gives its own: b's curve there, with its band's standard
// error, unless b gives T0 at that very time.
std::pair<double, double> t0_at(const NewtonFit& b, double time_s) {
  if (b.origin_s + b.t0_reference_s == time_s) return {b.t0_c.value, b.t0_c.std_error};
  const double half_width = b.temperature_half_width_at(time_s);
  return {b.temperature_at(time_s), b.summary.t_critical > 0 ? half_width / b.summary.t_critical : kNoValue};
}

int severity(Verdict v) { return v == Verdict::kDiffer ? 2 : v == Verdict::kInconclusive ? 1 : 0; }

double reach(const ParameterAgreement& p) {
  return std::max(std::abs(p.interval_low), std::abs(p.interval_high)) / p.margin;
}

CurveAgreement compare_curves(const NewtonFit& a, const NewtonFit& b, const AgreementOptions& o, bool lag_estimated) {
  CurveAgreement curve;
  curve.alpha = o.equivalence_alpha;
  curve.confidence = 1.0 - 2.0 * o.equivalence_alpha;
  const double level = curve.confidence;
  const double dof_a = variance_dof(a), dof_b = variance_dof(b);
  const ParameterShifts &sa = o.a_systematic, &sb = o.b_systematic;
  const double k_margin = o.margin_k_relative * std::abs(0.5 * (a.k_per_s.value + b.k_per_s.value));
  curve.parameters.push_back(test_parameter("k_per_s", {a.k_per_s.value, a.k_per_s.std_error, dof_a},
                                            {b.k_per_s.value, b.k_per_s.std_error, dof_b},
                                            std::hypot(sa.k_per_s, sb.k_per_s), k_margin, level));
  if (o.b_is_temperature) {
    // b's T0 systematic is its fit's at its own T0 time, which is a's when
    // both are fitted from one origin (as `process` fits them).
    const auto [b_t0, b_t0_se] = t0_at(b, a.origin_s + a.t0_reference_s);
    curve.parameters.push_back(test_parameter("T0_c", {a.t0_c.value, a.t0_c.std_error, dof_a}, {b_t0, b_t0_se, dof_b},
                                              std::hypot(sa.t0_c, sb.t0_c), o.margin_c, level));
    curve.parameters.back().in_verdict = !lag_estimated;
    curve.parameters.push_back(test_parameter("T_amb_c", {a.ambient_c.value, a.ambient_c.std_error, dof_a},
                                              {b.ambient_c.value, b.ambient_c.std_error, dof_b},
                                              std::hypot(sa.t_amb_c, sb.t_amb_c), o.margin_c, level));
  }
  curve.verdict = Verdict::kAgree;
  for (const auto& p : curve.parameters) {
    if (p.in_verdict && severity(p.verdict) > severity(curve.verdict)) curve.verdict = p.verdict;
  }
  double furthest = -1;
  for (const auto& p : curve.parameters) {
    if (p.in_verdict && p.verdict == curve.verdict && reach(p) > furthest) {
      furthest = reach(p);
      curve.deciding_parameter = p.name;
    }
  }
  return curve;
}

// The name, unit and number format of a parameter in sentences.
struct Wording {
  const char* name;
  const char* unit;
};

Wording wording(const std::string& parameter) {
  if (parameter == "k_per_s") return {"k", "1/s"};
  if (parameter == "T0_c") return {"T0", "°C"};
  return {"T_amb", "°C"};
}

std::string parameter_clause(const ParameterAgreement& p) {
  const Wording w = wording(p.name);
  std::string text = std::string(w.name) + " " + to_string(p.verdict) +
                     format_number(" (Δ = %.3g ± %.2g ", p.difference, p.std_error) + w.unit +
                     format_number(", z = %.2f, margin ±%.2g ", p.z, p.margin) + w.unit +
                     (p.systematic_std_error > 0
                          ? format_number("; random ± %.2g, systematic ± %.2g", p.random_std_error,
                                          p.systematic_std_error)
                          : std::string()) +
                     ")";
  return p.in_verdict ? text : text + " [not in the verdict: the lag was estimated from it]";
}

// Which part of the deciding parameter's uncertainty is the larger, when a
// systematic part was stated: more frames reduce only the random one.
std::string dominant_part(const ParameterAgreement* d) {
  if (!d || !(d->systematic_std_error > 0)) return {};
  return d->systematic_std_error > d->random_std_error
             ? "; the systematic part (the set-up's Type-B budget) dominates, which more frames do not reduce"
             : "; the random part dominates, which more frames reduce";
}

std::string curve_sentence(const CurveAgreement& curve, const AgreementOptions& o) {
  const std::string confidence = format_number("%.0f%%", 100.0 * curve.confidence);
  const std::string level = format_number("two one-sided tests at α = %.3g", curve.alpha);
  const std::string tested = o.b_is_temperature ? "the whole curve (k, T0, T_amb)" : "k (the probe is not in °C)";
  const ParameterAgreement* d = curve.deciding();
  std::string text;
  switch (curve.verdict) {
    case Verdict::kAgree:
      text = "Agree: " + tested + " of " + o.label_a + " and " + o.label_b + " within the margins (" + confidence +
             " intervals inside ±margin: " + level + ").";
      break;
    case Verdict::kDiffer:
      text = "Differ: " + std::string(wording(d->name).name) + " of " + o.label_a + " and " + o.label_b +
             " differ beyond the margin (its " + confidence + " interval lies wholly outside ±margin; " + level + ").";
      break;
    case Verdict::kInconclusive:
      text = "Inconclusive: the uncertainty of " + std::string(d ? wording(d->name).name : "the curve") +
             " is too large to tell whether " + o.label_a + " and " + o.label_b + " agree (its " + confidence +
             " interval reaches past ±margin; " + level + ")" + dominant_part(d) + ".";
      break;
  }
  text += " ";
  for (std::size_t i = 0; i < curve.parameters.size(); ++i) {
    text += (i ? "; " : "") + parameter_clause(curve.parameters[i]);
  }
  return text + ". ";
}

std::string lag_sentence(const LagModel& lag) {
  if (lag.source == "given") {
    return format_number(
        "The thermocouple's response lag τ = %.3g s (given) is removed: it is compared de-lagged, "
        "T + τ·dT/dt. ",
        lag.time_constant_s);
  }
  if (lag.source == "estimated") {
    return format_number(
        "The thermocouple's response lag, estimated from the paired differences as τ = %.3g ± %.2g s "
        "(it also absorbs any difference in amplitude), is removed. ",
        lag.time_constant_s, lag.std_error_s);
  }
  if (lag.estimated_s) {
    return format_number(
        "No lag is removed: the estimate from the paired differences, τ = %.3g ± %.2g s, is not "
        "resolved above zero. ",
        *lag.estimated_s, lag.std_error_s);
  }
  return {};
}

std::string series_sentence(const SeriesAgreement& s, const AgreementOptions& o, bool delagged) {
  std::string text = format_number("On %.0f BOS frame times the temperatures differ by %.3g °C RMS",
                                   static_cast<double>(s.common_points), s.rms_difference_c);
  if (delagged) text += format_number(" (%.3g °C as read, with the lag)", s.rms_difference_as_read_c);
  return text + format_number("; bias %.3g °C, ", s.bias_c) +
         format_number("%.0f%% limits of agreement [%.3g, %.3g] °C.", 100.0 * o.confidence, s.limits_of_agreement_low_c,
                       s.limits_of_agreement_high_c);
}

std::string failed_fit_sentence(const NewtonFit& a, const NewtonFit& b, const AgreementOptions& o) {
  std::string text = "Inconclusive: the curves cannot be compared:";
  if (!a.ok()) text += " the " + o.label_a + " fit failed (" + a.summary.message + ")";
  if (!a.ok() && !b.ok()) text += ";";
  if (!b.ok()) text += " the " + o.label_b + " fit failed (" + b.summary.message + ")";
  return text + ". ";
}

LagModel lag_of(const NewtonFit& a, const NewtonFit& b, const CleanSeries& a_series, const CleanSeries& b_series,
                const AgreementOptions& o) {
  LagModel lag;
  if (o.a_time_constant_s) {
    lag.source = "given";
    lag.time_constant_s = *o.a_time_constant_s;
    return lag;
  }
  if (!o.estimate_lag || !o.b_is_temperature || !b.ok()) return lag;
  const auto estimate = estimate_lag(a_series, a, b_series);
  if (!estimate || !std::isfinite(estimate->time_constant_s)) return lag;
  lag.estimated_s = estimate->time_constant_s;
  lag.std_error_s = estimate->std_error_s;
  // Only a lag resolved above the noise of the differences is removed (noise
  // alone gives a τ of either sign), and one that would leave nothing of the
  // curve (kτ ≥ 1) is no lag either.
  const double resolved_s = estimate->time_constant_s - normal_critical(o.confidence) * estimate->std_error_s;
  if (resolved_s > 0 && a.k_per_s.value * estimate->time_constant_s < 1.0) {
    lag.source = "estimated";
    lag.time_constant_s = estimate->time_constant_s;
  }
  return lag;
}

}  // namespace

const char* to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::kAgree:
      return "agree";
    case Verdict::kDiffer:
      return "differ";
    case Verdict::kInconclusive:
      return "inconclusive";
  }
  return "inconclusive";
}

const ParameterAgreement* CurveAgreement::deciding() const {
  for (const auto& p : parameters) {
    if (p.name == deciding_parameter) return &p;
  }
  return nullptr;
}

std::string AgreementOptions::Validate() const {
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must lie strictly between 0 and 1";
  if (!(equivalence_alpha > 0.0 && equivalence_alpha < 0.5)) {
    return "the equivalence test's level alpha must lie strictly between 0 and 0.5";
  }
  if (min_common_points < 2) return "at least 2 common points are needed for a spread";
  if (!(margin_c > 0.0 && std::isfinite(margin_c))) return "the temperature margin must be positive and finite";
  if (!(margin_k_relative > 0.0 && std::isfinite(margin_k_relative))) {
    return "the relative margin of k must be positive and finite";
  }
  if (a_time_constant_s && !(*a_time_constant_s >= 0.0 && std::isfinite(*a_time_constant_s))) {
    return "the thermocouple's time constant must be finite and not negative";
  }
  for (const ParameterShifts* u : {&a_systematic, &b_systematic}) {
    for (double value : {u->k_per_s, u->t0_c, u->t_amb_c}) {
      if (!(value >= 0.0 && std::isfinite(value))) return "a systematic uncertainty must be finite and not negative";
    }
  }
  return {};
}

std::optional<SeriesAgreement> compare_series(const CleanSeries& a, const CleanSeries& b, double confidence,
                                              std::size_t min_common_points) {
  if (a.size() == 0 || b.size() == 0) return std::nullopt;
  const double shift_s = b.origin_s - a.origin_s;  // b's relative time + shift = a's relative time
  std::vector<double> differences;
  SeriesAgreement s;
  s.overlap_start_s = std::max(a.time_s.front(), b.time_s.front() + shift_s);
  s.overlap_end_s = std::min(a.time_s.back(), b.time_s.back() + shift_s);
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (const auto reading = interpolate(a, b.time_s[i] + shift_s))
      differences.push_back(*reading - b.temperature_c[i]);
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
  s.rms_difference_as_read_c = s.rms_difference_c;
  s.bias_as_read_c = s.bias_c;
  return s;
}

Agreement compare_fits(const NewtonFit& a, const NewtonFit& b, const CleanSeries& a_series, const CleanSeries& b_series,
                       const AgreementOptions& options) {
  if (auto reason = options.Validate(); !reason.empty()) throw std::invalid_argument(reason);
  Agreement result;
  result.confidence = options.confidence;
  result.lag = a.ok() ? lag_of(a, b, a_series, b_series, options) : LagModel{};
  const double tau_s = result.lag.time_constant_s;
  const NewtonFit a_delagged = delagged(a, tau_s);
  if (a_delagged.ok() && b.ok()) {
    result.k = compare_k(a_delagged.k_per_s, b.k_per_s, normal_critical(options.confidence));
    result.curve = compare_curves(a_delagged, b, options, result.lag.source == "estimated");
    result.verdict = curve_sentence(*result.curve, options);
  } else {
    result.verdict = failed_fit_sentence(a_delagged, b, options);
  }
  result.verdict += lag_sentence(result.lag);
  if (options.b_is_temperature) {
    result.series =
        compare_series(delagged(a_series, a, tau_s), b_series, options.confidence, options.min_common_points);
    if (const auto as_read = compare_series(a_series, b_series, options.confidence, options.min_common_points);
        result.series && as_read) {
      result.series->rms_difference_as_read_c = as_read->rms_difference_c;
      result.series->bias_as_read_c = as_read->bias_c;
    }
  }
  result.verdict.append(result.series ? series_sentence(*result.series, options, tau_s > 0)
                                      : "The temperature series share too few common times to compare them directly.");
  return result;
}

std::string Agreement::brief_report() const {
  std::string text = verdict + "\n";
  if (curve) {
    for (const auto& p : curve->parameters) {
      const Wording w = wording(p.name);
      text += std::string("  Δ") + w.name + format_number(" = %.4g ± %.2g ", p.difference, p.std_error) + w.unit +
              format_number(", z = %.2f, %.0f%% interval [%.4g, %.4g] ", p.z, 100.0 * curve->confidence, p.interval_low,
                            p.interval_high) +
              w.unit + format_number(" against ±%.3g ", p.margin) + w.unit + ": " + to_string(p.verdict) +
              (p.in_verdict ? "\n" : " (not in the verdict)\n");
    }
  }
  if (series) {
    text +=
        format_number("  Bland–Altman n = %.0f: RMS difference %.3g °C (as read %.3g °C), bias %.3g °C, sd %.3g °C\n",
                      static_cast<double>(series->common_points), series->rms_difference_c,
                      series->rms_difference_as_read_c, series->bias_c, series->difference_std_c);
  }
  return text;
}

}  // namespace bosfuse::fitting
