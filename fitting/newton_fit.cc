#include "fitting/newton_fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <utility>

#include "fitting/student_t.h"
#include "fitting/uncertainty_digits.h"

namespace bosfuse::fitting {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxStartSamples = 1000;  // the start-value scan runs on every n/1000-th sample
constexpr int kStartGridSize = 121;
constexpr std::size_t kSamplesPerResidualBlock = 64;
constexpr double kStartGridDecades = 3.0;      // τ from duration·1e-3 to duration·1e3
constexpr double kTauBoundFactor = 1e6;        // the solver keeps τ within duration·[1e-6, 1e6]
constexpr double kOutlierRobustSigmas = 5.0;   // beyond this many robust σ a residual counts as an outlier
constexpr double kLongestResolvableTau = 1e3;  // with free ambient, τ beyond 1000 durations is a straight line

std::string format(const char* pattern, ...) {
  char text[512];
  va_list args;
  va_start(args, pattern);
  std::vsnprintf(text, sizeof text, pattern, args);
  va_end(args);
  return text;
}

// Residuals (model − measured) / σ_i of a run of consecutive samples, with
// analytic derivatives in (log τ, ΔT, T_amb). Without a robust loss the
// samples go to Ceres in chunks, which cuts its per-block overhead; a robust
// loss acts on a block's whole squared norm, so it gets one sample per block.
class NewtonResidualChunk final : public ceres::CostFunction {
 public:
  NewtonResidualChunk(const double* t_s, const double* temperature_c, const double* inverse_sigma, int count)
      : t_s_(t_s), temperature_c_(temperature_c), inverse_sigma_(inverse_sigma) {
    set_num_residuals(count);
    *mutable_parameter_block_sizes() = {1, 1, 1};
  }

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const double k = std::exp(-p[0][0]);
    const double delta = p[1][0];
    const double ambient = p[2][0];
    for (int i = 0; i < num_residuals(); ++i) {
      const double decay = std::exp(-k * t_s_[i]);
      const double w = inverse_sigma_[i];
      residuals[i] = (ambient + delta * decay - temperature_c_[i]) * w;
      if (jacobians == nullptr) continue;
      if (jacobians[0]) jacobians[0][i] = delta * decay * k * t_s_[i] * w;
      if (jacobians[1]) jacobians[1][i] = decay * w;
      if (jacobians[2]) jacobians[2][i] = w;
    }
    return true;
  }

 private:
  const double* t_s_;
  const double* temperature_c_;
  const double* inverse_sigma_;  // per sample
};

// The measured ambient as one more observation of T_amb.
class AmbientPriorResidual final : public ceres::SizedCostFunction<1, 1> {
 public:
  AmbientPriorResidual(double value_c, double sigma_c) : value_c_(value_c), sigma_c_(sigma_c) {}
  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    residual[0] = (p[0][0] - value_c_) / sigma_c_;
    if (jacobians && jacobians[0]) jacobians[0][0] = 1.0 / sigma_c_;
    return true;
  }

 private:
  double value_c_;
  double sigma_c_;
};

struct Parameters {
  double log_tau = 0.0;
  double delta_c = 0.0;
  double ambient_c = 0.0;
};

struct StartValues {
  Parameters parameters;
  double rms_c = 0.0;
};

// Amplitude and ambient for one τ by linear least squares (the model is
// linear in them once τ is fixed); returns the mean squared residual. The
// sums are taken about the mean temperature so the closed-form residual
// does not cancel catastrophically.
double solve_linear_part(const CleanSeries& s, std::size_t stride, double tau_s, bool ambient_free, double fixed_c,
                         double mean_c, Parameters& out) {
  double n = 0, se = 0, see = 0, sy = 0, sey = 0, syy = 0;
  const double offset_c = ambient_free ? mean_c : fixed_c;
  for (std::size_t i = 0; i < s.size(); i += stride) {
    const double e = std::exp(-s.time_s[i] / tau_s);
    const double y = s.temperature_c[i] - offset_c;
    n += 1;
    se += e;
    see += e * e;
    sy += y;
    sey += e * y;
    syy += y * y;
  }
  out.log_tau = std::log(tau_s);
  double a = 0.0;  // ambient relative to offset_c
  if (ambient_free) {
    const double det = n * see - se * se;
    if (!(det > 1e-12 * n * see)) return std::numeric_limits<double>::infinity();  // e ≈ const: a, ΔT inseparable
    a = (see * sy - se * sey) / det;
    out.delta_c = (n * sey - se * sy) / det;
  } else {
    out.delta_c = see > 0 ? sey / see : 0.0;
  }
  out.ambient_c = offset_c + a;
  const double d = out.delta_c;
  const double ssr = syy - 2 * a * sy - 2 * d * sey + n * a * a + 2 * a * d * se + d * d * see;
  return std::max(0.0, ssr) / n;
}

// Start values by a log-spaced scan of τ with the linear parameters solved
// exactly at each step (variable projection): it needs no guess from the
// user and cannot be fooled into a local minimum the way a three-point
// estimate can be by noise.
StartValues start_values(const CleanSeries& s, const AmbientModel& ambient) {
  const std::size_t stride = std::max<std::size_t>(1, s.size() / kMaxStartSamples);
  const bool free = ambient.mode != AmbientModel::Mode::kFixed;
  double mean_c = 0;
  for (double v : s.temperature_c) mean_c += v / static_cast<double>(s.size());
  StartValues best;
  double best_mean_square = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kStartGridSize; ++i) {
    const double decades = kStartGridDecades * (2.0 * i / (kStartGridSize - 1) - 1.0);
    Parameters candidate;
    const double mean_square = solve_linear_part(s, stride, s.duration_s() * std::pow(10.0, decades), free,
                                                 ambient.value_c, mean_c, candidate);
    if (mean_square < best_mean_square) {
      best_mean_square = mean_square;
      best.parameters = candidate;
    }
  }
  if (!std::isfinite(best_mean_square)) {  // no τ separated ambient from amplitude: hold ambient at a guess
    const double guess_c = ambient.mode == AmbientModel::Mode::kPrior ? ambient.value_c : s.temperature_c.back();
    best_mean_square = solve_linear_part(s, stride, s.duration_s(), false, guess_c, mean_c, best.parameters);
  }
  best.rms_c = std::sqrt(best_mean_square);
  return best;
}

int free_parameter_count(const AmbientModel& ambient) { return ambient.mode == AmbientModel::Mode::kFixed ? 2 : 3; }

double degrees_of_freedom(std::size_t n, const AmbientModel& ambient) {
  const double prior_observations = ambient.mode == AmbientModel::Mode::kPrior ? 1.0 : 0.0;
  return static_cast<double>(n) + prior_observations - free_parameter_count(ambient);
}

std::unique_ptr<ceres::LossFunction> make_loss(const RobustLoss& loss, double sigma_w_c) {
  const double scale = loss.scale_c / sigma_w_c;  // residuals are in units of σ_w
  switch (loss.kind) {
    case RobustLoss::Kind::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale);
    case RobustLoss::Kind::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale);
    case RobustLoss::Kind::kNone:
      break;
  }
  return nullptr;
}

// One Ceres problem over the cleaned series, with residuals weighted by
// each sample's σ when the series has them, else by one σ_w (which is also
// the scale a robust loss's °C are turned into residual units by).
class NewtonProblem {
 public:
  NewtonProblem(const CleanSeries& s, const NewtonFitOptions& options, const Parameters& start, double sigma_w_c)
      : parameters_(start),
        loss_(make_loss(options.loss, sigma_w_c)),
        inverse_sigma_(s.size(), 1.0 / sigma_w_c),
        sigma_w_c_(sigma_w_c) {
    for (std::size_t i = 0; i < s.sigma_c.size(); ++i) inverse_sigma_[i] = 1.0 / s.sigma_c[i];
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one loss shared by every block
    problem_ = std::make_unique<ceres::Problem>(problem_options);
    const std::size_t chunk = loss_ ? 1 : kSamplesPerResidualBlock;
    for (std::size_t i = 0; i < s.size(); i += chunk) {
      const int count = static_cast<int>(std::min(chunk, s.size() - i));
      problem_->AddResidualBlock(new NewtonResidualChunk(&s.time_s[i], &s.temperature_c[i], &inverse_sigma_[i], count),
                                 loss_.get(), &parameters_.log_tau, &parameters_.delta_c, &parameters_.ambient_c);
    }
    const double log_duration = std::log(s.duration_s());
    problem_->SetParameterLowerBound(&parameters_.log_tau, 0, log_duration - std::log(kTauBoundFactor));
    problem_->SetParameterUpperBound(&parameters_.log_tau, 0, log_duration + std::log(kTauBoundFactor));
    const auto& ambient = options.ambient;
    if (ambient.mode == AmbientModel::Mode::kFixed) problem_->SetParameterBlockConstant(&parameters_.ambient_c);
    if (ambient.mode == AmbientModel::Mode::kPrior) {
      problem_->AddResidualBlock(new AmbientPriorResidual(ambient.value_c, ambient.sigma_c), nullptr,
                                 &parameters_.ambient_c);
    }
  }

  ceres::Solver::Summary solve(int max_iterations) {
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = max_iterations;
    options.function_tolerance = 1e-12;
    options.parameter_tolerance = 1e-12;
    options.gradient_tolerance = 1e-14;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, problem_.get(), &summary);
    return summary;
  }

  // Covariance of (log τ, ΔT, T_amb) for the weighted residuals, or nullopt
  // when J has a null space (rank deficiency).
  std::optional<ParameterCovariance> covariance(bool ambient_fixed) {
    ceres::Covariance::Options options;
    options.algorithm_type = ceres::DENSE_SVD;  // rank deficiency is detected, not papered over
    options.num_threads = 1;
    ceres::Covariance covariance(options);
    std::vector<double*> blocks = {&parameters_.log_tau, &parameters_.delta_c};
    if (!ambient_fixed) blocks.push_back(&parameters_.ambient_c);
    std::vector<std::pair<const double*, const double*>> pairs;
    for (auto* a : blocks)
      for (auto* b : blocks) pairs.emplace_back(a, b);
    if (!covariance.Compute(pairs, problem_.get())) return std::nullopt;
    ParameterCovariance c{};  // a fixed ambient leaves its row and column zero
    for (std::size_t i = 0; i < blocks.size(); ++i)
      for (std::size_t j = 0; j < blocks.size(); ++j) covariance.GetCovarianceBlock(blocks[i], blocks[j], &c[i][j]);
    return c;
  }

  // Σ ρ(r²) over the data residuals in units of σ_w (ρ(s) = s without a loss).
  double robust_sum_of_squares(const std::vector<double>& residuals_c) const {
    double sum = 0;
    for (double r : residuals_c) {
      const double s = (r / sigma_w_c_) * (r / sigma_w_c_);
      if (!loss_) {
        sum += s;
        continue;
      }
      double rho[3];
      loss_->Evaluate(s, rho);
      sum += rho[0];
    }
    return sum;
  }

  const Parameters& parameters() const { return parameters_; }

 private:
  Parameters parameters_;
  std::unique_ptr<ceres::LossFunction> loss_;
  std::vector<double> inverse_sigma_;  // 1/σ of each sample; the chunks point into it
  std::unique_ptr<ceres::Problem> problem_;
  double sigma_w_c_;
};

std::vector<double> residuals(const CleanSeries& s, const Parameters& p) {
  std::vector<double> r(s.size());
  const double k = std::exp(-p.log_tau);
  for (std::size_t i = 0; i < s.size(); ++i) {
    r[i] = s.temperature_c[i] - (p.ambient_c + p.delta_c * std::exp(-k * s.time_s[i]));
  }
  return r;
}

// A noise scale outliers cannot inflate: 1.4826 × the median absolute
// residual equals σ for Gaussian noise.
double robust_sigma(const std::vector<double>& r) {
  std::vector<double> magnitudes(r.size());
  for (std::size_t i = 0; i < r.size(); ++i) magnitudes[i] = std::abs(r[i]);
  const auto middle = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2);
  std::nth_element(magnitudes.begin(), middle, magnitudes.end());
  return 1.4826 * *middle;
}

std::size_t count_outliers(const std::vector<double>& r, double limit_c) {
  return static_cast<std::size_t>(std::count_if(r.begin(), r.end(), [&](double v) { return std::abs(v) > limit_c; }));
}

double lag1_autocorrelation(const std::vector<double>& r) {
  if (r.size() < 3) return 0.0;
  double mean = 0;
  for (double v : r) mean += v;
  mean /= static_cast<double>(r.size());
  double numerator = 0, denominator = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    denominator += (r[i] - mean) * (r[i] - mean);
    if (i + 1 < r.size()) numerator += (r[i] - mean) * (r[i + 1] - mean);
  }
  return denominator > 0 ? numerator / denominator : 0.0;
}

double median_sigma(std::vector<double> sigma_c) {
  const auto middle = sigma_c.begin() + static_cast<std::ptrdiff_t>(sigma_c.size() / 2);
  std::nth_element(sigma_c.begin(), middle, sigma_c.end());
  return *middle;
}

double first_sample_gap_s(const CleanSeries& s) {
  for (std::size_t i = 1; i < s.size(); ++i) {
    if (s.time_s[i] > s.time_s[0]) return s.time_s[i] - s.time_s[0];
  }
  return 0.0;
}

using Failure = std::pair<FitStatus, std::string>;

NewtonFit failed(NewtonFit fit, FitStatus status, std::string message) {
  fit.summary.status = status;
  fit.summary.message = std::move(message);
  fit.covariance.reset();
  fit.t0_reference_s = 0.0;
  for (Estimate* e : {&fit.k_per_s, &fit.tau_s, &fit.t0_c, &fit.ambient_c}) *e = {kNaN, kNaN, kNaN, kNaN, false};
  return fit;
}

NewtonFit failed(NewtonFit fit, Failure failure) {
  return failed(std::move(fit), failure.first, std::move(failure.second));
}

// The parameters and their covariance with ΔT where T0 is reported: moved
// from the first sample (where the fit works) to the origin, which lies
// first_sample_s before it, as ΔT(0) = ΔT(first)·e^(k·first_sample_s), the
// covariance carried by that map's Jacobian, so the curve and its band stay
// the same; left at the first sample when the origin lies too far for T0
// there (kMaxT0Extrapolation).
struct ReportedParameters {
  Parameters parameters;
  ParameterCovariance covariance;
  double t0_reference_s = 0.0;
};

ReportedParameters at_reported_t0(const Parameters& p, const ParameterCovariance& c, double first_sample_s) {
  const double exponent = std::exp(-p.log_tau) * first_sample_s;  // ln(ΔT(origin) / ΔT(first sample))
  if (!(std::abs(exponent) <= std::log(kMaxT0Extrapolation))) return {p, c, first_sample_s};
  ReportedParameters r{p, {}, 0.0};
  const double factor = std::exp(exponent);
  r.parameters.delta_c = p.delta_c * factor;
  // ∂ΔT(0)/∂log τ = −k·first_sample_s·ΔT(0) (k = e^(−log τ)), ∂ΔT(0)/∂ΔT(first) = the factor.
  const double jacobian[3][3] = {{1, 0, 0}, {-exponent * r.parameters.delta_c, factor, 0}, {0, 0, 1}};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) {
      double sum = 0;
      for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t b = 0; b < 3; ++b) sum += jacobian[i][a] * c[a][b] * jacobian[j][b];
      r.covariance[i][j] = sum;
    }
  }
  return r;
}

Estimate symmetric(double value, double std_error, double critical) {
  return {value, std_error, value - critical * std_error, value + critical * std_error, false};
}

// Fills k, τ, T0, T_amb from the parameters and their covariance.
void set_estimates(NewtonFit& fit, const Parameters& p, const ParameterCovariance& c, bool fixed, double critical) {
  const double se_log_tau = std::sqrt(c[0][0]);
  const double tau = std::exp(p.log_tau);
  const double tau_low = std::exp(p.log_tau - critical * se_log_tau);
  const double tau_high = std::exp(p.log_tau + critical * se_log_tau);
  fit.tau_s = {tau, tau * se_log_tau, tau_low, tau_high, false};
  fit.k_per_s = {1.0 / tau, se_log_tau / tau, 1.0 / tau_high, 1.0 / tau_low, false};
  const double var_t0 = fixed ? c[1][1] : c[1][1] + c[2][2] + 2.0 * c[1][2];
  fit.t0_c = symmetric(p.ambient_c + p.delta_c, std::sqrt(std::max(0.0, var_t0)), critical);
  fit.ambient_c = fixed ? Estimate{p.ambient_c, 0.0, p.ambient_c, p.ambient_c, true}
                        : symmetric(p.ambient_c, std::sqrt(c[2][2]), critical);
}

void add_warnings(NewtonFit& fit, const NewtonFitOptions& options, const Parameters& p) {
  auto& s = fit.summary;
  const double limit_c = kOutlierRobustSigmas * robust_sigma(fit.residuals_c);
  s.outliers = count_outliers(fit.residuals_c, limit_c);
  if (s.outliers > 0 && options.loss.kind == RobustLoss::Kind::kNone) {
    s.warnings.push_back(
        format("%zu residuals lie beyond %.3g °C (%.0f robust σ): outliers pull a least-squares fit; "
               "consider a robust loss (--loss huber:S with S about twice the noise, %.3g °C)",
               s.outliers, limit_c, kOutlierRobustSigmas, 2.0 * limit_c / kOutlierRobustSigmas));
  }
  if (options.ambient.mode == AmbientModel::Mode::kFree &&
      s.record_time_constants < options.min_time_constants_for_free_ambient) {
    s.warnings.push_back(
        format("the record covers only %.2g time constants (%.4g s of τ = %.4g s): the ambient temperature is weakly "
               "identified and k with it; fix the ambient (--ambient fixed:VALUE) or tie it to a measurement "
               "(--ambient prior:VALUE,SIGMA)",
               s.record_time_constants, fit.duration_s, fit.tau_s.value));
  }
  const double r = s.lag1_autocorrelation;
  if (r > options.max_lag1_autocorrelation) {
    s.warnings.push_back(
        format("residuals are correlated (lag-1 autocorrelation %.2f): the intervals assume independent noise and are "
               "optimistic (effective sample size about %.0f of %zu); check for drift, filtering or a model mismatch",
               r, std::max(1.0, s.points_used * (1 - r) / (1 + r)), s.points_used));
  } else if (r < -options.max_lag1_autocorrelation) {
    // Residuals that alternate in sign carry more information per point than
    // independent ones, so there is no smaller effective sample to quote.
    s.warnings.push_back(
        format("residuals alternate in sign (lag-1 autocorrelation %.2f): the intervals assume independent noise and "
               "are conservative; check for a sampling or filtering artefact",
               r));
  }
  if (fit.k_per_s.std_error > 0.5 * fit.k_per_s.value) {
    s.warnings.push_back(format("k is poorly determined (standard error %.0f%% of its value)",
                                100.0 * fit.k_per_s.std_error / fit.k_per_s.value));
  }
  if (s.reduced_chi_square && s.dof >= 10) {
    const double band = 3.0 * std::sqrt(2.0 / s.dof);
    if (std::abs(*s.reduced_chi_square - 1.0) > band) {
      s.warnings.push_back(format(
          "reduced χ² = %.3g differs from 1 by more than chance allows: the given σ%s is %s, or the model does "
          "not describe the data",
          *s.reduced_chi_square,
          options.measurement_sigma_c ? format(" = %.4g °C", *options.measurement_sigma_c).c_str() : " of each sample",
          *s.reduced_chi_square > 1 ? "too small" : "too large"));
    }
  }
  if (options.ambient.mode == AmbientModel::Mode::kPrior) {
    const double pull = (p.ambient_c - options.ambient.value_c) / options.ambient.sigma_c;
    if (std::abs(pull) > 3.0) {
      s.warnings.push_back(format("the fitted ambient %.4g °C is %.1f σ from the measured %.4g ± %.2g °C", p.ambient_c,
                                  pull, options.ambient.value_c, options.ambient.sigma_c));
    }
  }
}

// With a free ambient, a τ far beyond the record makes the curve a straight
// line, on which ambient and k trade off exactly.
std::optional<std::string> no_curvature(double tau, const CleanSeries& s, const AmbientModel& ambient) {
  if (ambient.mode != AmbientModel::Mode::kFree || tau <= kLongestResolvableTau * s.duration_s()) return std::nullopt;
  return format(
      "the record shows no curvature (τ ≈ %.3g s, over 1000 times its %.3g s length): ambient and k "
      "cannot be separated; fix the ambient (--ambient fixed:VALUE) or record longer",
      tau, s.duration_s());
}

// Statuses that depend on the solution rather than on the input.
std::optional<Failure> check_identifiable(const NewtonFit& fit, const CleanSeries& s, const NewtonFitOptions& options) {
  const double tau = fit.tau_s.value;
  const double gap = first_sample_gap_s(s);
  if (tau < gap) {
    return Failure{FitStatus::kUnidentifiable,
                   format("the fitted time constant (%.3g s) is shorter than the first sampling interval (%.3g s): "
                          "the decay is not resolved; sample faster or start the record earlier",
                          tau, gap)};
  }
  if (auto straight = no_curvature(tau, s, options.ambient)) return Failure{FitStatus::kUnidentifiable, *straight};
  return std::nullopt;
}

void describe_input(NewtonFitSummary& summary, const CleanSeries& s, const NewtonFitOptions& options) {
  summary.points_used = s.size();
  summary.rejected_non_finite = s.rejected_non_finite;
  summary.duplicate_times = s.duplicate_times;
  summary.parameters = free_parameter_count(options.ambient);
  summary.dof = degrees_of_freedom(s.size(), options.ambient);
  summary.absolute_sigma = options.measurement_sigma_c.has_value() || !s.sigma_c.empty();
  summary.confidence = options.confidence;
}

std::optional<Failure> check_input(const NewtonFitSummary& summary, const CleanSeries& s,
                                   const NewtonFitOptions& options) {
  if (auto reason = options.Validate(); !reason.empty()) return Failure{FitStatus::kInvalidOptions, reason};
  if (options.measurement_sigma_c && !s.sigma_c.empty()) {
    return Failure{FitStatus::kInvalidOptions,
                   "both one measurement σ and a σ per sample are given: give one or the other"};
  }
  if (summary.dof < 1 || s.size() < 3) {
    const int prior = options.ambient.mode == AmbientModel::Mode::kPrior ? 1 : 0;
    return Failure{
        FitStatus::kTooFewPoints,
        format("%zu usable points (%zu rejected as NaN/inf) for %d parameters: at least %d are needed", s.size(),
               s.rejected_non_finite, summary.parameters, std::max(3, summary.parameters + 1 - prior))};
  }
  if (!(s.duration_s() > 0.0)) {
    return Failure{FitStatus::kNoTimeSpan, "every sample has the same time: a rate cannot be fitted"};
  }
  return std::nullopt;
}

double sum_of_squares(const std::vector<double>& r) {
  double sum = 0;
  for (double v : r) sum += v * v;
  return sum;
}

// Why Ceres stopped, in the fit's own words: its message names internals
// (parameter-block addresses) that mean nothing to the user.
std::string solver_failure(const ceres::Solver::Summary& solver, int max_iterations) {
  const int steps = static_cast<int>(solver.iterations.size());
  if (solver.termination_type == ceres::NO_CONVERGENCE) {
    return format("it reached its limit of %d iterations", max_iterations);
  }
  return format("the model could not be evaluated (a non-finite residual or derivative) after %d iterations", steps);
}

// The solved problem: kept alive because the covariance is computed on it.
struct Solution {
  Parameters parameters;
  std::vector<double> residuals_c;
  std::unique_ptr<NewtonProblem> problem;
};

std::optional<Failure> solve(const CleanSeries& s, const NewtonFitOptions& options, Solution& solution,
                             NewtonFitSummary& summary) {
  const StartValues start = start_values(s, options.ambient);
  double scale_c = 0.0;  // a temperature scale for the σ_w floor
  for (double v : s.temperature_c) scale_c = std::max(scale_c, std::abs(v - s.temperature_c.front()));
  const double sigma_floor_c = 1e-9 * (scale_c + 1.0);
  double sigma_w_c = !s.sigma_c.empty() ? median_sigma(s.sigma_c)
                                        : options.measurement_sigma_c.value_or(std::max(start.rms_c, sigma_floor_c));
  // With an ambient prior and unknown σ the prior's weight depends on the
  // data noise, which is estimated: one more pass with the estimate settles it.
  const bool reweight =
      options.ambient.mode == AmbientModel::Mode::kPrior && !options.measurement_sigma_c && s.sigma_c.empty();
  solution.parameters = start.parameters;
  for (int pass = 0; pass < (reweight ? 2 : 1); ++pass) {
    solution.problem = std::make_unique<NewtonProblem>(s, options, solution.parameters, sigma_w_c);
    const auto solver = solution.problem->solve(options.max_iterations);
    summary.iterations += static_cast<int>(solver.iterations.size());
    solution.parameters = solution.problem->parameters();
    if (solver.termination_type != ceres::CONVERGENCE) {
      if (auto straight = no_curvature(std::exp(solution.parameters.log_tau), s, options.ambient)) {
        return Failure{FitStatus::kUnidentifiable, *straight};
      }
      return Failure{FitStatus::kNotConverged,
                     format("the solver did not converge: %s; fix the ambient (--ambient fixed:VALUE) or use a "
                            "robust loss if there are outliers",
                            solver_failure(solver, options.max_iterations).c_str())};
    }
    solution.residuals_c = residuals(s, solution.parameters);
    sigma_w_c = std::max(std::sqrt(sum_of_squares(solution.residuals_c) / summary.dof), sigma_floor_c);
  }
  return std::nullopt;
}

// Σ (r_i/σ_i)², each sample with its own σ or all with one.
double chi_square(const std::vector<double>& r, const CleanSeries& s, double one_sigma_c) {
  double sum = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double sigma = s.sigma_c.empty() ? one_sigma_c : s.sigma_c[i];
    sum += (r[i] / sigma) * (r[i] / sigma);
  }
  return sum;
}

void set_residual_statistics(NewtonFit& fit, const std::vector<double>& r, const CleanSeries& s,
                             const NewtonFitOptions& options) {
  auto& summary = fit.summary;
  const double ssr_c = sum_of_squares(r);
  summary.residual_rms_c = std::sqrt(ssr_c / static_cast<double>(r.size()));
  summary.residual_std_c = std::sqrt(ssr_c / summary.dof);
  summary.lag1_autocorrelation = lag1_autocorrelation(r);
  if (summary.absolute_sigma) {
    summary.reduced_chi_square = chi_square(r, s, options.measurement_sigma_c.value_or(1.0)) / summary.dof;
  }
}

Failure flat_record(double delta_c, double noise_c, const char* noise_name) {
  return {FitStatus::kNoDecay, format("no exponential change stands out of the noise (ΔT = %.3g °C, %s %.3g °C): "
                                      "is the record flat?",
                                      delta_c, noise_name, noise_c)};
}

std::optional<Failure> set_uncertainties(NewtonFit& fit, Solution& solution, const NewtonFitOptions& options,
                                         double first_sample_s) {
  auto& summary = fit.summary;
  const Parameters& p = solution.parameters;
  const bool fixed = options.ambient.mode == AmbientModel::Mode::kFixed;
  auto covariance = solution.problem->covariance(fixed);
  if (!covariance) {
    if (std::abs(p.delta_c) < 3.0 * summary.residual_std_c) {
      return flat_record(p.delta_c, summary.residual_std_c, "residual σ");
    }
    return Failure{FitStatus::kRankDeficient,
                   "the parameters are not all determined by the data (rank-deficient covariance)" +
                       std::string(fixed ? ""
                                         : "; fix the ambient temperature (--ambient fixed:VALUE) or record for "
                                           "longer than one time constant")};
  }
  // Scaled convention: multiply the weighted covariance by the (robust)
  // residual variance in units of σ_w², i.e. s² / σ_w².
  const double variance_factor =
      summary.absolute_sigma ? 1.0 : solution.problem->robust_sum_of_squares(solution.residuals_c) / summary.dof;
  for (auto& row : *covariance)
    for (double& v : row) v *= variance_factor;
  if (summary.absolute_sigma) summary.interval_dof = options.interval_dof;
  summary.t_critical = !summary.absolute_sigma ? student_t_critical(summary.dof, options.confidence)
                       : options.interval_dof  ? student_t_critical(*options.interval_dof, options.confidence)
                                               : normal_critical(options.confidence);
  // The amplitude is judged where the data are, not at an origin that may lie far from them.
  const double delta_se = std::sqrt((*covariance)[1][1]);
  if (std::abs(p.delta_c) < summary.t_critical * delta_se) return flat_record(p.delta_c, delta_se, "±");
  const ReportedParameters reported = at_reported_t0(p, *covariance, first_sample_s);
  set_estimates(fit, reported.parameters, reported.covariance, fixed, summary.t_critical);
  fit.covariance = reported.covariance;
  fit.t0_reference_s = reported.t0_reference_s;
  summary.record_time_constants = fit.duration_s / fit.tau_s.value;
  return std::nullopt;
}

// The fit proper, on a series whose times count from its first sample, so
// that nothing in it (start values, solver, covariance, checks) depends on
// where the origin lies; `first_sample_s` places the first sample relative
// to the origin the fit reports at, `origin_s`.
NewtonFit fit_from_first_sample(const CleanSeries& data, double origin_s, double first_sample_s,
                                const NewtonFitOptions& options) {
  NewtonFit fit;
  fit.origin_s = origin_s;
  fit.duration_s = data.duration_s();
  describe_input(fit.summary, data, options);
  if (auto failure = check_input(fit.summary, data, options)) return failed(fit, std::move(*failure));

  Solution solution;
  if (auto failure = solve(data, options, solution, fit.summary)) return failed(fit, std::move(*failure));
  set_residual_statistics(fit, solution.residuals_c, data, options);
  if (auto failure = set_uncertainties(fit, solution, options, first_sample_s)) {
    return failed(fit, std::move(*failure));
  }
  if (auto failure = check_identifiable(fit, data, options)) return failed(fit, std::move(*failure));

  fit.residuals_c = std::move(solution.residuals_c);
  add_warnings(fit, options, solution.parameters);
  fit.summary.status = FitStatus::kOk;
  return fit;
}

}  // namespace

std::string NewtonFitOptions::Validate() const {
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must lie strictly between 0 and 1";
  if (max_iterations < 1) return "max_iterations must be at least 1";
  if (origin_s && !std::isfinite(*origin_s)) return "the time origin must be finite";
  if (measurement_sigma_c && !(*measurement_sigma_c > 0.0 && std::isfinite(*measurement_sigma_c))) {
    return "the measurement σ must be positive and finite";
  }
  if (interval_dof && !(*interval_dof > 0.0 && std::isfinite(*interval_dof))) {
    return "the intervals' degrees of freedom must be positive and finite";
  }
  if (!std::isfinite(ambient.value_c)) return "the ambient value must be finite";
  if (ambient.mode == AmbientModel::Mode::kPrior && !(ambient.sigma_c > 0.0 && std::isfinite(ambient.sigma_c))) {
    return "the ambient prior needs a positive, finite σ";
  }
  if (loss.kind != RobustLoss::Kind::kNone && !(loss.scale_c > 0.0 && std::isfinite(loss.scale_c))) {
    return "the robust loss needs a positive, finite scale";
  }
  return {};
}

const char* to_string(FitStatus status) {
  switch (status) {
    case FitStatus::kOk:
      return "ok";
    case FitStatus::kInvalidOptions:
      return "invalid options";
    case FitStatus::kTooFewPoints:
      return "too few points";
    case FitStatus::kNoTimeSpan:
      return "no time span";
    case FitStatus::kNoDecay:
      return "no decay resolved";
    case FitStatus::kUnidentifiable:
      return "unidentifiable";
    case FitStatus::kRankDeficient:
      return "rank deficient";
    case FitStatus::kNotConverged:
      return "not converged";
  }
  return "unknown";
}

NewtonFit fit_newton(std::span<const double> time_s, std::span<const double> temperature_c,
                     const NewtonFitOptions& options) {
  if (time_s.size() != temperature_c.size()) throw std::invalid_argument("time and temperature differ in length");
  NewtonFit fit;
  if (auto reason = options.Validate(); !reason.empty()) {
    return failed(fit, FitStatus::kInvalidOptions, reason);
  }
  const CleanSeries data = clean_series(time_s, temperature_c);  // from the first sample, rounded once
  const double origin_s = options.origin_s.value_or(data.origin_s);
  return fit_from_first_sample(data, origin_s, data.origin_s - origin_s, options);
}

NewtonFit fit_newton(std::span<const double> time_s, std::span<const double> temperature_c,
                     std::span<const double> sigma_c, const NewtonFitOptions& options) {
  NewtonFit fit;
  if (auto reason = options.Validate(); !reason.empty()) {
    return failed(fit, FitStatus::kInvalidOptions, reason);
  }
  const CleanSeries data = clean_series(time_s, temperature_c, sigma_c);
  const double origin_s = options.origin_s.value_or(data.origin_s);
  return fit_from_first_sample(data, origin_s, data.origin_s - origin_s, options);
}

NewtonFit fit_newton(const CleanSeries& s, const NewtonFitOptions& options) {
  if (s.size() == 0) return fit_from_first_sample(s, s.origin_s, 0.0, options);
  CleanSeries data = s;
  const double first_sample_s = s.time_s.front();
  for (double& t : data.time_s) t -= first_sample_s;
  return fit_from_first_sample(data, s.origin_s, first_sample_s, options);
}

double NewtonFit::temperature_at(double time_s) const {
  if (!ok()) return kNaN;
  const double delta = t0_c.value - ambient_c.value;
  return ambient_c.value + delta * std::exp(-k_per_s.value * ((time_s - origin_s) - t0_reference_s));
}

double NewtonFit::temperature_half_width_at(double time_s) const {
  if (!ok() || !covariance) return kNaN;
  const double t = (time_s - origin_s) - t0_reference_s;
  const double decay = std::exp(-k_per_s.value * t);
  const double delta = t0_c.value - ambient_c.value;
  // ∂T/∂log τ = ΔT·e^(−kt)·kt, ∂T/∂ΔT = e^(−kt), ∂T/∂T_amb = 1.
  const std::array<double, 3> g{delta * decay * k_per_s.value * t, decay, 1.0};
  double variance = 0.0;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) variance += g[i] * (*covariance)[i][j] * g[j];
  // Rounding can leave a tiny negative variance where the true one is 0.
  return summary.t_critical * std::sqrt(std::max(0.0, variance));
}

std::string NewtonFitSummary::brief_report() const {
  if (!ok()) {
    return format("Newton fit failed (%s): %s\n", to_string(status), message.c_str());
  }
  std::string text = format(
      "Newton fit: ok; %zu points (%zu rejected as NaN/inf, %zu duplicate times kept), %d "
      "iterations\n",
      points_used, rejected_non_finite, duplicate_times, iterations);
  text += format("  residual RMS %.4g °C, s = %.4g °C (dof %.0f), lag-1 autocorrelation %.2f, record spans %.2f τ\n",
                 residual_rms_c, residual_std_c, dof, lag1_autocorrelation, record_time_constants);
  if (absolute_sigma) {
    text +=
        format("  uncertainties absolute (from the given σ), reduced χ² = %.3g\n", reduced_chi_square.value_or(kNaN));
  } else {
    text += "  uncertainties scaled by the residual variance (s² = SSR/dof)\n";
  }
  for (const auto& w : warnings) text += "  warning: " + w + "\n";
  return text;
}

std::string NewtonFit::brief_report() const {
  if (!ok()) return summary.brief_report();
  // Names arrive padded: printf pads bytes, and τ takes two.
  const auto line = [](const char* name, const char* unit, const Estimate& e) {
    if (e.fixed) return format("  %s = %.6g %s (fixed)\n", name, e.value, unit);
    // At the digits σ supports (fitting/uncertainty_digits.h).
    const auto at_sigma = [&e](double v) { return format_at_uncertainty(v, e.std_error); };
    return format("  %s = %s ± %s %s  [%s, %s]\n", name, at_sigma(e.value).c_str(), at_sigma(e.std_error).c_str(),
                  unit, at_sigma(e.low).c_str(), at_sigma(e.high).c_str());
  };
  std::string text = "T(t) = T_amb + (T0 − T_amb)·exp(−k·t), t from the origin; intervals at " +
                     format("%.3g%%", 100.0 * summary.confidence) + "\n";
  if (!t0_at_origin()) {
    text = "T(t) = T_amb + (T0 − T_amb)·exp(−k·(t − t₀)), t from the origin; intervals at " +
           format(
               "%.3g%%\n  T0 is at t₀ = %.10g s, the first sample: the origin lies %.3g time constants from the "
               "data, too far for T0 there\n",
               100.0 * summary.confidence, t0_reference_s, std::abs(t0_reference_s) / tau_s.value);
  }
  text += line("k    ", "1/s", k_per_s);
  text += line("τ    ", "s", tau_s);
  text += line("T0   ", "°C", t0_c);
  text += line("T_amb", "°C", ambient_c);
  return text + summary.brief_report();
}

}  // namespace bosfuse::fitting
