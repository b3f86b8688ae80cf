// The temperature field of a 16 MP frame (4928×3264, IW 16 px, step 8 px:
// 615×407 nodes, ~250 k unknowns): the Poisson solve that process runs for
// every frame, by solver (0: CHOLMOD supernodal, 1: Eigen simplicial LDLT).
//   BM_TemperatureFieldOneShot/s       recover_temperature_field: analysis (AMD ordering), factorisation and
//                                      solve each call
//   BM_TemperatureFieldPerFrame/s/m    one TemperatureFieldSolver over a run's frames, each with new
//                                      displacements; m = 0: the same unmeasured nodes every frame (the
//                                      factor is reused, only solved), m = 1: they change every frame
//                                      (refactorised on the kept analysis; CHOLMOD orders by nested dissection)
//   BM_TemperatureFieldWeighted/e      the same solver over frames whose vectors carry σ (log-normal across the
//                                      field, new every frame, as an evaluator's are), unmeasured nodes the same:
//                                      weighted, so refactorised every frame; e = 1: also σ of T at every node
//                                      (64 noise draws solved in blocks of 16)
//   BM_TemperatureFieldSigmaDrift/j/t  σ as a run's are: one log-normal pattern across the field, each frame's
//                                      σ that pattern times a log-normal jitter of j % (new every frame), the
//                                      first frame the pattern itself; t > 0: frames solved by conjugate gradients
//                                      on the kept factor to a relative residual 1e-t where the weights moved
//                                      little enough (the default, t = 10), t = 0: refactorised every frame;
//                                      max_dT_c: the largest |ΔT| of any node from the exact weighted solve
// Run: build/bench/temperature_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// Figures go into docs/BENCHMARKS.md.

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_field.h"
#include "fusion/temperature_field.h"

namespace {

using namespace bosfuse::fusion;

constexpr int kRows = 407, kCols = 615;  // 16 MP, IW 16, step 8
constexpr double kStepPx = 8;

BosGeometry geometry() {
  BosGeometryOptions o;
  o.z_d_m = 0.5;
  o.depth_m = 0.1;
  o.magnification = 0.15;
  o.pixel_pitch_um = 5.0;
  return BosGeometry(o);
}

// A hot plume's shifts (a Gaussian's gradient, inward), its centre moving
// with the frame; with `masked_block` a 20×20-node block at a place that
// depends on the frame is unmeasured.
DisplacementField frame_field(int frame, bool masked_block) {
  DisplacementField field;
  field.rows = kRows;
  field.cols = kCols;
  field.vectors.resize(static_cast<std::size_t>(kRows) * kCols);
  const double cx = 2400 + 40 * frame, cy = 1600 - 25 * frame, sigma = 500, amplitude_px = 1.5;
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      DisplacementVector& v = field.at(r, c);
      v.x_px = 8 + c * kStepPx;
      v.y_px = 8 + r * kStepPx;
      const double dx = v.x_px - cx, dy = v.y_px - cy;
      const double g = amplitude_px * std::exp(-(dx * dx + dy * dy) / (2 * sigma * sigma)) / sigma;
      v.u_px = -g * dx;
      v.v_px = -g * dy;
    }
  }
  if (masked_block) {
    const int r0 = 100 + 30 * (frame % 5), c0 = 200 + 40 * (frame % 5);
    for (int r = r0; r < r0 + 20; ++r) {
      for (int c = c0; c < c0 + 20; ++c) field.at(r, c).flag = VectorFlag::kMasked;
    }
  }
  return field;
}

TemperatureFieldOptions options_for(std::int64_t solver) {
  TemperatureFieldOptions o;
  o.solver = solver == 0 ? PoissonSolver::kCholmodSupernodal : PoissonSolver::kEigenSimplicial;
  return o;
}

void BM_TemperatureFieldOneShot(benchmark::State& state) {
  const BosGeometry g = geometry();
  const auto options = options_for(state.range(0));
  const DisplacementField field = frame_field(0, true);
  for (auto _ : state) benchmark::DoNotOptimize(recover_temperature_field(field, g, options));
  state.SetLabel(state.range(0) == 0 ? "cholmod supernodal" : "eigen simplicial");
}

void BM_TemperatureFieldPerFrame(benchmark::State& state) {
  const BosGeometry g = geometry();
  const bool masks_change = state.range(1) != 0;
  constexpr int kFrames = 6;
  std::vector<DisplacementField> frames;
  for (int f = 0; f < kFrames; ++f) frames.push_back(frame_field(f, true));
  if (!masks_change) {
    for (int f = 1; f < kFrames; ++f) {
      for (std::size_t i = 0; i < frames[f].size(); ++i) frames[f].vectors[i].flag = frames[0].vectors[i].flag;
    }
  }
  TemperatureFieldSolver solver(g, options_for(state.range(0)));
  solver.recover(frames[kFrames - 1]);  // the run's first frame, analysed outside the timing
  int f = 0;
  for (auto _ : state) benchmark::DoNotOptimize(solver.recover(frames[f++ % kFrames]));
  state.counters["factorisations"] = solver.factorisations();
  state.SetLabel(std::string(state.range(0) == 0 ? "cholmod supernodal" : "eigen simplicial") +
                 (masks_change ? ", refactorised" : ", factor reused"));
}

void BM_TemperatureFieldWeighted(benchmark::State& state) {
  const BosGeometry g = geometry();
  constexpr int kFrames = 6;
  std::vector<DisplacementField> frames;
  std::mt19937_64 random(29);
  std::normal_distribution<double> normal;
  for (int f = 0; f < kFrames; ++f) {
    frames.push_back(frame_field(f, true));
    for (std::size_t i = 0; i < frames[f].size(); ++i) {
      DisplacementVector& v = frames[f].vectors[i];
      v.flag = frames[0].vectors[i].flag;
      v.sigma_u_px = 0.02 * std::exp(0.5 * normal(random));
      v.sigma_v_px = 0.02 * std::exp(0.5 * normal(random));
    }
  }
  TemperatureFieldOptions options = options_for(0);
  options.estimate_uncertainty = state.range(0) != 0;
  TemperatureFieldSolver solver(g, options);
  solver.recover(frames[kFrames - 1]);  // the run's first frame, analysed outside the timing
  int f = 0;
  double sampling_s = 0;
  for (auto _ : state) {
    const auto result = solver.recover(frames[f++ % kFrames]);
    sampling_s += result.summary.uncertainty_seconds;
    benchmark::DoNotOptimize(result);
  }
  state.counters["factorisations"] = solver.factorisations();
  state.counters["sigma_of_T_s"] = sampling_s / static_cast<double>(state.iterations());
  state.SetLabel(options.estimate_uncertainty ? "weighted, sigma of T (K = 64)" : "weighted");
}

void BM_TemperatureFieldSigmaDrift(benchmark::State& state) {
  const BosGeometry g = geometry();
  constexpr int kFrames = 6;
  const double jitter = static_cast<double>(state.range(0)) / 100;
  std::mt19937_64 random(29);
  std::normal_distribution<double> normal;
  DisplacementField pattern = frame_field(0, true);
  for (auto& v : pattern.vectors) {
    v.sigma_u_px = 0.02 * std::exp(0.5 * normal(random));
    v.sigma_v_px = 0.02 * std::exp(0.5 * normal(random));
  }
  std::vector<DisplacementField> frames;
  for (int f = 0; f < kFrames; ++f) {
    frames.push_back(frame_field(f, true));
    for (std::size_t i = 0; i < frames[f].size(); ++i) {
      DisplacementVector& v = frames[f].vectors[i];
      v.flag = pattern.vectors[i].flag;
      v.sigma_u_px = pattern.vectors[i].sigma_u_px * std::exp(jitter * normal(random));
      v.sigma_v_px = pattern.vectors[i].sigma_v_px * std::exp(jitter * normal(random));
    }
  }
  TemperatureFieldOptions options = options_for(0);
  options.iterative_tolerance = state.range(1) == 0 ? 0 : std::pow(10.0, -static_cast<double>(state.range(1)));
  TemperatureFieldSolver solver(g, options);
  solver.recover(pattern);  // the run's first frame, analysed and factorised outside the timing
  int f = 0;
  double iterations = 0, condition = 0;
  for (auto _ : state) {
    const auto result = solver.recover(frames[f++ % kFrames]);
    iterations += result.summary.solver_iterations;
    condition = std::max(condition, result.summary.kept_factor_condition);
    benchmark::DoNotOptimize(result);
  }
  state.counters["factorisations"] = solver.factorisations() - 1;
  state.counters["iterative_solves"] = solver.iterative_solves();
  state.counters["iterations"] = iterations / static_cast<double>(state.iterations());
  state.counters["condition_bound"] = condition;
  // How far the frames lie from the exact weighted solution (each frame factorised for its own σ).
  if (state.range(1) != 0) {
    TemperatureFieldSolver iterating(g, options), exact(g, options_for(0));
    iterating.recover(pattern);
    double largest_c = 0;
    for (const auto& frame : frames) {
      const auto a = iterating.recover(frame).field, b = exact.recover(frame).field;
      for (std::size_t i = 0; i < a.temperature_c.size(); ++i)
        largest_c = std::max(largest_c, std::abs(a.temperature_c[i] - b.temperature_c[i]));
    }
    state.counters["max_dT_c"] = largest_c;
  }
  state.SetLabel(state.range(1) != 0 ? "iterated on the kept factor" : "refactorised");
}

BENCHMARK(BM_TemperatureFieldOneShot)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TemperatureFieldPerFrame)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TemperatureFieldWeighted)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TemperatureFieldSigmaDrift)
    ->ArgsProduct({{2, 5, 10, 20}, {0, 6, 8, 10}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
