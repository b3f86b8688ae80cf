// bosfuse bench: a quick run-time-against-error sweep on synthetic pairs, so
// a user can see what window size, passes and method cost and buy on this
// machine. The full study is bench/bos_bench (see docs/BENCHMARKS.md).
// The table goes to standard output once every case has run, so progress
// on a terminal (standard error) never lands between its rows.

#include <fmt/format.h>

#include <iostream>

#include "app/command.h"
#include "app/progress_display.h"
#include "sim/evaluation_study.h"

namespace bosfuse::app {
namespace {

struct BenchArgs {
  int size_px = 256;
  double noise = 0.01;
  double dot_px = 3;
};

struct SweepCase {
  std::string name;
  fusion::EvaluatorOptions evaluator;
  int window = 0;
  int passes = 1;
};

std::vector<SweepCase> sweep_cases() {
  std::vector<SweepCase> cases;
  for (const int window : {32, 16, 8}) {
    for (const int passes : {1, 3}) cases.push_back({"xcorr", {}, window, passes});
  }
  fusion::EvaluatorOptions flow;
  flow.method = fusion::Method::kOpticalFlow;
  for (const auto algorithm : {fusion::FlowAlgorithm::kDis, fusion::FlowAlgorithm::kFarneback}) {
    flow.flow.algorithm = algorithm;
    cases.push_back({"flow-" + fusion::to_string(algorithm), flow, 16, 1});
  }
  return cases;
}

std::string sweep_row(const BenchArgs& args, SweepCase c) {
  sim::StudyCase study;
  c.evaluator.set_grid(c.window, c.window / 2);
  c.evaluator.xcorr.passes = c.passes;
  study.evaluator = c.evaluator;
  study.size_px = args.size_px;
  study.noise_std = args.noise;
  study.dot_diameter_px = args.dot_px;
  study.shifts_px = {0.0, 0.2, 0.4, 0.6, 0.8, 1.0};
  const auto r = sim::run_uniform_study(study);
  return fmt::format("{:<14} {:>4} {:>6} {:>12.0f} {:>10.4f} {:>9.4f} {:>9.4f}\n", c.name, c.window, c.passes,
                     r.vectors_per_s, r.max_abs_bias_px, r.rms_px, r.p95_px);
}

void bench(const BenchArgs& args) {
  const auto cases = sweep_cases();
  constexpr int kStepWindows[] = {32, 16, 8};
  const std::size_t total = cases.size() + std::size(kStepWindows);
  std::size_t done = 0;
  ProgressDisplay progress;
  std::string table =
      fmt::format("synthetic {0}x{0} pairs, dots {1} px, noise {2:.1f}% of full scale, uniform shifts 0..1 px\n",
                  args.size_px, args.dot_px, 100 * args.noise);
  table += fmt::format("{:<14} {:>4} {:>6} {:>12} {:>10} {:>9} {:>9}\n", "method", "IW", "passes", "vectors/s",
                       "max|bias|", "RMS", "p95");
  for (const auto& c : cases) {
    progress.step(done++, total,
                  fmt::format("{}, IW {}, {} pass{}", c.name, c.window, c.passes, c.passes > 1 ? "es" : ""));
    table += sweep_row(args, c);
  }
  table += "\nstep test (128x128, right half shifted 1 px): rise width 10%-90%\n";
  for (const int window : kStepWindows) {
    progress.step(done++, total, fmt::format("step test, IW {}", window));
    fusion::EvaluatorOptions options;
    options.set_grid(window, 1);
    table += fmt::format("  IW {:>2}: {:.1f} px\n", window, sim::run_step_study(options).rise_width_px);
  }
  progress.step(done, total, "done");
  progress.finish();
  std::cout << table << std::flush;
}

void add_bench(CLI::App& root) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = root.add_subcommand("bench", "Quick sweep of evaluation speed and error on synthetic image pairs");
  cmd->add_option("--size", args->size_px, "Image size, px")->check(CLI::Range(64, 4096))->capture_default_str();
  cmd->add_option("--noise", args->noise, "Image noise, fraction of full scale")->capture_default_str();
  cmd->add_option("--dot-px", args->dot_px, "Dot diameter, px")->capture_default_str();
  cmd->callback([args] { bench(*args); });
}

BOSFUSE_COMMAND(add_bench);

}  // namespace
}  // namespace bosfuse::app
