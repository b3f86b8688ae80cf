#pragma once
// Run time against error: evaluates synthetic pairs with known displacement
// and reports speed and accuracy, for the benchmarks (bench/bos_bench.cc)
// and `bosfuse bench`. Also the paper's resolution study: the step test,
// whose rise width (distance between the 10% and 90% points of the evaluated
// shift across a one-pixel step) is the effective spatial resolution.

#include <cstdint>
#include <string>
#include <vector>

#include "fusion/displacement_evaluator.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::sim {

struct StudyCase {
  fusion::EvaluatorOptions evaluator;  // method, window, step, passes...
  int size_px = 256;
  double dot_diameter_px = 3;
  double coverage = 0.5;
  double noise_std = 0.01;
  std::uint64_t seed = 11;
  // Uniform shifts evaluated, each along x and y at once (u = v = s).
  std::vector<double> shifts_px{0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};

  std::string describe() const;
};

struct StudyResult {
  std::size_t vectors = 0;   // over all shifts
  std::size_t valid = 0;     // flagged ok, whole field
  std::size_t compared = 0;  // valid and a window away from the edge: the errors are over these
  double seconds = 0;        // evaluation only, rendering excluded
  double vectors_per_s = 0;
  double max_abs_bias_px = 0;  // the worst |mean error| of u or v over the shifts
  double rms_px = 0;           // of the error magnitude, all valid vectors
  double p95_px = 0;           // 95th percentile of the error magnitude
  // Of the compared vectors: more than 0.5 px from the truth (a wrong
  // peak), and a component off by more than 3 of its σ (where σ is given).
  std::size_t wrong = 0;
  std::size_t beyond_3_sigma = 0;
};

// Errors are taken against the truth averaged over each window, on valid
// vectors at least a window away from the image edge.
StudyResult run_uniform_study(const StudyCase& study);

struct StepResult {
  double rise_width_px = 0;     // 10%→90% distance of the column-averaged u across the step
  double plateau_error_px = 0;  // mean |u − truth| more than a window away from the step
  std::vector<double> x_px;     // the profile
  std::vector<double> u_px;
};

// The paper's test: a 128×128 pattern whose right half (x ≥ 64) moves by
// 1 px in x, evaluated on a 1 px grid.
StepResult run_step_study(const fusion::EvaluatorOptions& evaluator, double dot_diameter_px = 3,
                          double noise_std = 0.01, std::uint64_t seed = 5);

// The 10%→90% rise width of a profile rising from `low` to `high`; NaN-free:
// returns the profile's extent when it never crosses a level.
double rise_width_px(const std::vector<double>& x, const std::vector<double>& profile, double low, double high);

}  // namespace bosfuse::sim
