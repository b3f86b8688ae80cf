// bosfuse demo: the main job, runnable without hardware. The demo's
// experiment (sim/demo_setup.h) is recorded through the real device paths
// into a new run folder, a few minutes of cooling in a few seconds
// (sim/demo_recording.h), processed as a user would and reported; it ends
// with the report's path and the fitted cooling rates beside the true one.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/clock.h"
#include "app/command.h"
#include "app/output_stream.h"
#include "app/progress_display.h"
#include "app/run_control.h"
#include "app/served_view.h"
#include "pipeline/process.h"
#include "report/report.h"
#include "report/run_input.h"
#include "sim/demo_recording.h"
#include "sim/demo_truth.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct DemoArgs {
  std::string out = "demo-run";
  std::string live;  // --live HOST:PORT; empty: no live page
  sim::DemoOptions demo;
};

// Processes the run as a user would (its settings stored with the results,
// so `bosfuse process RUN` repeats them) and writes the report. False when
// Ctrl-C stopped the processing.
bool process_and_report(const sim::DemoOptions& demo, const sim::DemoSetup& setup, const std::filesystem::path& run_dir,
                        ProgressDisplay& display) {
  cv::imwrite((run_dir / "holder-mask.png").string(), setup.model->holder_mask());
  pipeline::ProcessOptions process;
  process.overrides.window_px = sim::kDemoWindowPx;
  process.overrides.step_px = 8;
  process.overrides.mask = "holder-mask.png";
  process.stop = &stop_requested_by_signal();
  process.progress = [&](const pipeline::ProcessProgress& p) {
    p.frame ? display.step(p.done, p.total, p.line) : display.note(p.line);
  };
  display.note("processing (full displacement and temperature fields) ...");
  const auto processed = pipeline::process_run(run_dir, process);
  display.finish();
  // The processing's summary is a message; the demo's data is its table of rates.
  display.note(processed.text);
  if (!processed.complete) return false;

  report::RunReportOptions input_options;
  input_options.map_times_s = {0.1 * demo.experiment_s, 0.6 * demo.experiment_s};  // early and late in the cooling
  display.note("writing the report ...");
  report::write_report(report::build_report_input(storage::RunStore::open(run_dir), input_options), {},
                       run_dir / "report");
  return true;
}

// Said before the recording starts, so a user does not wait for a run
// whose BOS probes cannot be fitted.
void warn_when_too_short_for_bos_fits(const sim::DemoOptions& demo) {
  const int frames = demo.frames_after_reference();
  if (frames >= sim::kFramesForABosFit) return;
  spdlog::warn(
      "demo: {:g} s of cooling at one frame per {:g} s gives {} frame(s) after the reference, and a BOS fit needs "
      "at least {}: the BOS probes will not be fitted; give --experiment-time {:g}s or more, or a shorter "
      "--frame-interval",
      demo.experiment_s, demo.frame_interval_s, frames, sim::kFramesForABosFit,
      sim::kFramesForABosFit * demo.frame_interval_s);
}

void run_demo(const DemoArgs& args) {
  warn_when_too_short_for_bos_fits(args.demo);
  refuse_standard_output(args.out, "--out", "the demo records a run, which is a folder");
  // A new folder per demo, so running it again never touches an earlier run.
  const std::filesystem::path run_dir =
      std::filesystem::path(args.out) / acquisition::format_compact_utc(acquisition::utc_now_ns());
  check_new_run_output(run_dir.string(), "--out");  // the new run lands on no run's own files
  const sim::DemoSetup setup = sim::demo_setup(args.demo.experiment_s);
  ProgressDisplay display;
  // The live page, when asked, starts with the run and serves on through processing and report.
  std::unique_ptr<ServedView> live;
  const auto summary = sim::record_demo(args.demo, setup, run_dir,
                                        {.note = [&](const std::string& line) { display.note(line); },
                                         .run_created = [&] { live = start_live_view(run_dir, args.live); },
                                         .stop = &stop_requested_by_signal()});
  // The logger's summary is progress (stderr); the demo's result, on
  // stdout, is the table of fitted rates beside the truth and where the run
  // and its report are (the folder is the demo's to choose).
  std::cerr << summary.BriefReport() << "\n";
  sim::write_truth(run_dir, args.demo, setup);
  if (stop_requested_by_signal()) {
    throw CommandFailure(kExitStopped, "stopped: the run is recorded up to here in " + run_dir.string() +
                                           "; `bosfuse process " + run_dir.string() + "` processes it");
  }
  if (!process_and_report(args.demo, setup, run_dir, display)) {
    throw CommandFailure(kExitStopped,
                         "stopped while processing; `bosfuse process " + run_dir.string() + " --resume` continues");
  }
  sim::print_rates_beside_truth(std::cout, run_dir, sim::true_plume_cooling_rate(setup));
  std::cout << "\nrun:     " << run_dir.string() << "\n"
            << "report:  " << (run_dir / "report" / "report.html").string() << "\n";
}

double seconds_within(const std::string& text, const char* option, double low_s, double high_s) {
  const double s = std::chrono::duration<double>(parse_duration(text)).count();
  if (s < low_s || s > high_s) {
    throw std::runtime_error(fmt::format("{} {}: expected {:g} s to {:g} s", option, text, low_s, high_s));
  }
  return s;
}

void add_demo(CLI::App& root) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = root.add_subcommand(
      "demo", "Simulate a convection experiment and record it through the real device paths (no hardware needed)");
  cmd->add_option("--out,-o", args->out,
                  "Folder for demo runs: each demo records a new run in a timestamped folder inside it, so an "
                  "earlier run is never touched")
      ->capture_default_str();
  auto experiment_time = std::make_shared<std::string>("4m");
  auto frame_interval = std::make_shared<std::string>("10s");
  add_live_option(*cmd, args->live);
  cmd->add_option("--experiment-time", *experiment_time, "Cooling to simulate, experiment time (20s .. 1h)")
      ->capture_default_str();
  cmd->add_option("--speed", args->demo.speed, "Times faster than real time (the run's time scale)")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--frame-interval", *frame_interval, "Experiment time between frames (1s .. 10m)")
      ->capture_default_str();
  cmd->add_option("--camera", args->demo.camera,
                  "How frames are recorded: virtual (in process) or genicam (a simulated GigE Vision camera on "
                  "127.0.0.1 read through Aravis, as a lab camera is)")
      ->check(CLI::IsMember({"virtual", "genicam"}))
      ->capture_default_str();
  cmd->add_option("--seed", args->demo.seed,
                  "Seed of the random background and the thermocouples' noise: the same seed simulates the same "
                  "signals (default: the start time, a new run each time)");
  cmd->callback([args, experiment_time, frame_interval] {
    args->demo.experiment_s = seconds_within(*experiment_time, "--experiment-time", 20, 3600);
    args->demo.frame_interval_s = seconds_within(*frame_interval, "--frame-interval", 1, 600);
    run_demo(*args);
  });
}

BOSFUSE_COMMAND(add_demo);

}  // namespace
}  // namespace bosfuse::app
