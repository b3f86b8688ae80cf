#include "acquisition/cameras/genicam_clock_mapping.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace bosfuse::acquisition {
namespace {

constexpr std::int64_t kGenicamMinDriftSpanNs = 1'000'000'000;

}  // namespace

GenicamClockMapping::GenicamClockMapping(std::size_t max_pairs) : max_pairs_(std::max<std::size_t>(max_pairs, 4)) {}

void GenicamClockMapping::add(std::int64_t camera_ns, std::int64_t host_ns) {
  if (pairs_.size() >= max_pairs_) {
    // Thin the older half to every other pair: the fit keeps its span.
    const std::size_t half = pairs_.size() / 2;
    std::size_t kept = 1;
    for (std::size_t i = 2; i < half; i += 2) pairs_[kept++] = pairs_[i];
    for (std::size_t i = half; i < pairs_.size(); ++i) pairs_[kept++] = pairs_[i];
    pairs_.resize(kept);
  }
  pairs_.push_back({camera_ns, host_ns});
  fit_.reset();
}

void GenicamClockMapping::clear() {
  pairs_.clear();
  fit_.reset();
}

void GenicamClockMapping::refit() const {
  Fit f;
  f.camera_origin_ns = pairs_.front().camera_ns;
  const std::int64_t host_origin = pairs_.front().host_ns;
  // Relative to the first pair, in double: 10 minutes is 6e11 ns, well
  // inside double's 53 bits.
  double mean_x = 0, mean_y = 0;
  for (const Pair& p : pairs_) {
    mean_x += static_cast<double>(p.camera_ns - f.camera_origin_ns);
    mean_y += static_cast<double>(p.host_ns - host_origin);
  }
  const double n = static_cast<double>(pairs_.size());
  mean_x /= n;
  mean_y /= n;
  double sxx = 0, sxy = 0;
  for (const Pair& p : pairs_) {
    const double dx = static_cast<double>(p.camera_ns - f.camera_origin_ns) - mean_x;
    sxx += dx * dx;
    sxy += dx * (static_cast<double>(p.host_ns - host_origin) - mean_y);
  }
  // Drift is fitted once the pairs span a second: over less, latency
  // jitter would dominate it (100 µs over 10 ms is 1 %). Before, an offset.
  const bool spans = pairs_.back().camera_ns - f.camera_origin_ns >= kGenicamMinDriftSpanNs;
  const double slope = spans && sxx > 0 ? sxy / sxx : 1.0;
  f.drift = slope - 1.0;
  const double intercept = mean_y - slope * mean_x;
  f.host_at_origin_ns = static_cast<double>(host_origin) + intercept;
  double sum_sq = 0;
  for (const Pair& p : pairs_) {
    const double x = static_cast<double>(p.camera_ns - f.camera_origin_ns);
    const double r = static_cast<double>(p.host_ns - host_origin) - (intercept + slope * x);
    sum_sq += r * r;
    f.residual_max_ns = std::max(f.residual_max_ns, std::abs(r));
  }
  f.residual_rms_ns = std::sqrt(sum_sq / n);
  f.pairs = pairs_.size();
  f.span_ns = pairs_.back().camera_ns - f.camera_origin_ns;
  fit_ = f;
}

std::optional<GenicamClockMapping::Fit> GenicamClockMapping::fit() const {
  if (pairs_.empty()) return std::nullopt;
  if (!fit_) refit();
  return fit_;
}

std::optional<std::int64_t> GenicamClockMapping::map(std::int64_t camera_ns) const {
  const std::optional<Fit> f = fit();
  if (!f) return std::nullopt;
  const double x = static_cast<double>(camera_ns - f->camera_origin_ns);
  return static_cast<std::int64_t>(std::llround(f->host_at_origin_ns + (1.0 + f->drift) * x));
}

std::string GenicamClockMapping::describe(const Fit& fit) {
  const double offset_s = (fit.host_at_origin_ns - static_cast<double>(fit.camera_origin_ns)) * 1e-9;
  return fmt::format(
      "offset {:+.6f} s at camera time {} ns, drift {:+.3f} ppm, residual {:.0f} µs RMS ({:.0f} µs max) "
      "over {} pairs in {:.1f} s",
      offset_s, fit.camera_origin_ns, fit.drift * 1e6, fit.residual_rms_ns * 1e-3, fit.residual_max_ns * 1e-3,
      fit.pairs, static_cast<double>(fit.span_ns) * 1e-9);
}

}  // namespace bosfuse::acquisition
