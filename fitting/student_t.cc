#include "fitting/student_t.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace bosfuse::fitting {
namespace {

// Continued fraction for the incomplete beta function (Lentz's method), as
// in Numerical Recipes' betacf; converges fast for x < (a + 1) / (a + b + 2).
double beta_continued_fraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr int kMaxTerms = 500;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= kMaxTerms; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
    d = 1.0 + aa * d;
    c = 1.0 + aa / c;
    d = 1.0 / (std::abs(d) < kTiny ? kTiny : d);
    c = std::abs(c) < kTiny ? kTiny : c;
    h *= d * c;
    aa = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
    d = 1.0 + aa * d;
    c = 1.0 + aa / c;
    d = 1.0 / (std::abs(d) < kTiny ? kTiny : d);
    c = std::abs(c) < kTiny ? kTiny : c;
    const double step = d * c;
    h *= step;
    if (std::abs(step - 1.0) < 1e-15) break;
  }
  return h;
}

double regularized_incomplete_beta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double log_front = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(a, b, x) / a;
  return 1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b;
}

void check_confidence(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must lie in (0, 1)");
}

}  // namespace

double student_t_cdf(double t, double dof) {
  if (!(dof > 0.0)) throw std::invalid_argument("Student t needs dof > 0");
  const double x = dof / (dof + t * t);
  const double tail = 0.5 * regularized_incomplete_beta(0.5 * dof, 0.5, x);
  return t >= 0.0 ? 1.0 - tail : tail;
}

double student_t_critical(double dof, double confidence) {
  check_confidence(confidence);
  if (!(dof > 0.0)) throw std::invalid_argument("Student t needs dof > 0");
  const double target = 0.5 + 0.5 * confidence;
  // Bisection on a bracket that holds every case of interest (dof >= 1 at
  // 99.99% needs ~6366); 200 halvings exhaust double precision.
  double low = 0.0;
  double high = 1e7;
  for (int i = 0; i < 200 && high - low > 1e-12 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (student_t_cdf(mid, dof) < target ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

double normal_critical(double confidence) {
  check_confidence(confidence);
  const double target = 0.5 + 0.5 * confidence;
  double low = 0.0;
  double high = 40.0;
  for (int i = 0; i < 200 && high - low > 1e-14; ++i) {
    const double mid = 0.5 * (low + high);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < target ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

}  // namespace bosfuse::fitting
