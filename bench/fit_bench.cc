// Newton's-law fit speed: the whole fit_newton() call (cleaning, start
// values, Ceres solve, covariance, diagnostics) on synthetic cooling records
// of 1,000 to 1,000,000 points. Figures go into docs/BENCHMARKS.md.

#include <benchmark/benchmark.h>

#include "fitting/newton_fit.h"
#include "tests/support/cooling_curve.h"

namespace {

using bosfuse::fitting::fit_newton;
using bosfuse::fitting::NewtonFitOptions;
using bosfuse::fitting::RobustLoss;

// 5 time constants over the record whatever its length, 0.1 °C noise,
// epoch-scale times as a logger stores them.
bosfuse::testing::CoolingRecord record(std::size_t n) {
  const bosfuse::testing::CoolingCurve curve{22.0, 80.0, 0.01};
  const double dt_s = 500.0 / static_cast<double>(n);
  return bosfuse::testing::sample_cooling(curve, n, dt_s, 0.1, 42, 1.8e9);
}

void fit_benchmark(benchmark::State& state, const NewtonFitOptions& options) {
  const auto r = record(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    auto fit = fit_newton(r.time_s, r.temperature_c, options);
    if (!fit.ok()) state.SkipWithError(fit.summary.message.c_str());
    benchmark::DoNotOptimize(fit);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_NewtonFit(benchmark::State& state) { fit_benchmark(state, {}); }

void BM_NewtonFitHuber(benchmark::State& state) {
  NewtonFitOptions options;
  options.loss = RobustLoss::huber(0.2);
  fit_benchmark(state, options);
}

BENCHMARK(BM_NewtonFit)->Arg(1'000)->Arg(10'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_NewtonFitHuber)->Arg(10'000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
