// The Newton fit does not depend on where t = 0 lies nor on the time unit:
// the same curve, its times shifted by anything from −1e6 to +1e8 s (with
// the origin kept at 0, as `bosfuse fit` keeps a file's own t = 0) or
// multiplied by 1e-3 to 1e3, gives the same k, τ, intervals, curve and band
// to 1e-9 relative, and T0 is either at the origin or at the first sample,
// which the fit says. Found by a probe: at −300 s the fit failed with a
// Ceres parameter-block address, at −1e4 s it called the record flat, and at
// +1e4 s it called it rank-deficient.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "fitting/newton_fit.h"
#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

using testing::CoolingCurve;
using testing::CoolingRecord;
using testing::sample_cooling;

constexpr double kRelative = 1e-9;

const CoolingCurve kCurve{22.0, 80.0, 0.005};  // τ = 200 s; 300 samples 2 s apart span 3 τ

struct Variant {
  const char* name;
  double sigma_c;
  AmbientModel ambient;
};

std::vector<Variant> variants() {
  return {{"noiseless, free ambient", 0.0, AmbientModel::free()},
          {"noisy, free ambient", 0.05, AmbientModel::free()},
          {"noiseless, fixed ambient", 0.0, AmbientModel::fixed(kCurve.ambient_c)},
          {"noisy, fixed ambient", 0.05, AmbientModel::fixed(kCurve.ambient_c)},
          {"noiseless, ambient prior", 0.0, AmbientModel::prior(kCurve.ambient_c, 0.1)},
          {"noisy, ambient prior", 0.05, AmbientModel::prior(kCurve.ambient_c, 0.1)}};
}

// 300 samples about 2 s apart, each time jittered by up to ±0.4 s so that
// shifted times round differently (whole seconds would shift exactly).
CoolingRecord jittered_cooling(double sigma_c, unsigned seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  std::normal_distribution<double> noise(0.0, sigma_c > 0 ? sigma_c : 1.0);
  CoolingRecord r;
  for (int i = 0; i < 300; ++i) {
    const double t = 2.0 * i + (i > 0 ? jitter(random) : 0.0);
    r.time_s.push_back(t);
    r.temperature_c.push_back(kCurve.at(t) + (sigma_c > 0 ? noise(random) : 0.0));
  }
  return r;
}

NewtonFit fit_at_zero(const CoolingRecord& r, const Variant& v) {
  NewtonFitOptions options;
  options.origin_s = 0.0;
  options.ambient = v.ambient;
  return fit_newton(r.time_s, r.temperature_c, options);
}

CoolingRecord transformed(CoolingRecord r, double scale, double shift_s) {
  for (double& t : r.time_s) t = t * scale + shift_s;
  return r;
}

// a and b agree to kRelative of their size (a noiseless fit's zero widths agree with zero).
void expect_close(double a, double b, const std::string& what) {
  EXPECT_LE(std::abs(a - b), kRelative * std::max(std::abs(a), std::abs(b))) << what << ": " << a << " vs " << b;
}

void expect_same_rate(const NewtonFit& a, const NewtonFit& b, double scale, const std::string& what) {
  expect_close(a.k_per_s.value * scale, b.k_per_s.value, what + " k");
  expect_close(a.k_per_s.low * scale, b.k_per_s.low, what + " k low");
  expect_close(a.k_per_s.high * scale, b.k_per_s.high, what + " k high");
  expect_close(a.tau_s.value, b.tau_s.value * scale, what + " τ");
  expect_close(a.tau_s.low, b.tau_s.low * scale, what + " τ low");
  expect_close(a.tau_s.high, b.tau_s.high * scale, what + " τ high");
  expect_close(a.ambient_c.value, b.ambient_c.value, what + " T_amb");
  expect_close(a.ambient_c.low, b.ambient_c.low, what + " T_amb low");
  expect_close(a.ambient_c.high, b.ambient_c.high, what + " T_amb high");
}

// T0 with its interval where the shifted fit states it, against the curve
// and band of the unshifted one at the same moment of the record.
void expect_same_t0(const NewtonFit& base, const NewtonFit& shifted, double shift_s, const std::string& what) {
  const double at_s = shifted.origin_s + shifted.t0_reference_s - shift_s;  // on the unshifted record's clock
  const double curve_c = base.temperature_at(at_s);
  const double half_width_c = base.temperature_half_width_at(at_s);
  expect_close(shifted.t0_c.value, curve_c, what + " T0");
  expect_close(shifted.t0_c.low, curve_c - half_width_c, what + " T0 low");
  expect_close(shifted.t0_c.high, curve_c + half_width_c, what + " T0 high");
}

void expect_same_curve(const NewtonFit& base, const NewtonFit& shifted, double shift_s, const std::string& what) {
  for (double t_s : {0.0, 150.0, 598.0, 1200.0}) {
    expect_close(shifted.temperature_at(t_s + shift_s), base.temperature_at(t_s),
                 what + " curve at " + std::to_string(t_s));
    // The band's half-width is a difference-free sum of squares: as precise as the curve relative to the curve.
    EXPECT_LE(std::abs(shifted.temperature_half_width_at(t_s + shift_s) - base.temperature_half_width_at(t_s)),
              kRelative * base.temperature_at(t_s))
        << what << " band at " << t_s;
  }
}

TEST(NewtonFitOrigin, AShiftOfTheTimesFromMinusAMillionToPlusTenToTheEightChangesNothing) {
  const double limit = std::log(kMaxT0Extrapolation);
  for (const auto& v : variants()) {
    const auto record = jittered_cooling(v.sigma_c, 21);
    const NewtonFit base = fit_at_zero(record, v);
    ASSERT_TRUE(base.ok()) << v.name << "\n" << base.brief_report();
    ASSERT_TRUE(base.t0_at_origin());
    for (double shift_s : {-1e6, -1e4, -3000.0, -1000.0, -300.0, -100.0, 300.0, 2500.0, 1e4, 1e6, 1e8}) {
      const std::string what = std::string(v.name) + ", shift " + std::to_string(shift_s) + " s:";
      const NewtonFit shifted = fit_at_zero(transformed(record, 1.0, shift_s), v);
      ASSERT_TRUE(shifted.ok()) << what << "\n" << shifted.brief_report();
      EXPECT_EQ(shifted.t0_at_origin(), std::abs(kCurve.k_per_s * shift_s) <= limit) << what;
      if (!shifted.t0_at_origin()) {
        EXPECT_EQ(shifted.t0_reference_s, shift_s) << what << " T0 at the first sample";
      }
      expect_same_rate(base, shifted, 1.0, what);
      expect_same_t0(base, shifted, shift_s, what);
      expect_same_curve(base, shifted, shift_s, what);
      EXPECT_EQ(shifted.summary.status, base.summary.status) << what;
      // (A noiseless fit's residuals are rounding, whose autocorrelation and outliers are chance.)
      if (v.sigma_c > 0) {
        EXPECT_EQ(shifted.summary.warnings, base.summary.warnings) << what;
      }
    }
  }
}

// With the default origin (the first sample) the shift is only a different
// clock: everything, T0 included, is the same.
TEST(NewtonFitOrigin, TheDefaultOriginFollowsTheData) {
  for (const auto& v : variants()) {
    const auto record = jittered_cooling(v.sigma_c, 22);
    NewtonFitOptions options;
    options.ambient = v.ambient;
    const NewtonFit base = fit_newton(record.time_s, record.temperature_c, options);
    ASSERT_TRUE(base.ok()) << base.brief_report();
    for (double shift_s : {-1e6, -300.0, 1e4, 1.8e9}) {
      const std::string what = std::string(v.name) + ", shift " + std::to_string(shift_s) + " s:";
      const auto shifted_record = transformed(record, 1.0, shift_s);
      const NewtonFit shifted = fit_newton(shifted_record.time_s, shifted_record.temperature_c, options);
      ASSERT_TRUE(shifted.ok()) << what << "\n" << shifted.brief_report();
      EXPECT_EQ(shifted.origin_s, shift_s);
      EXPECT_TRUE(shifted.t0_at_origin());
      expect_same_rate(base, shifted, 1.0, what);
      expect_close(shifted.t0_c.value, base.t0_c.value, what + " T0");
      expect_close(shifted.t0_c.low, base.t0_c.low, what + " T0 low");
    }
  }
}

TEST(NewtonFitOrigin, TimesMultipliedByAFactorDivideKByIt) {
  for (const auto& v : variants()) {
    const auto record = jittered_cooling(v.sigma_c, 23);
    const NewtonFit base = fit_at_zero(record, v);
    ASSERT_TRUE(base.ok()) << base.brief_report();
    for (double scale : {1e-3, 0.01, 0.37, 3.0, 100.0, 1e3}) {
      const std::string what = std::string(v.name) + ", times × " + std::to_string(scale) + ":";
      const NewtonFit scaled = fit_at_zero(transformed(record, scale, 0.0), v);
      ASSERT_TRUE(scaled.ok()) << what << "\n" << scaled.brief_report();
      expect_same_rate(base, scaled, 1.0 / scale, what);
      expect_close(scaled.t0_c.value, base.t0_c.value, what + " T0");
      expect_close(scaled.t0_c.low, base.t0_c.low, what + " T0 low");
      expect_close(scaled.t0_c.high, base.t0_c.high, what + " T0 high");
      expect_close(scaled.temperature_at(300.0 * scale), base.temperature_at(300.0), what + " curve");
    }
  }
}

// Scaled and shifted at once: the start of a second session an hour into a
// run recorded in milliseconds.
TEST(NewtonFitOrigin, AScaledAndShiftedRecordGivesTheSameRate) {
  const Variant v{"noisy, free ambient", 0.05, AmbientModel::free()};
  const auto record = jittered_cooling(v.sigma_c, 24);
  const NewtonFit base = fit_at_zero(record, v);
  const NewtonFit moved = fit_at_zero(transformed(record, 1e3, 3.6e6), v);
  ASSERT_TRUE(base.ok() && moved.ok()) << moved.brief_report();
  expect_same_rate(base, moved, 1e-3, "ms, an hour in:");
  EXPECT_FALSE(moved.t0_at_origin());
  EXPECT_NE(moved.brief_report().find("T0 is at t₀ = 3600000 s, the first sample"), std::string::npos)
      << moved.brief_report();
}

// A fit whose T0 lies at the first sample keeps one consistent set of
// numbers: its covariance is of ΔT there, so the band at the stated
// reference is T0's interval.
TEST(NewtonFitOrigin, TheCovarianceIsOfTheAmplitudeWhereT0IsStated) {
  const auto record = transformed(sample_cooling(kCurve, 300, 2.0, 0.05, 25), 1.0, 1e4);
  const NewtonFit fit = fit_at_zero(record, {"noisy", 0.05, AmbientModel::free()});
  ASSERT_TRUE(fit.ok() && fit.covariance) << fit.brief_report();
  ASSERT_FALSE(fit.t0_at_origin());
  const double at_s = fit.origin_s + fit.t0_reference_s;
  EXPECT_NEAR(fit.temperature_at(at_s), fit.t0_c.value, 1e-12 * fit.t0_c.value);
  EXPECT_NEAR(fit.temperature_half_width_at(at_s), fit.t0_c.high - fit.t0_c.value, 1e-9);
  const auto& c = *fit.covariance;
  EXPECT_NEAR(fit.t0_c.std_error, std::sqrt(c[1][1] + c[2][2] + 2 * c[1][2]), 1e-12);
}

void expect_no_internals(const NewtonFit& fit, const std::string& what) {
  std::vector<std::string> texts = fit.summary.warnings;
  texts.push_back(fit.summary.message);
  texts.push_back(fit.brief_report());
  for (const auto& text : texts) {
    EXPECT_EQ(text.find("0x"), std::string::npos) << what << ": " << text;
    EXPECT_EQ(text.find("ParameterBlock"), std::string::npos) << what << ": " << text;
  }
}

// Ceres' own messages name parameter blocks by address; none reaches the
// user, whatever makes the fit fail.
TEST(NewtonFitOrigin, NoMessageNamesASolverInternal) {
  std::vector<std::pair<std::string, NewtonFit>> fits;
  const auto record = sample_cooling(kCurve, 300, 2.0, 0.05, 26);
  for (double shift_s : {-1e6, -1e4, -300.0, 1e4, 1e6, 1e8}) {
    fits.emplace_back("shifted", fit_at_zero(transformed(record, 1.0, shift_s), {"", 0, AmbientModel::free()}));
  }
  CoolingRecord overflowing;  // finite temperatures whose differences overflow: the model cannot be evaluated
  for (int i = 0; i < 20; ++i) {
    overflowing.time_s.push_back(i);
    overflowing.temperature_c.push_back(i % 2 ? 1.7e308 : -1.7e308);
  }
  fits.emplace_back("overflowing", fit_at_zero(overflowing, {"", 0, AmbientModel::free()}));
  NewtonFitOptions one_step;
  one_step.max_iterations = 1;
  fits.emplace_back("one iteration", fit_newton(record.time_s, record.temperature_c, one_step));
  const std::vector<double> t{0, 1, 2, 3, 4, 5}, flat(6, 22.0), line{60, 59, 58, 57, 56, 55};
  fits.emplace_back("flat", fit_newton(t, flat));
  fits.emplace_back("straight line", fit_newton(t, line));
  bool one_failed_in_the_solver = false;
  for (const auto& [what, fit] : fits) {
    expect_no_internals(fit, what);
    one_failed_in_the_solver |= fit.summary.status == FitStatus::kNotConverged;
  }
  EXPECT_FALSE(fits[6].second.ok());
  EXPECT_EQ(fits[6].second.summary.status, FitStatus::kNotConverged) << fits[6].second.summary.message;
  EXPECT_TRUE(one_failed_in_the_solver);
}

// Beyond the one curve: records spanning 30, 3, 0.3 and 0.03 τ, falling and
// rising, with and without a robust loss, give the same status (a fit or the
// same refusal) and the same numbers wherever their times lie.
TEST(NewtonFitOrigin, LongShortRisingAndRobustFitsAreShiftFreeToo) {
  int fitted = 0;
  for (double k_per_s : {0.05, 0.005, 0.0005, 0.00005}) {
    for (const RobustLoss& loss : {RobustLoss::none(), RobustLoss::huber(0.1)}) {
      const CoolingCurve curve{30.0, k_per_s < 0.001 ? 15.0 : 75.0, k_per_s};
      std::mt19937_64 random(7);
      std::normal_distribution<double> noise(0.0, 0.05);
      CoolingRecord record = jittered_cooling(0.0, 27);
      for (std::size_t i = 0; i < record.time_s.size(); ++i) {
        record.temperature_c[i] = curve.at(record.time_s[i]) + noise(random);
      }
      NewtonFitOptions options;
      options.origin_s = 0.0;
      options.loss = loss;
      const NewtonFit base = fit_newton(record.time_s, record.temperature_c, options);
      fitted += base.ok();
      for (double shift_s : {-1e6, -1e4, -300.0, 1e4, 1e6, 1e8}) {
        const auto moved = transformed(record, 1.0, shift_s);
        const NewtonFit fit = fit_newton(moved.time_s, moved.temperature_c, options);
        const std::string what = "k " + std::to_string(k_per_s) +
                                 (loss.kind == RobustLoss::Kind::kNone ? "" : ", Huber") + ", shift " +
                                 std::to_string(shift_s) + " s:";
        ASSERT_EQ(fit.summary.status, base.summary.status) << what << " " << fit.summary.message;
        EXPECT_EQ(fit.summary.message, base.summary.message) << what;
        if (!base.ok()) continue;
        expect_same_rate(base, fit, 1.0, what);
        expect_same_t0(base, fit, shift_s, what);
      }
    }
  }
  EXPECT_GE(fitted, 6) << "the 30, 3 and 0.3 τ records fit";
}

}  // namespace
}  // namespace bosfuse::fitting
