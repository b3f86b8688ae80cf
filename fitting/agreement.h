#pragma once
// How well two measurements of one cooling process agree, typically a
// thermocouple (a) and the BOS probe at its image position (b). Use
// compare_fits() once both series have been fitted with fit_newton().
//
// Like is compared with like. The thermocouple's first-order response lag
// (sensor_lag.h; its τ given, else estimated) is removed first, from its fit
// and its readings, so that the lag is not reported as disagreement. The
// series are paired at b's times (the BOS frames) with a interpolated there:
// RMS difference, Bland–Altman bias and 95% limits of agreement on as many
// pairs as there are frames in the overlap, as read and de-lagged.
//
// The verdict is an equivalence test of the whole curve, two one-sided
// tests (TOST, Schuirmann 1987) for each of k, T0 (at a's T0 time) and
// T_amb: equivalence at level α = 0.05 is shown when the difference's
// 1 − 2α = 90 % interval lies inside ±margin (each one-sided test rejects
// "beyond that side's margin" at α; a 95 % two-sided interval inside the
// margin tests at α = 0.025 and overstates the standard). The difference
// a − b gets that interval from the two fits' standard errors (the fits are independent:
// different sensors, different noise; within each fit the parameters'
// correlations are in its marginal standard errors) and, when given, each
// series' systematic standard uncertainty of that parameter (a Type-B
// budget propagated through its fit, fit_systematics.h: common to the
// whole series, so more frames do not reduce it; infinite degrees of
// freedom), added in squares, and is
//   agree         when the interval lies inside ±margin,
//   differ        when it lies wholly outside ±margin,
//   inconclusive  otherwise (the uncertainty or the difference straddles the
//                 margin: the data cannot tell).
// The curve's verdict is the worst of its parameters' (differ over
// inconclusive over agree): the curve agrees only when every parameter does,
// which is stricter than a joint (Mahalanobis) test and needs no assumption
// about how the two fits' parameters correlate with each other. With an
// estimated τ the T0 difference is what τ was estimated from, so T0 is shown
// but left out of the verdict. When b is not a temperature (a shift in px)
// only k is tested. Times of both series are in one time base; each series
// keeps its own origin, which compare_fits() accounts for. A systematic
// part that cannot be excluded therefore reads inconclusive, not differ,
// and the sentence says whether the random or the systematic part decided.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "fitting/fit_systematics.h"
#include "fitting/newton_fit.h"
#include "fitting/series.h"

namespace bosfuse::fitting {

enum class Verdict { kAgree, kDiffer, kInconclusive };
const char* to_string(Verdict verdict);  // "agree", "differ", "inconclusive"

struct AgreementOptions {
  double confidence = 0.95;           // of the limits of agreement and the k significance test
  // Level of each one-sided test of the equivalence (TOST): the verdict's
  // intervals are at 1 − 2α (0.90 for the standard α = 0.05).
  double equivalence_alpha = 0.05;
  std::size_t min_common_points = 3;  // fewer common times: no series statistics
  std::string label_a = "thermocouple";
  std::string label_b = "BOS probe";
  // Equivalence margins: |difference| a curve parameter may have and still agree.
  double margin_c = 1.0;            // T0 and T_amb, °C
  double margin_k_relative = 0.05;  // k, as a fraction of the two k's mean
  bool b_is_temperature = true;     // false (a shift in px): only k is compared
  // a's response time constant: given (the experiment file's time_constant_s),
  // or nullopt: estimated from the paired differences when estimate_lag, else
  // no lag is modelled.
  std::optional<double> a_time_constant_s;
  bool estimate_lag = true;
  // Systematic standard uncertainties (≥ 0) of each series' k, T0 and T_amb
  // (FitSystematics::combined); zero: none stated.
  ParameterShifts a_systematic, b_systematic;

  // Empty when usable, else the reason.
  std::string Validate() const;
};

// Statistics of the paired differences a − b at b's times within the overlap.
struct SeriesAgreement {
  std::size_t common_points = 0;  // b's samples in the overlap (Bland–Altman's n)
  double overlap_start_s = 0.0;   // in a's time base (relative to a's origin)
  double overlap_end_s = 0.0;
  double rms_difference_c = 0.0;            // a de-lagged when a lag is modelled
  double bias_c = 0.0;                      // mean of a − b
  double difference_std_c = 0.0;            // sample standard deviation of a − b
  double limits_of_agreement_low_c = 0.0;   // bias − z·sd (Bland–Altman)
  double limits_of_agreement_high_c = 0.0;  // bias + z·sd
  // The same two with a as read (no lag removed); equal to the above when no lag is modelled.
  double rms_difference_as_read_c = 0.0;
  double bias_as_read_c = 0.0;
};

struct KAgreement {
  double difference_per_s = 0.0;     // k_a − k_b
  double std_error_per_s = 0.0;      // sqrt(se_a² + se_b²)
  double z = 0.0;                    // difference / std_error
  double relative_difference = 0.0;  // difference / mean of the two k
  bool agree = false;                // |z| within the two-sided critical value (a significance test, not the verdict)
};

// One curve parameter's equivalence test.
struct ParameterAgreement {
  std::string name;           // "k_per_s", "T0_c", "T_amb_c"
  double difference = 0.0;    // a − b
  double std_error = 0.0;     // sqrt(random² + systematic²)
  double random_std_error = 0.0;      // sqrt(se_a² + se_b²), the fits' standard errors
  double systematic_std_error = 0.0;  // sqrt(sys_a² + sys_b²), the stated systematic parts
  double z = 0.0;             // difference / std_error
  double margin = 0.0;        // ± this is "the same"
  double critical = 0.0;      // normal, or Student t with the Welch–Satterthwaite dof of two scaled fits,
                              // one-sided at α (two-sided at 1 − 2α)
  double interval_low = 0.0;  // difference ∓ critical · std_error: the 1 − 2α interval
  double interval_high = 0.0;
  Verdict verdict = Verdict::kInconclusive;
  bool in_verdict = true;  // false: shown only (T0 with an estimated lag)
};

struct CurveAgreement {
  Verdict verdict = Verdict::kInconclusive;
  double alpha = 0.05;        // of each one-sided test (TOST)
  double confidence = 0.90;   // of the parameters' intervals: 1 − 2α
  // Of the parameters with the curve's verdict, the one whose interval
  // reaches furthest relative to its margin: the closest call for agree, the
  // clearest for differ.
  std::string deciding_parameter;
  std::vector<ParameterAgreement> parameters;  // k, then T0 and T_amb when b is a temperature

  const ParameterAgreement* deciding() const;
};

// The lag removed from a before comparing.
struct LagModel {
  std::string source = "none";        // "given", "estimated", "none"
  double time_constant_s = 0.0;       // applied (0 when none, or an estimate ≤ 0)
  std::optional<double> estimated_s;  // the estimate, whether applied or not
  double std_error_s = 0.0;           // of the estimate
};

struct Agreement {
  std::optional<KAgreement> k;            // nullopt when a fit failed
  std::optional<CurveAgreement> curve;    // nullopt when a fit failed
  std::optional<SeriesAgreement> series;  // nullopt when the series share too few common times
  LagModel lag;
  double confidence = 0.95;
  std::string verdict;  // plain sentences, beginning with the verdict

  std::string brief_report() const;
};

Agreement compare_fits(const NewtonFit& a, const NewtonFit& b, const CleanSeries& a_series, const CleanSeries& b_series,
                       const AgreementOptions& options = {});

// Paired-difference statistics only (no fits needed): a − b at b's times
// with a interpolated (the as-read fields equal the others).
std::optional<SeriesAgreement> compare_series(const CleanSeries& a, const CleanSeries& b, double confidence = 0.95,
                                              std::size_t min_common_points = 3);

}  // namespace bosfuse::fitting
