#include "report/run_input.h"

#include <gtest/gtest.h>

#include "report/report.h"
#include "report/test_run.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

double max_unmasked(const MapField& map) {
  double high = 0;
  for (int r = 0; r < map.values.rows; ++r) {
    for (int c = 0; c < map.values.cols; ++c) {
      if (!map.mask.at<std::uint8_t>(r, c)) high = std::max(high, map.values.at<double>(r, c));
    }
  }
  return high;
}

TEST(RunInput, ThermocouplesAreFittedOnOkSamplesRelativeToTheFirstSample) {
  testing::TempDir dir;
  const testrun::Truth truth;
  testrun::create_run(dir / "run", false, truth);
  const auto input = build_report_input(storage::RunStore::open(dir / "run"));
  EXPECT_EQ(input.run_name, "synthetic cooling");
  EXPECT_EQ(input.status, "complete");
  ASSERT_EQ(input.series.size(), 2u);
  for (int c = 0; c < 2; ++c) {
    const auto& s = input.series[c];
    EXPECT_EQ(s.name, "tc" + std::to_string(c));
    EXPECT_EQ(s.excluded_samples, static_cast<std::size_t>(truth.bad_samples));
    EXPECT_EQ(s.time_s.size() + s.excluded_samples, static_cast<std::size_t>(truth.samples));
    ASSERT_TRUE(s.image_px);
    EXPECT_DOUBLE_EQ(s.image_px->x, truth.tc_px[c].x);
    ASSERT_TRUE(s.fit && s.fit->ok()) << (s.fit ? s.fit->summary.message : "");
    EXPECT_NEAR(s.fit->k_per_s.value, truth.k_per_s[c], 0.02 * truth.k_per_s[c]);
    EXPECT_LE(s.fit->k_per_s.low, truth.k_per_s[c] * 1.01);
    EXPECT_GE(s.fit->k_per_s.high, truth.k_per_s[c] * 0.99);
    EXPECT_NEAR(s.fit->t0_c.value, truth.t0_c[c], 0.2);
  }
  EXPECT_DOUBLE_EQ(input.series[0].time_s.front(), 0.0) << "times start at the run's first sample";
  EXPECT_TRUE(input.displacement_maps.empty());
  EXPECT_EQ(input.displacement_maps_note, "the run has no frames");
  EXPECT_FALSE(input.quality);
  EXPECT_FALSE(input.has_probes());
}

TEST(RunInput, FramesGiveDisplacementMapsNearTheChosenTimesAndAQualityIndex) {
  testing::TempDir dir;
  const testrun::Truth truth;
  testrun::create_run(dir / "run", true, truth);
  RunReportOptions options;
  options.map_times_s = {12, 50, 1000};  // 50 and 1000 both pick the frame at 60 s: one map
  options.px_per_mm = 30;
  std::vector<std::string> progress;
  options.on_progress = [&](const std::string& line) { progress.push_back(line); };
  const auto input = build_report_input(storage::RunStore::open(dir / "run"), options);
  ASSERT_EQ(input.displacement_maps.size(), 2u);
  ASSERT_EQ(progress.size(), 3u) << "fitting, then one line per evaluated frame";
  EXPECT_NE(progress[1].find("evaluating frame"), std::string::npos) << progress[1];
  for (int f = 0; f < 2; ++f) {
    const auto& map = input.displacement_maps[f];
    EXPECT_NEAR(map.time_s, truth.frame_times_s[f], 0.01);
    EXPECT_EQ(map.image_size_px, truth.image);
    EXPECT_DOUBLE_EQ(map.step_px, 8);
    // The window-averaged peak of |shift| is a little below the true peak.
    EXPECT_NEAR(max_unmasked(map), truth.frame_peak_px[f], 0.2 * truth.frame_peak_px[f]) << "frame " << f;
    // Far from the bump the shift is ~0.
    EXPECT_LT(map.values.at<double>(1, 1), 0.05);
  }
  ASSERT_TRUE(input.quality);
  EXPECT_GT(input.quality->index.q_mod, 0.9) << "same pattern, same exposure";
  EXPECT_EQ(input.px_per_mm, 30.0);
}

TEST(RunInput, TheHolderMaskIsNotEvaluatedAndShowsAsMaskedCells) {
  testing::TempDir dir;
  const testrun::Truth truth;
  testrun::create_run(dir / "run", true, truth);
  RunReportOptions options;
  options.map_times_s = {10};
  options.mask = testrun::holder_mask(truth);
  const auto input = build_report_input(storage::RunStore::open(dir / "run"), options);
  ASSERT_EQ(input.displacement_maps.size(), 1u);
  const auto& map = input.displacement_maps[0];
  int masked_inside = 0, masked_outside = 0;
  for (int r = 0; r < map.values.rows; ++r) {
    for (int c = 0; c < map.values.cols; ++c) {
      const cv::Point centre(static_cast<int>(map.x0_px + c * map.step_px),
                             static_cast<int>(map.y0_px + r * map.step_px));
      const bool masked = map.mask.at<std::uint8_t>(r, c) != 0;
      (truth.holder_px.contains(centre) ? masked_inside : masked_outside) += masked;
    }
  }
  EXPECT_GT(masked_inside, 10);
  EXPECT_EQ(masked_outside, 0) << "only the holder is masked on this textured pattern";

  options.mask = cv::Mat::zeros(10, 10, CV_8U);
  const auto wrong = build_report_input(storage::RunStore::open(dir / "run"), options);
  EXPECT_TRUE(wrong.displacement_maps.empty());
  EXPECT_NE(wrong.displacement_maps_note.find("mask is 10×10 px"), std::string::npos) << wrong.displacement_maps_note;
}

TEST(RunInput, AMissingFrameFileIsANoteNotAFailure) {
  testing::TempDir dir;
  testrun::create_run(dir / "run", true);
  std::filesystem::remove(dir / "run" / "frames" / "frame1.png");  // the frame at 60 s, also the last one
  const auto input = build_report_input(storage::RunStore::open(dir / "run"));
  ASSERT_EQ(input.displacement_maps.size(), 1u);
  std::string notes;
  for (const auto& n : input.notes) notes += n + "\n";
  EXPECT_NE(notes.find("No displacement map at t = 60.0 s: cannot read frame"), std::string::npos) << notes;
  EXPECT_NE(notes.find("No image quality index: cannot read frame"), std::string::npos) << notes;
  EXPECT_FALSE(input.quality);
}

TEST(RunInput, DisplacementMagnitudeMapMasksWhatWasNotMeasured) {
  fusion::DisplacementField field;
  field.rows = 2;
  field.cols = 3;
  for (int i = 0; i < 6; ++i) {
    fusion::DisplacementVector v;
    v.x_px = 8 + 8 * (i % 3);
    v.y_px = 8 + 8 * (i / 3);
    v.u_px = 0.3;
    v.v_px = 0.4;
    v.flag = i == 4 ? fusion::VectorFlag::kMasked
                    : (i == 5 ? fusion::VectorFlag::kOutlierReplaced : fusion::VectorFlag::kOk);
    field.vectors.push_back(v);
  }
  const auto map = displacement_magnitude_map(field, {32, 24});
  EXPECT_DOUBLE_EQ(map.values.at<double>(0, 0), 0.5);
  EXPECT_EQ(map.mask.at<std::uint8_t>(1, 1), 255);
  EXPECT_EQ(map.mask.at<std::uint8_t>(1, 2), 0) << "a replaced outlier is shown";
  EXPECT_DOUBLE_EQ(map.x0_px, 8);
  EXPECT_DOUBLE_EQ(map.step_px, 8);
  EXPECT_THROW(displacement_magnitude_map(fusion::DisplacementField{}, {}), std::invalid_argument);
}

TEST(RunInput, IsoTimes) {
  EXPECT_EQ(iso8601_utc(0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(iso8601_utc(1'795'000'000'123'000'000), "2026-11-18T11:06:40.123Z");
}

}  // namespace
}  // namespace bosfuse::report
