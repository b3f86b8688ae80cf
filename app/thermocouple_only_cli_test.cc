// A thermocouple-only run (no camera) through `bosfuse process` and
// `bosfuse report`, and what a failed processing leaves behind: its row
// marked failed with the error, which report and `process --resume` repeat.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "app/test_streams.h"
#include "storage/database.h"
#include "storage/processing_store.h"
#include "tests/support/browser.h"
#include "tests/support/file_bytes.h"
#include "tests/support/subprocess.h"
#include "tests/support/synthetic_run.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using testing::shell_quote;

using testing::kBosfuse;

class ThermocoupleOnlyCli : public ::testing::Test {
 protected:
  fs::path run() const { return dir_ / "run"; }
  testing::CommandResult bosfuse(const std::string& command, const std::string& args = "") {
    return testing::run_command(kBosfuse + " " + command + " " + shell_quote(run()) + " " + args, 120);
  }
  testing::StreamsResult streams(const std::string& command, const std::string& args = "") {
    return testing::run_with_streams(kBosfuse + " " + command + " " + shell_quote(run()) + " " + args, dir_.path(), 120);
  }
  nlohmann::json report_json(const std::string& out) {
    return nlohmann::json::parse(testing::file_bytes(dir_ / out / "report.json"));
  }
  // Every processing row of the run: id → status.
  std::map<std::int64_t, std::string> statuses() const {
    storage::Database db((run() / "run.sqlite").string(), storage::Database::Mode::kReadOnly);
    auto rows = db.prepare("SELECT id, status FROM processings ORDER BY id");
    std::map<std::int64_t, std::string> out;
    while (rows.step()) out[rows.column_int64(0)] = rows.column_text(1);
    return out;
  }
  void unmark_reference_frames() const {
    storage::Database db((run() / "run.sqlite").string(), storage::Database::Mode::kReadWrite);
    db.execute("UPDATE frames SET is_reference = 0");
  }

  testing::TempDir dir_;
  const testrun::Truth truth_{};
};

double stored_k(const storage::FitRecord& fit) {
  return nlohmann::json::parse(fit.json).at("parameters").at("k_per_s").at("value").get<double>();
}

TEST_F(ThermocoupleOnlyCli, ProcessFitsEveryThermocoupleAndSaysNoBosEvaluationWasDone) {
  testrun::create_run(run(), false, truth_);
  const auto processed = bosfuse("process");
  ASSERT_EQ(processed.exit_code, 0) << processed.output;
  EXPECT_NE(processed.output.find("the run has no frames: no BOS evaluation was done"), std::string::npos)
      << processed.output;
  EXPECT_NE(processed.output.find("thermocouples only"), std::string::npos) << processed.output;

  const storage::ProcessingStore results(run());
  const auto processing = results.current_processing();
  ASSERT_TRUE(processing.has_value());
  EXPECT_EQ(processing->status, "complete");
  EXPECT_EQ(nlohmann::json::parse(processing->summary_json).at("thermocouples_only"), "the run has no frames");
  const auto fits = results.fits();
  ASSERT_EQ(fits.size(), 2u);
  for (std::size_t c = 0; c < fits.size(); ++c) {
    ASSERT_EQ(fits[c].subject, storage::FitSubject::kChannel);
    ASSERT_TRUE(fits[c].ok) << fits[c].json;
    EXPECT_NEAR(stored_k(fits[c]), truth_.k_per_s[c], 0.02 * truth_.k_per_s[c]) << fits[c].json;
  }
  EXPECT_TRUE(results.probes().empty());
  EXPECT_TRUE(results.agreements().empty());
  EXPECT_EQ(statuses(), (std::map<std::int64_t, std::string>{{processing->id, "complete"}}));

  const auto calibrated = bosfuse("calibrate");
  EXPECT_NE(calibrated.exit_code, 0);
  EXPECT_NE(calibrated.output.find("the run has no frames: a calibration compares BOS probes"), std::string::npos)
      << calibrated.output;
  EXPECT_EQ(calibrated.output.find("run `bosfuse process RUN` first"), std::string::npos) << "it was processed";
}

// Standard output holds data only: the summaries of process, calibrate,
// report and mark are for a person and go to standard error.
TEST_F(ThermocoupleOnlyCli, SummariesGoToStandardErrorAndStandardOutputStaysEmpty) {
  testrun::create_run(run(), false, truth_);
  const auto processed = streams("process");
  ASSERT_EQ(processed.exit_code, 0) << processed.err;
  EXPECT_EQ(processed.out, "");
  EXPECT_NE(processed.err.find("the run has no frames: no BOS evaluation was done"), std::string::npos)
      << processed.err;
  const auto calibrated = streams("calibrate");
  EXPECT_EQ(calibrated.out, "");
  EXPECT_NE(calibrated.err.find("the run has no frames: a calibration compares BOS probes"), std::string::npos)
      << calibrated.err;
  const auto made = streams("report", "-o " + shell_quote(dir_ / "out"));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  EXPECT_EQ(made.out, "");
  EXPECT_NE(made.err.find("tc0: k = "), std::string::npos) << made.err;
  EXPECT_NE(made.err.find("report: " + (dir_ / "out" / "report.html").string()), std::string::npos) << made.err;
  const auto marked = streams("mark", "note --at +1s");
  ASSERT_EQ(marked.exit_code, 0) << marked.err;
  EXPECT_EQ(marked.out, "");
  EXPECT_NE(marked.err.find("marked \"note\" at "), std::string::npos) << marked.err;
}

TEST_F(ThermocoupleOnlyCli, ReportOfAProcessedRunHasTheFitsAndNoBosSectionsOrProcessHint) {
  testrun::create_run(run(), false, truth_);
  ASSERT_EQ(bosfuse("process").exit_code, 0);
  const auto made = bosfuse("report", "-o " + shell_quote(dir_ / "out"));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const auto json = report_json("out");
  ASSERT_EQ(json["series"].size(), 2u) << "the two thermocouples, no BOS probe";
  for (int c = 0; c < 2; ++c) {
    const auto& k = json["series"][c]["fit"]["parameters"]["k_per_s"];
    EXPECT_NEAR(k["value"].get<double>(), truth_.k_per_s[c], 0.02 * truth_.k_per_s[c]) << "tc" << c;
  }
  for (const char* name : {"curves_all.png", "curve_tc0.png", "curve_tc1.svg", "fits.csv", "summary.csv"}) {
    EXPECT_TRUE(fs::exists(dir_ / "out" / name)) << name;
  }
  const std::string html = testing::file_bytes(dir_ / "out" / "report.html");
  EXPECT_NE(html.find("Thermocouples only: the run has no frames"), std::string::npos);
  EXPECT_NE(html.find("thermocouple fits only"), std::string::npos) << "the stored processing is named";
  EXPECT_NE(html.find("Cooling curves"), std::string::npos);
  for (const char* absent : {"bosfuse process", "Not processed", "Displacement maps", "Temperature maps",
                             "Image quality index", "Agreement of thermocouples"}) {
    EXPECT_EQ(html.find(absent), std::string::npos) << absent;
  }
}

TEST_F(ThermocoupleOnlyCli, FramesWithoutAReferenceFailSayingHowToMarkOneAndLeaveNoRunningRow) {
  testrun::create_run(run(), true, truth_);
  unmark_reference_frames();
  const auto processed = bosfuse("process");
  EXPECT_EQ(processed.exit_code, 1) << processed.output;
  EXPECT_NE(processed.output.find("no reference frame"), std::string::npos) << processed.output;
  EXPECT_NE(processed.output.find("UPDATE frames SET is_reference = 1"), std::string::npos) << processed.output;
  const auto rows = statuses();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows.begin()->second, "abandoned") << "failed, not left running";
  const auto last = storage::ProcessingStore(run()).latest_processing();
  ASSERT_TRUE(last.has_value());
  EXPECT_NE(last->summary_json.find("no reference frame"), std::string::npos) << last->summary_json;
  EXPECT_TRUE(storage::ProcessingStore(run()).fits().empty()) << "a failed processing stores nothing";

  const auto made = bosfuse("report", "-o " + shell_quote(dir_ / "out"));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const std::string notes = report_json("out")["notes"].dump();
  EXPECT_NE(notes.find("processing 1 failed"), std::string::npos) << notes;
  EXPECT_NE(notes.find("no reference frame"), std::string::npos) << notes;
  EXPECT_EQ(notes.find("interrupted"), std::string::npos) << notes;
  EXPECT_EQ(notes.find("--resume"), std::string::npos) << notes;

  const auto resumed = bosfuse("process", "--resume");
  EXPECT_NE(resumed.exit_code, 0);
  EXPECT_NE(resumed.output.find("processing 1 failed"), std::string::npos) << resumed.output;
  EXPECT_NE(resumed.output.find("no reference frame"), std::string::npos) << resumed.output;
  EXPECT_EQ(statuses().size(), 1u) << "--resume of a failed processing starts none";
}

// A frame that fails after others were staged leaves its processing
// resumable at that frame; the report says it failed, not that it was interrupted.
TEST_F(ThermocoupleOnlyCli, AFrameThatFailsLeavesItsProcessingResumableWithTheError) {
  testrun::create_run(run(), true, truth_);
  ASSERT_EQ(bosfuse("process", "--mode probes").exit_code, 0);
  const fs::path later = run() / "frames/frame1.png";  // the second measurement, at t = 60 s
  fs::rename(later, dir_ / "away.png");
  const auto failed = bosfuse("process", "--mode probes --frames-at-once 1");
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  const auto rows = statuses();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows.rbegin()->second, "running") << "one frame staged: resumable";
  const auto last = storage::ProcessingStore(run()).latest_processing();
  ASSERT_TRUE(last.has_value());
  EXPECT_NE(last->summary_json.find("frame1.png"), std::string::npos) << last->summary_json;

  ASSERT_EQ(bosfuse("report", "-o " + shell_quote(dir_ / "out")).exit_code, 0);
  const std::string notes = report_json("out")["notes"].dump();
  EXPECT_NE(notes.find("failed at a frame"), std::string::npos) << notes;
  EXPECT_EQ(notes.find("interrupted"), std::string::npos) << notes;

  fs::rename(dir_ / "away.png", later);
  const auto resumed = bosfuse("process", "--resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("done before the resume"), std::string::npos) << resumed.output;
}

}  // namespace
}  // namespace bosfuse
