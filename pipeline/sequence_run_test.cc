#include "pipeline/sequence_run.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/shifted_pair.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

// What the sink was told, in the order it was told.
class RecordingSink : public SequenceSink {
 public:
  void open(const SequenceLayout& layout) override {
    this->layout = layout;
    calls.push_back("open");
  }
  void write(std::size_t index, std::size_t count, const SequenceFrameResult& result) override {
    calls.push_back(fmt::format("write {} of {}: {}", index, count, result.ok() ? "ok" : "failed"));
    results.push_back(result);
  }
  void warn(const std::string& line) override { warnings.push_back(line); }
  void frames_done() override { calls.push_back("frames done"); }
  void commit() override { calls.push_back("commit"); }

  SequenceLayout layout;
  std::vector<std::string> calls, warnings;
  std::vector<SequenceFrameResult> results;
};

// Evaluates every frame here, as one rank alone would, keeping the plan.
class LocalDistributor : public FrameDistributor {
 public:
  std::size_t run(const Bytes& plan, std::size_t count, const FrameWork& local, const TakeFrame& take,
                  const std::atomic<bool>*) override {
    this->plan = plan;
    for (std::size_t i = 0; i < count; ++i) take(i, local(i));
    return count;
  }
  std::string brief_report() const override { return "rank 0: every frame"; }

  Bytes plan;
};

class SequenceRun : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int k = 1; k <= 2; ++k) {
      testing::write_shifted_pair(k == 1 ? path("ref.png") : "", path("frames/f_" + std::to_string(k) + ".png"),
                                  {96, 64}, 0.5 * k, -0.25);
    }
    std::ofstream(path("frames/f_3.png")) << "not an image";
    options.reference = path("ref.png");
    options.sequence = path("frames");
    options.settings = resolve_runless_settings("", {});
  }
  std::string path(const std::string& name) const {
    std::filesystem::create_directories((dir.path() / name).parent_path());
    return (dir.path() / name).string();
  }

  testing::TempDir dir;
  SequenceRunOptions options;
};

TEST_F(SequenceRun, EveryFrameReachesTheSinkInOrderAndAFailedOneIsNamed) {
  RecordingSink sink;
  const auto summary = run_sequence(options, sink);
  EXPECT_TRUE(summary.complete());
  EXPECT_EQ(summary.frames, 3u);
  EXPECT_EQ(summary.frames_failed, 1u);
  EXPECT_EQ(sink.calls, (std::vector<std::string>{"open", "write 0 of 3: ok", "write 1 of 3: ok",
                                                  "write 2 of 3: failed", "frames done", "commit"}));
  EXPECT_EQ(sink.layout.reference, path("ref.png"));
  EXPECT_EQ(sink.layout.frame_names,
            (std::vector<std::string>{path("frames/f_1.png"), path("frames/f_2.png"), path("frames/f_3.png")}));
  EXPECT_EQ(sink.layout.grid.cols, (96 - 16) / 8 + 1);
  EXPECT_EQ(sink.layout.grid.rows, (64 - 16) / 8 + 1);
  ASSERT_EQ(sink.warnings.size(), 1u);
  EXPECT_TRUE(sink.warnings[0].starts_with("frame " + path("frames/f_3.png") + ": ")) << sink.warnings[0];
  EXPECT_EQ(sink.results[1].name, path("frames/f_2.png"));
  EXPECT_EQ(sink.results[1].field.cols, sink.layout.grid.cols);
}

TEST_F(SequenceRun, TheSettingsRecordHoldsTheStoredKeysAndTheCommandLinesChoices) {
  options.subpixel = "gauss3";
  const auto j = nlohmann::json::parse(sequence_settings_json(options));
  EXPECT_EQ(j.at("window_px"), 16);
  EXPECT_EQ(j.at("method"), "xcorr");
  EXPECT_EQ(j.at("subpixel"), "gauss3");
  EXPECT_EQ(j.at("interpolator"), "bspline5");
  EXPECT_EQ(j.at("dis_preset"), "medium");
  EXPECT_EQ(j.at("source"), "defaults");
  EXPECT_FALSE(j.contains("mode"));
  EXPECT_FALSE(j.contains("geometry"));
}

TEST_F(SequenceRun, AStoppedRunIsNeverCommitted) {
  const std::atomic<bool> stop{true};
  options.stop = &stop;
  RecordingSink sink;
  const auto summary = run_sequence(options, sink);
  EXPECT_FALSE(summary.complete());
  EXPECT_EQ(summary.frames_taken, 0u);
  EXPECT_EQ(sink.calls, std::vector<std::string>{"open"});
}

TEST_F(SequenceRun, AnotherRankEvaluatesFromThePlanAndRefusesOtherSettings) {
  LocalDistributor distributor;
  options.distributor = &distributor;
  RecordingSink sink;
  ASSERT_TRUE(run_sequence(options, sink).complete());
  options.distributor = nullptr;

  const FrameWork work = sequence_frame_work(options, distributor.plan);
  const auto result = result_from_bytes(work(1));
  EXPECT_EQ(result.name, path("frames/f_2.png"));
  EXPECT_EQ(result.field.vectors.size(), sink.results[1].field.vectors.size());

  SequenceRunOptions other = options;
  other.settings.evaluator.xcorr.passes = 2;
  other.settings_file = "settings.toml";
  try {
    sequence_frame_work(other, distributor.plan);
    FAIL() << "other settings were accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("differ from rank 0's: is settings.toml the same file"), std::string::npos)
        << e.what();
  }
}

TEST_F(SequenceRun, ProbeModeAndAMissingReferenceAreRefusedBeforeTheSinkOpens) {
  RecordingSink sink;
  options.settings.probes_only = true;
  EXPECT_THROW(run_sequence(options, sink), std::invalid_argument);
  options.settings.probes_only = false;
  options.reference = path("none.png");
  EXPECT_THROW(run_sequence(options, sink), std::runtime_error);
  EXPECT_TRUE(sink.calls.empty());
}

}  // namespace
}  // namespace bosfuse::pipeline
