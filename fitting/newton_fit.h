#pragma once
// Newton's law of cooling fitted to one temperature series:
//
//     T(t) = T_amb + (T0 − T_amb) · exp(−k · (t − t₀)),   τ = 1 / k,
//
// with t in seconds from a chosen origin (by default the first sample) and
// T0 the temperature at t₀ = 0, the origin, unless it lies too far from the
// data (NewtonFit::t0_reference_s). Use
// fit_newton() for a thermocouple channel or a BOS probe series; the result
// carries k, τ, T0 and T_amb with standard errors and confidence intervals,
// and a NewtonFitSummary that says whether the numbers can be trusted and,
// when they cannot, why and what to change.
//
// Internally the parameters are log τ, ΔT = T0 − T_amb and T_amb, with t
// counted from the first sample whatever the origin, so the fit does not
// depend on where t = 0 lies: log τ keeps the time constant positive and
// makes its scale irrelevant to the solver, and ΔT decouples the amplitude
// from the ambient level. T0 is then reported at the origin, unless the
// origin lies so far from the data that T0 there would overflow or lose its
// digits: then T0 is the temperature at the first sample, and
// NewtonFit::t0_reference_s says so. A record rising
// towards a warmer ambient is the same law with ΔT < 0 and is fitted as
// such. Ambient can be free, fixed, or tied to a measured value by a
// Gaussian prior. Uncertainties come from ceres::Covariance; by default they
// are scaled by the residual variance s² = SSR / (n − p), the convention of
// scipy's curve_fit(absolute_sigma=False); when the measurement σ is known
// they are absolute and a reduced χ² tells whether σ was right.
// See docs/FITTING.md.

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "fitting/series.h"

namespace bosfuse::fitting {

struct AmbientModel {
  enum class Mode { kFree, kFixed, kPrior };
  Mode mode = Mode::kFree;
  double value_c = 0.0;  // kFixed: the value; kPrior: the measured mean
  double sigma_c = 0.0;  // kPrior: its standard uncertainty

  static AmbientModel free() { return {}; }
  static AmbientModel fixed(double value_c) { return {Mode::kFixed, value_c, 0.0}; }
  static AmbientModel prior(double value_c, double sigma_c) { return {Mode::kPrior, value_c, sigma_c}; }
};

// Robust loss against outliers: residuals beyond `scale_c` count linearly
// (Huber) or logarithmically (Cauchy) instead of quadratically.
struct RobustLoss {
  enum class Kind { kNone, kHuber, kCauchy };
  Kind kind = Kind::kNone;
  double scale_c = 1.0;

  static RobustLoss none() { return {}; }
  static RobustLoss huber(double scale_c) { return {Kind::kHuber, scale_c}; }
  static RobustLoss cauchy(double scale_c) { return {Kind::kCauchy, scale_c}; }
};

struct NewtonFitOptions {
  std::optional<double> origin_s;             // default: the earliest finite sample time
  AmbientModel ambient;                       // default: free
  RobustLoss loss;                            // default: plain least squares
  std::optional<double> measurement_sigma_c;  // known σ of every sample: absolute uncertainties and a χ² test
                                              // (a σ per sample: fit_newton's sigma_c or CleanSeries::sigma_c)
  double confidence = 0.95;                   // of the reported intervals
  // With a known σ whose scale was itself estimated from a fit's residuals
  // (a Birge ratio from n − p residuals): the intervals' critical value is
  // Student t at these degrees of freedom rather than normal.
  std::optional<double> interval_dof;
  int max_iterations = 200;
  // A free ambient is weakly identified when the record spans fewer time
  // constants than this; the fit then warns and suggests fixing it.
  double min_time_constants_for_free_ambient = 1.0;
  // |lag-1 residual autocorrelation| above this adds a warning that the
  // intervals are optimistic.
  double max_lag1_autocorrelation = 0.3;

  // Empty when the options are usable, else the reason they are not.
  std::string Validate() const;
};

enum class FitStatus {
  kOk,
  kInvalidOptions,
  kTooFewPoints,
  kNoTimeSpan,      // every sample at one instant
  kNoDecay,         // no exponential change resolved above the noise (flat record)
  kUnidentifiable,  // τ outside what the record's sampling can resolve
  kRankDeficient,   // covariance not computable: some combination of parameters is undetermined
  kNotConverged,
};

const char* to_string(FitStatus status);

// One fitted quantity: value, standard error and a two-sided interval at the
// options' confidence. k and τ have intervals computed in log τ (where the
// fit is nearly linear), so they are asymmetric and stay positive.
struct Estimate {
  double value = 0.0;
  double std_error = 0.0;
  double low = 0.0;
  double high = 0.0;
  bool fixed = false;  // held constant (fixed ambient): std_error 0, low = high = value
};

struct NewtonFitSummary {
  FitStatus status = FitStatus::kNotConverged;
  std::string message;                // the reason when status != kOk
  std::vector<std::string> warnings;  // usable fit, but read these
  std::size_t points_used = 0;
  std::size_t rejected_non_finite = 0;
  std::size_t duplicate_times = 0;  // kept, see series.h
  int parameters = 0;               // free parameters p
  double dof = 0.0;                 // n − p (+1 with an ambient prior)
  int iterations = 0;
  bool absolute_sigma = false;               // uncertainties from the known σ rather than scaled by s²
  double residual_rms_c = 0.0;               // of the data residuals, unweighted
  double residual_std_c = 0.0;               // s = sqrt(SSR / dof): the noise level the fit implies
  std::optional<double> reduced_chi_square;  // only with a known σ
  double lag1_autocorrelation = 0.0;
  double record_time_constants = 0.0;  // duration / τ
  double confidence = 0.95;
  double t_critical = 0.0;   // Student t (scaled) or normal (absolute) critical value of the intervals
  // The dof of the variances with an absolute σ whose scale was estimated
  // (NewtonFitOptions::interval_dof): t_critical is Student t at it.
  std::optional<double> interval_dof;
  std::size_t outliers = 0;  // residuals beyond 5 robust σ (1.4826 × median |residual|)

  bool ok() const { return status == FitStatus::kOk; }
  // A few lines a person can read: status, numbers, warnings.
  std::string brief_report() const;
};

// Covariance of the parameters in the order (log τ, ΔT = T0 − T_amb in °C,
// T_amb in °C) — ΔT at the time T0 is given, NewtonFit::t0_reference_s — in
// the convention of the fit's uncertainties (scaled by s² unless
// summary.absolute_sigma). With a fixed ambient the T_amb row and column are
// zero.
using ParameterCovariance = std::array<std::array<double, 3>, 3>;

// T0 is given at the origin while the curve's amplitude T0 − T_amb there is
// within this factor of its amplitude at the first sample (|k · first
// sample's t| ≤ ln 1e6 ≈ 13.8): further out, T0 would be a number far beyond
// anything measured whose difference from T_amb rounding eats (the origin
// long after the data), or that overflows (long before).
inline constexpr double kMaxT0Extrapolation = 1e6;

struct NewtonFit {
  double origin_s = 0.0;  // absolute time of t = 0, in the caller's time base
  // The time T0 is given at, in s from the origin: 0 (T0 is the temperature
  // at the origin) unless the origin lies too far from the data
  // (kMaxT0Extrapolation); then the first sample's time.
  double t0_reference_s = 0.0;
  double duration_s = 0.0;
  Estimate k_per_s;
  Estimate tau_s;
  Estimate t0_c;
  Estimate ambient_c;
  NewtonFitSummary summary;
  std::vector<double> residuals_c;  // data − model, in time order of the cleaned series
  // Kept so that a derived quantity (the curve at a time) gets its
  // uncertainty with the parameters' correlations, which the four Estimates
  // alone lose. nullopt for a failed fit and for a stored fit written before
  // the covariance was.
  std::optional<ParameterCovariance> covariance;

  bool ok() const { return summary.ok(); }
  bool t0_at_origin() const { return t0_reference_s == 0.0; }
  // The fitted curve at an absolute time (same time base as the input).
  double temperature_at(double time_s) const;
  // Half-width of the confidence interval (at summary.confidence) of the
  // fitted curve at an absolute time, by the delta method: t_critical ·
  // sqrt(g·C·gᵀ) with g the gradient of T(t) in the parameters. It is the
  // band of the curve, not a prediction band for new samples (no noise
  // term). ≥ 0 and finite for an ok fit within its record, 0 for a noiseless
  // one; NaN when the fit is not ok or has no covariance.
  double temperature_half_width_at(double time_s) const;
  // Parameters with intervals, then the summary.
  std::string brief_report() const;
};

// Fits Newton's law. Never throws for bad data: a fit that cannot be
// trusted has summary.status != kOk, a reason in summary.message, and NaN
// parameters. Throws std::invalid_argument only when the spans differ in
// length.
NewtonFit fit_newton(std::span<const double> time_s, std::span<const double> temperature_c,
                     const NewtonFitOptions& options = {});

// Weighted by each sample's standard uncertainty σ_i (sigma_c, in the order
// of the samples): residuals count as (T_i − T(t_i))/σ_i, uncertainties are
// absolute (the covariance of the weighted problem, not scaled by s²) and
// reduced χ² = Σ(r_i/σ_i)²/dof tells whether the σ_i were right. A sample
// whose σ is NaN or infinite is left out like a NaN temperature; throws
// std::invalid_argument when the spans differ in length or a σ is ≤ 0.
// options.measurement_sigma_c must then be unset (kInvalidOptions).
NewtonFit fit_newton(std::span<const double> time_s, std::span<const double> temperature_c,
                     std::span<const double> sigma_c, const NewtonFitOptions& options = {});

// The same on an already cleaned series (its origin is kept), weighted by
// its sigma_c when it has them.
NewtonFit fit_newton(const CleanSeries& series, const NewtonFitOptions& options = {});

}  // namespace bosfuse::fitting
