#include "sim/evaluation_study.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

namespace bosfuse::sim {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int window_of(const fusion::EvaluatorOptions& e) {
  return e.method == fusion::Method::kCrossCorrelation ? e.xcorr.window_px : e.flow.window_px;
}

// First x where the profile crosses `level` going up, linearly interpolated.
double crossing(const std::vector<double>& x, const std::vector<double>& p, double level) {
  for (std::size_t i = 1; i < p.size(); ++i) {
    if (p[i - 1] < level && p[i] >= level) return x[i - 1] + (level - p[i - 1]) / (p[i] - p[i - 1]) * (x[i] - x[i - 1]);
  }
  return p.empty() ? 0.0 : (level <= p.front() ? x.front() : x.back());
}

}  // namespace

std::string StudyCase::describe() const {
  const bool xcorr = evaluator.method == fusion::Method::kCrossCorrelation;
  return fmt::format("{} IW {} passes {} noise {:.3f} dot {:.1f} px coverage {:.2f}",
                     xcorr ? "xcorr" : "flow-" + fusion::to_string(evaluator.flow.algorithm), window_of(evaluator),
                     xcorr ? evaluator.xcorr.passes : 1, noise_std, dot_diameter_px, coverage);
}

StudyResult run_uniform_study(const StudyCase& study) {
  StudyResult result;
  std::vector<double> magnitudes;
  const int window = window_of(study.evaluator);
  double sum_sq = 0;
  for (std::size_t i = 0; i < study.shifts_px.size(); ++i) {
    PairOptions options;
    options.pattern.width_px = options.pattern.height_px = study.size_px;
    options.pattern.dot_diameter_px = study.dot_diameter_px;
    options.pattern.coverage = study.coverage;
    options.pattern.seed = study.seed + i;
    options.noise_std = study.noise_std;
    options.noise_seed = study.seed * 31 + i;
    options.field = DisplacementModel::uniform(study.shifts_px[i], study.shifts_px[i]);
    const SyntheticPair pair = render_pair(options);
    const auto start = std::chrono::steady_clock::now();
    const auto evaluated = fusion::evaluate_displacement(pair.reference, pair.measurement, study.evaluator);
    result.seconds += seconds_since(start);
    result.vectors += evaluated.field.size();
    double sum_u = 0, sum_v = 0;
    std::size_t counted = 0;
    result.valid += evaluated.field.count_valid();
    for (const auto& v : evaluated.field.vectors) {
      const bool inner =
          v.x_px >= window && v.y_px >= window && v.x_px <= study.size_px - window && v.y_px <= study.size_px - window;
      if (!v.valid() || !inner) continue;
      const double du = v.u_px - study.shifts_px[i], dv = v.v_px - study.shifts_px[i];
      sum_u += du;
      sum_v += dv;
      sum_sq += du * du + dv * dv;
      magnitudes.push_back(std::hypot(du, dv));
      if (magnitudes.back() > 0.5) ++result.wrong;
      if ((v.sigma_u_px > 0 && std::abs(du) > 3 * v.sigma_u_px) ||
          (v.sigma_v_px > 0 && std::abs(dv) > 3 * v.sigma_v_px)) {
        ++result.beyond_3_sigma;
      }
      ++counted;
    }
    result.compared += counted;
    if (counted) {
      result.max_abs_bias_px = std::max({result.max_abs_bias_px, std::abs(sum_u / counted), std::abs(sum_v / counted)});
    }
  }
  result.vectors_per_s = result.seconds > 0 ? result.vectors / result.seconds : 0;
  if (!magnitudes.empty()) {
    result.rms_px = std::sqrt(sum_sq / magnitudes.size());
    const auto p95 = magnitudes.begin() + static_cast<long>(0.95 * (magnitudes.size() - 1));
    std::nth_element(magnitudes.begin(), p95, magnitudes.end());
    result.p95_px = *p95;
  }
  return result;
}

double rise_width_px(const std::vector<double>& x, const std::vector<double>& profile, double low, double high) {
  const double span = high - low;
  return crossing(x, profile, low + 0.9 * span) - crossing(x, profile, low + 0.1 * span);
}

StepResult run_step_study(const fusion::EvaluatorOptions& evaluator, double dot_diameter_px, double noise_std,
                          std::uint64_t seed) {
  constexpr int kSize = 128;
  constexpr double kStepX = 64;
  PairOptions options;
  options.pattern.width_px = options.pattern.height_px = kSize;
  options.pattern.dot_diameter_px = dot_diameter_px;
  options.pattern.seed = seed;
  options.noise_std = noise_std;
  options.field = DisplacementModel::step(kStepX, 1.0, 0.0);
  const SyntheticPair pair = render_pair(options);
  fusion::EvaluatorOptions fine = evaluator;
  fine.set_grid(window_of(evaluator), 1);
  const auto evaluated = fusion::evaluate_displacement(pair.reference, pair.measurement, fine);
  std::map<double, std::pair<double, int>> columns;  // x → (sum u, count)
  for (const auto& v : evaluated.field.vectors) {
    if (!v.valid()) continue;
    auto& c = columns[v.x_px];
    c.first += v.u_px;
    ++c.second;
  }
  StepResult result;
  double plateau_error = 0;
  int plateau_count = 0;
  const int window = window_of(evaluator);
  for (const auto& [x, sum] : columns) {
    const double u = sum.first / sum.second;
    result.x_px.push_back(x);
    result.u_px.push_back(u);
    if (std::abs(x - kStepX) > window) {
      plateau_error += std::abs(u - (x >= kStepX ? 1.0 : 0.0));
      ++plateau_count;
    }
  }
  result.rise_width_px = rise_width_px(result.x_px, result.u_px, 0.0, 1.0);
  result.plateau_error_px = plateau_count ? plateau_error / plateau_count : 0.0;
  return result;
}

}  // namespace bosfuse::sim
