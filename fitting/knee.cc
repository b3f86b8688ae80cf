#include "fitting/knee.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

namespace bosfuse::fitting {
namespace {

constexpr std::size_t kSmoothingHalfWidth = 2;  // a 5-point running mean finds the maximum through the noise
constexpr std::size_t kEdgePoints = 4;          // a knee needs this many samples on each side
constexpr double kWindowDropFraction = 0.2;     // the window ends where the curve has fallen by a fifth
constexpr int kFineStepsPerInterval = 8;        // the t_k scan's steps per sample interval
constexpr std::size_t kMostCandidates = 200'000;  // a bound on the scan, far above any window

struct KneePoints {
  std::vector<double> t, y;
};

KneePoints finite_points(std::span<const double> t_s, std::span<const double> temperature_c) {
  KneePoints s;
  for (std::size_t i = 0; i < std::min(t_s.size(), temperature_c.size()); ++i) {
    if (std::isfinite(t_s[i]) && std::isfinite(temperature_c[i])) {
      s.t.push_back(t_s[i]);
      s.y.push_back(temperature_c[i]);
    }
  }
  return s;
}

std::vector<double> running_mean(const std::vector<double>& y) {
  std::vector<double> out(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) {
    const std::size_t lo = i < kSmoothingHalfWidth ? 0 : i - kSmoothingHalfWidth;
    const std::size_t hi = std::min(y.size() - 1, i + kSmoothingHalfWidth);
    double sum = 0;
    for (std::size_t j = lo; j <= hi; ++j) sum += y[j];
    out[i] = sum / static_cast<double>(hi - lo + 1);
  }
  return out;
}

struct HingeFit {
  double ssr = 0;
  double b_before = 0, b_after = 0;
};

// The hinge (knee.h) at `t_k` fitted to points [first, last).
HingeFit fit_hinge(const KneePoints& s, std::size_t first, std::size_t last, double t_k) {
  Eigen::Matrix<double, 5, 5> normal = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> rhs = Eigen::Matrix<double, 5, 1>::Zero();
  double yy = 0;
  for (std::size_t i = first; i < last; ++i) {
    const double d = s.t[i] - t_k;
    Eigen::Matrix<double, 5, 1> row = Eigen::Matrix<double, 5, 1>::Zero();
    row[0] = 1;
    if (d < 0) {
      row[1] = d;
      row[2] = d * d;
    } else {
      row[3] = d;
      row[4] = d * d;
    }
    normal += row * row.transpose();
    rhs += row * s.y[i];
    yy += s.y[i] * s.y[i];
  }
  const Eigen::Matrix<double, 5, 1> p = normal.ldlt().solve(rhs);
  return {std::max(0.0, yy - p.dot(rhs)), p[1], p[3]};
}

// Where the profile first rises by `rise` above its minimum at `best`,
// walking one way; none when it never does within the scan.
std::optional<double> crossing(const std::vector<double>& grid, const std::vector<double>& ssr, std::size_t best,
                               double rise, int step) {
  const double level = ssr[best] + rise;
  for (std::size_t i = best; i < grid.size(); i = static_cast<std::size_t>(static_cast<long>(i) + step)) {
    if (ssr[i] >= level) {
      const std::size_t prev = static_cast<std::size_t>(static_cast<long>(i) - step);
      const double f = (level - ssr[prev]) / (ssr[i] - ssr[prev]);
      return grid[prev] + f * (grid[i] - grid[prev]);
    }
    if (i == 0 && step < 0) break;
  }
  return std::nullopt;
}

struct KneeWindow {
  std::size_t first = 0, last = 0;  // [first, last)
};

std::optional<KneeWindow> window_around_maximum(const KneePoints& s, std::size_t peak, std::string& reason) {
  const std::vector<double> smooth = running_mean(s.y);
  const double low_after = *std::min_element(smooth.begin() + static_cast<long>(peak), smooth.end());
  const double level = smooth[peak] - kWindowDropFraction * (smooth[peak] - low_after);
  std::size_t end = peak;
  while (end + 1 < s.t.size() && smooth[end] > level) ++end;
  const double half_width_s = s.t[end] - s.t[peak];
  std::size_t first = peak;
  while (first > 0 && s.t[first - 1] >= s.t[peak] - half_width_s) --first;
  const KneeWindow w{first, end + 1};
  if (peak - w.first < kEdgePoints || w.last - peak < kEdgePoints) {
    reason = "too few samples on one side of the curve's maximum to place a knee";
    return std::nullopt;
  }
  return w;
}

}  // namespace

KneeResult find_knee(std::span<const double> t_s, std::span<const double> temperature_c) {
  const KneePoints s = finite_points(t_s, temperature_c);
  if (s.t.size() < 4 * kEdgePoints) return {std::nullopt, "too few samples for a knee"};
  const std::vector<double> smooth = running_mean(s.y);
  const auto peak = static_cast<std::size_t>(std::max_element(smooth.begin(), smooth.end()) - smooth.begin());
  if (peak < kEdgePoints) return {std::nullopt, "the curve falls from its first sample: the heater was off before"};
  if (peak + kEdgePoints >= s.t.size()) return {std::nullopt, "the curve rises to its last sample: no cooling seen"};
  std::string reason;
  const auto w = window_around_maximum(s, peak, reason);
  if (!w) return {std::nullopt, reason};
  // Candidates between the points that leave kEdgePoints on each side.
  const double from = s.t[w->first + kEdgePoints - 1], to = s.t[w->last - kEdgePoints];
  const double step = (s.t[w->last - 1] - s.t[w->first]) / static_cast<double>(w->last - w->first - 1) /
                      kFineStepsPerInterval;
  if (!(to > from) || !(step > 0)) return {std::nullopt, "the samples around the maximum share one time"};
  const auto count = static_cast<std::size_t>(std::min<double>(std::floor((to - from) / step) + 1, kMostCandidates));
  std::vector<double> grid(count), ssr(count);
  for (std::size_t i = 0; i < count; ++i) {
    grid[i] = from + static_cast<double>(i) * (to - from) / static_cast<double>(std::max<std::size_t>(count - 1, 1));
    ssr[i] = fit_hinge(s, w->first, w->last, grid[i]).ssr;
  }
  const auto best = static_cast<std::size_t>(std::min_element(ssr.begin(), ssr.end()) - ssr.begin());
  const HingeFit fit = fit_hinge(s, w->first, w->last, grid[best]);
  if (!(fit.b_before > 0 && fit.b_after < 0)) {
    return {std::nullopt, "the slopes around the maximum do not turn from heating to cooling"};
  }
  const std::size_t n = w->last - w->first;
  const double s2 = ssr[best] / static_cast<double>(n - 6);
  const auto left = crossing(grid, ssr, best, s2, -1);
  const auto right = crossing(grid, ssr, best, s2, +1);
  // A profile that never rises by s² inside the scan: the knee is no better
  // placed than the scan's extent on that side.
  const double profile_sigma = ((right ? *right : to) - (left ? *left : from)) / 2;
  // A kink between two samples is placed no better than that interval: its
  // quantisation (uniform over one interval, Δt/√12) is added, which the
  // profile, not quadratic near a kink, understates (3σ misses without it).
  const double interval_s = step * kFineStepsPerInterval;
  const double sigma = std::hypot(profile_sigma, interval_s / std::sqrt(12.0));
  return {Knee{grid[best], sigma, fit.b_before, fit.b_after, n}, ""};
}

}  // namespace bosfuse::fitting
