#include "app/sequence_file.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>

#include "app/progress_display.h"
#include "app/ranks.h"
#include "app/run_control.h"
#include "report/sequence_export.h"

namespace bosfuse::app {
namespace {

class SequenceFileSink : public pipeline::SequenceSink {
 public:
  explicit SequenceFileSink(std::filesystem::path hdf5_path) : hdf5_path_(std::move(hdf5_path)) {}

  void open(const pipeline::SequenceLayout& layout) override {
    grid_ = layout.grid;
    writer_.emplace(hdf5_path_, report::SequenceExportInfo{layout.reference, layout.settings_json, layout.frame_names,
                                                           layout.grid});
    display_.emplace();
  }
  void write(std::size_t index, std::size_t count, const pipeline::SequenceFrameResult& result) override {
    writer_->write(index, result);
    display_->step(index + 1, count, result.name);
  }
  void warn(const std::string& line) override {
    if (spdlog::should_log(spdlog::level::info)) {
      display_->note("warning: " + line);
    } else {
      spdlog::warn("{}", line);
    }
  }
  void frames_done() override { display_->finish(); }
  void commit() override {
    const auto written = writer_->commit();
    spdlog::info("wrote {} and {}: {} of {} frames evaluated, on a {}x{} grid", written.hdf5_path.string(),
                 written.xdmf_path.string(), written.frames_ok, written.frames, grid_.cols, grid_.rows);
  }

 private:
  std::filesystem::path hdf5_path_;
  fusion::GridGeometry grid_;
  std::optional<report::SequenceFieldWriter> writer_;
  // Made with the file, so its elapsed time starts there; ends first, so a
  // stopped run's last line stays on the screen before the file is dropped.
  std::optional<ProgressDisplay> display_;
};

void write_on_lead_rank(const pipeline::SequenceRunOptions& options, const std::string& hdf5_path) {
  SequenceFileSink sink(hdf5_path);
  const auto summary = pipeline::run_sequence(options, sink);
  if (!summary.complete())
    throw CommandFailure(kExitStopped, "stopped on request; nothing was written to " + hdf5_path);
  if (summary.frames_failed > 0) {
    throw CommandFailure(
        kExitSomeFramesFailed,
        fmt::format("{} of {} frames could not be evaluated (named above; their status is in {}:/status)",
                    summary.frames_failed, summary.frames, hdf5_path));
  }
}

}  // namespace

pipeline::SequenceRunOptions sequence_run_options(const std::string& settings_file, const EvaluatorArguments& args) {
  pipeline::SequenceRunOptions options;
  options.settings_file = settings_file;
  options.settings = pipeline::resolve_runless_settings(settings_file, settings_overrides(args));
  if (options.settings.probes_only) {
    throw std::runtime_error(settings_file +
                             ": mode = \"probes\" needs a run's thermocouples; a sequence is evaluated in full fields");
  }
  apply_evaluation_choices(args, options.settings.evaluator);
  if (const auto problem = options.settings.evaluator.Validate(); !problem.empty()) {
    throw CLI::ValidationError(problem);
  }
  options.subpixel = args.subpixel;
  options.interpolator = args.interpolator;
  options.stop = &stop_requested_by_signal();
  return options;
}

void write_sequence_file(pipeline::SequenceRunOptions options, const std::string& hdf5_path,
                         std::optional<int> threads) {
  run_on_ranks(
      threads,
      [&](pipeline::FrameDistributor* distributor) {
        options.distributor = distributor;
        write_on_lead_rank(options, hdf5_path);
      },
      [&](const pipeline::Bytes& plan) { return pipeline::sequence_frame_work(options, plan); });
}

}  // namespace bosfuse::app
