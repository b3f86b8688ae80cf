#include "acquisition/cameras/genicam_clock_mapping.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace bosfuse::acquisition {
namespace {

constexpr std::int64_t kGenicamMinDriftSpanNs = 1'000'000'000;
// The envelope's slope is fitted through the least-delayed pair of each of
// up to 16 stretches of camera time, with at least 8 pairs a stretch.
constexpr std::size_t kGenicamSegments = 16;
constexpr std::size_t kGenicamPairsPerSegment = 8;

// The lag of the host clock behind the camera's, l = (host − host_origin)
// − (camera − camera_origin) = intercept + drift · (camera − camera_origin),
// in ns: small numbers, so the drift keeps its digits.
struct GenicamLine {
  double intercept = 0;
  double drift = 0;
  double at(double x) const { return intercept + drift * x; }
};

// Least squares of `l` on `x` over the pairs `use` indexes; drift 0 (an
// offset alone) unless `fit_drift` and the pairs spread in x.
GenicamLine genicam_least_squares(const std::vector<double>& x, const std::vector<double>& l,
                                  const std::vector<std::size_t>& use, bool fit_drift) {
  double mean_x = 0, mean_l = 0;
  for (const std::size_t i : use) {
    mean_x += x[i];
    mean_l += l[i];
  }
  const double n = static_cast<double>(use.size());
  mean_x /= n;
  mean_l /= n;
  double sxx = 0, sxl = 0;
  for (const std::size_t i : use) {
    sxx += (x[i] - mean_x) * (x[i] - mean_x);
    sxl += (x[i] - mean_x) * (l[i] - mean_l);
  }
  GenicamLine line;
  line.drift = fit_drift && sxx > 0 ? sxl / sxx : 0.0;
  line.intercept = mean_l - line.drift * mean_x;
  return line;
}

// The least-delayed pair of each of `segments` equal stretches of camera
// time, below the line of slope `slope` (in l = y − x).
std::vector<std::size_t> genicam_segment_minima(const std::vector<double>& x, const std::vector<double>& l,
                                                std::size_t segments, double slope) {
  const double width = x.back() / static_cast<double>(segments);
  std::vector<std::size_t> minima(segments, x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const auto k = std::min(segments - 1, static_cast<std::size_t>(x[i] / width));
    if (minima[k] == x.size() || l[i] - slope * x[i] < l[minima[k]] - slope * x[minima[k]]) minima[k] = i;
  }
  std::erase(minima, x.size());  // stretches thinning left empty
  return minima;
}

// The lower envelope. Its slope: least squares through the least-delayed
// arrival of each stretch of camera time (spread over the span, so the
// drift has its lever arm), leaving out stretches whose least delay is far
// above the others' (a stretch under load throughout). Its offset: the
// line moved down until it lies under every arrival, so it passes through
// the least-delayed one and no mapped time is after its frame arrived.
// `minima` ends as the stretches' least-delayed pairs it was fitted to.
GenicamLine genicam_lower_envelope(const std::vector<double>& x, const std::vector<double>& l, bool fit_slope,
                                   std::vector<std::size_t>& minima) {
  double slope = 0;
  minima.assign(1, static_cast<std::size_t>(std::min_element(l.begin(), l.end()) - l.begin()));
  const std::size_t segments = std::clamp<std::size_t>(x.size() / kGenicamPairsPerSegment, 2, kGenicamSegments);
  if (fit_slope && x.back() > 0) {
    for (int round = 0; round < 3; ++round) {  // the minima move as the slope settles
      minima = genicam_segment_minima(x, l, segments, slope);
      if (minima.size() < 2) break;
      const GenicamLine through_minima = genicam_least_squares(x, l, minima, true);
      double fitted = through_minima.drift;
      std::vector<double> above;
      for (const std::size_t i : minima) above.push_back(l[i] - through_minima.at(x[i]));
      std::vector<double> sorted = above;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      const double median = sorted[sorted.size() / 2];
      for (double& a : sorted) a = std::abs(a - median);
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      const double limit = median + 3 * 1.4826 * sorted[sorted.size() / 2] + 1e3;  // 3 σ by the MAD, and 1 µs
      std::vector<std::size_t> kept;
      for (std::size_t j = 0; j < minima.size(); ++j) {
        if (above[j] <= limit) kept.push_back(minima[j]);
      }
      if (kept.size() >= 2 && kept.size() < minima.size()) {
        minima = kept;
        fitted = genicam_least_squares(x, l, minima, true).drift;
      }
      slope = fitted;
    }
  }
  GenicamLine line;
  line.drift = slope;
  line.intercept = l[0] - slope * x[0];
  for (std::size_t i = 1; i < x.size(); ++i) line.intercept = std::min(line.intercept, l[i] - slope * x[i]);
  return line;
}

}  // namespace

GenicamClockMapping::GenicamClockMapping(Pairs kind, std::size_t max_pairs)
    : kind_(kind), max_pairs_(std::max<std::size_t>(max_pairs, 4)) {}

void GenicamClockMapping::thin() {
  // The older half thinned to one pair in two: the fit keeps its span. Of
  // two arrivals the later-delivered one can only blur the envelope.
  const std::size_t half = pairs_.size() / 2;
  const double slope = fit_ ? 1.0 + fit_->drift : 1.0;
  std::size_t kept = 1;
  for (std::size_t i = 1; i + 1 < half; i += 2) {
    const Pair& a = pairs_[i];
    const Pair& b = pairs_[i + 1];
    const bool a_lower = static_cast<double>(a.host_ns - b.host_ns) < slope * static_cast<double>(a.camera_ns - b.camera_ns);
    pairs_[kept++] = kind_ == Pairs::kArrivals && a_lower ? a : b;
  }
  unthinned_from_ = kept;
  for (std::size_t i = half; i < pairs_.size(); ++i) pairs_[kept++] = pairs_[i];
  pairs_.resize(kept);
}

void GenicamClockMapping::add(std::int64_t camera_ns, std::int64_t host_ns) {
  if (pairs_.size() >= max_pairs_) thin();
  // Kept in camera-time order (the envelope's hull needs it): a frame out
  // of order, which a stream should not deliver, goes where it belongs.
  auto at = pairs_.end();
  if (!pairs_.empty() && camera_ns < pairs_.back().camera_ns) {
    at = std::upper_bound(pairs_.begin(), pairs_.end(), camera_ns,
                          [](std::int64_t c, const Pair& p) { return c < p.camera_ns; });
    if (static_cast<std::size_t>(at - pairs_.begin()) < unthinned_from_) ++unthinned_from_;
  }
  pairs_.insert(at, {camera_ns, host_ns});
  fit_.reset();
}

void GenicamClockMapping::clear() {
  pairs_.clear();
  unthinned_from_ = 0;
  fit_.reset();
}

void GenicamClockMapping::refit() const {
  Fit f;
  f.kind = kind_;
  f.camera_origin_ns = pairs_.front().camera_ns;
  const std::int64_t host_origin = pairs_.front().host_ns;
  // Relative to the first pair, in double: 10 minutes is 6e11 ns, well
  // inside double's 53 bits.
  std::vector<double> x, l;
  std::vector<std::size_t> use(pairs_.size());
  for (std::size_t i = 0; i < pairs_.size(); ++i) {
    x.push_back(static_cast<double>(pairs_[i].camera_ns - f.camera_origin_ns));
    l.push_back(static_cast<double>(pairs_[i].host_ns - host_origin) - x.back());
    use[i] = i;
  }
  // Drift is fitted once the pairs span a second: over less, latency
  // jitter would dominate it (100 µs over 10 ms is 1 %). Before, an offset.
  const bool spans = pairs_.back().camera_ns - f.camera_origin_ns >= kGenicamMinDriftSpanNs;
  const GenicamLine line =
      kind_ == Pairs::kArrivals ? genicam_lower_envelope(x, l, spans, use) : genicam_least_squares(x, l, use, spans);
  f.drift = line.drift;
  f.host_at_origin_ns = static_cast<double>(host_origin) + line.intercept;
  double sum_sq = 0;
  for (const std::size_t i : use) {
    const double r = l[i] - line.at(x[i]);
    sum_sq += r * r;
    f.residual_max_ns = std::max(f.residual_max_ns, std::abs(r));
  }
  f.residual_rms_ns = std::sqrt(sum_sq / static_cast<double>(use.size()));
  f.pairs = pairs_.size();
  f.span_ns = pairs_.back().camera_ns - f.camera_origin_ns;
  if (kind_ == Pairs::kArrivals) {
    f.envelope_pairs = use.size();
    std::vector<double> latency;
    for (std::size_t i = unthinned_from_; i < pairs_.size(); ++i) latency.push_back(l[i] - line.at(x[i]));
    f.latency_pairs = latency.size();
    f.latency_max_ns = *std::max_element(latency.begin(), latency.end());
    std::nth_element(latency.begin(), latency.begin() + latency.size() / 2, latency.end());
    f.latency_median_ns = latency[latency.size() / 2];
  }
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
  std::string text = fmt::format(
      "offset {:+.6f} s at camera time {} ns, drift {:+.3f} ppm, residual {:.0f} µs RMS ({:.0f} µs max) "
      "over {} pairs in {:.1f} s",
      offset_s, fit.camera_origin_ns, fit.drift * 1e6, fit.residual_rms_ns * 1e-3, fit.residual_max_ns * 1e-3,
      fit.pairs, static_cast<double>(fit.span_ns) * 1e-9);
  if (fit.kind == Pairs::kArrivals) {
    text += fmt::format(
        "; fitted under every arrival (their lower envelope; the residual is the spread above it of the "
        "least-delayed arrivals of {} stretches of the run), arrivals lag it by {:.0f} µs median ({:.0f} µs "
        "max) over the last {}; the camera's least latency from stamp to arrival is not seen without a latch",
        fit.envelope_pairs, fit.latency_median_ns * 1e-3, fit.latency_max_ns * 1e-3, fit.latency_pairs);
  }
  return text;
}

}  // namespace bosfuse::acquisition
