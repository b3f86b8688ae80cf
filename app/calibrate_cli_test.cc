// bosfuse calibrate's checks, --force, --clear, the reference frame's
// reading and the offset estimate, on small synthetic runs made as
// process_test_run.h makes them, with the thermocouples and the reference
// frame placed where each case needs them.

#include <fmt/format.h>

#include <fstream>

#include "app/process_test_run.h"
#include "app/run_control.h"
#include "pipeline/probe_calibration.h"
#include "tests/support/file_bytes.h"

namespace bosfuse {
namespace {

using namespace process_testing;

struct Layout {
  std::vector<cv::Point2d> thermocouples;
  double reference_t_s = -10;
  double first_sample_t_s = -15;  // one sample a second from here to 40 s
};

// The centreline case: thermocouples where the hot spot's
// displacement vanishes by symmetry, and a reference frame (no flow in its
// image) stamped at t = 0, when they read the hot air.
Layout centreline() { return {{{kCentreX, kCentreY}, {kCentreX + 2, kCentreY}}, 0.0, -15}; }

// Where the shift is largest, as ProcessCli's run has them.
Layout off_centre() { return {{{kCentreX + kRadius, kCentreY}, {kCentreX, kCentreY - kRadius}}, -10, -15}; }

class CalibrateCli : public ProcessCli {
 protected:
  void SetUp() override {}

  void make_calibration_run(const Layout& layout) {
    auto store = create_run_store();
    const auto device = store.add_device({0, "daq", "modbus-tcp", "generic", "sim"});
    for (std::size_t c = 0; c < layout.thermocouples.size(); ++c) {
      const auto& p = layout.thermocouples[c];
      channels_.push_back(
          store.add_channel({0, device, fmt::format("tc{}", c + 1), "thermocouple", "degC", "K", p.x, p.y}));
    }
    write_readings(store, layout.first_sample_t_s);
    add_frame(store, layout.reference_t_s, true, 0);
    for (int i = 0; i < 8; ++i) add_frame(store, 35.0 * i / 7, false, i + 1);
    store.finish(storage::RunStatus::kComplete, at_ns(41));
  }

  nlohmann::json conversions() const {
    const auto processing = storage::ProcessingStore(run_dir()).current_processing();
    return nlohmann::json::parse(processing->summary_json).at("temperature_conversions");
  }
};

TEST_F(CalibrateCli, TheCentrelineCaseIsRefusedNamingItsSlopeResidualAndShiftRange) {
  make_calibration_run(centreline());
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto refused = bosfuse("calibrate");
  RecordProperty("calibrate_output", refused.output);
  EXPECT_EQ(refused.exit_code, app::kExitRefused) << refused.output;
  for (const char* text :
       {"calibration refused, nothing stored", "tc1: the slope -", "has the wrong sign", "a slope > 0 is expected",
        "residual RMS", "r2 = ", "tc1: BOS sees no shift where this thermocouple is: the shift ranges over",
        "(the probe's median sigma over 8 samples)"}) {
    EXPECT_NE(refused.output.find(text), std::string::npos) << text << "\n" << refused.output;
  }
  EXPECT_FALSE(storage::ProcessingStore(run_dir()).latest_calibration().has_value()) << "nothing stored";
}

TEST_F(CalibrateCli, ForceStoresARefusedCalibrationWithAWarningAndClearRemovesIt) {
  make_calibration_run(centreline());
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  EXPECT_EQ(conversions().at("tc1"), "none: the shift in px");
  const auto forced = bosfuse("calibrate --force");
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_NE(forced.output.find("[warning] stored a FORCED calibration that failed its checks"), std::string::npos)
      << forced.output;
  EXPECT_NE(forced.output.find("has the wrong sign"), std::string::npos) << forced.output;
  {
    const storage::ProcessingStore results(run_dir());
    const auto j = nlohmann::json::parse(results.latest_calibration()->json);
    EXPECT_TRUE(j.at("forced").get<bool>());
    for (const auto& c : j.at("channels")) {
      EXPECT_TRUE(c.at("forced").get<bool>()) << c;
      EXPECT_FALSE(c.at("checks_failed").empty()) << c;
    }
    EXPECT_EQ(pipeline::stored_calibration(results).size(), 2u);
  }
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  EXPECT_NE(conversions().at("tc1").get<std::string>().find("FORCED although it failed its checks"), std::string::npos)
      << conversions();
  const auto report = bosfuse("report -o " + (dir_.path() / "report").string());
  ASSERT_EQ(report.exit_code, 0) << report.output;
  const std::string html = testing::file_bytes(dir_.path() / "report" / "report.html");
  EXPECT_NE(html.find("tc1 (BOS) by calibration stored"), std::string::npos) << "the report says the conversion";

  const auto cleared = bosfuse("calibrate --clear");
  ASSERT_EQ(cleared.exit_code, 0) << cleared.output;
  EXPECT_NE(cleared.output.find("cleared the calibration stored"), std::string::npos) << cleared.output;
  {
    const storage::ProcessingStore results(run_dir());
    EXPECT_TRUE(pipeline::stored_calibration(results).empty());
    EXPECT_EQ(results.probes().size(), 2u) << "the results are left as they were";
  }
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  EXPECT_EQ(conversions().at("tc1"), "none: the shift in px");
  const storage::ProcessingStore results(run_dir());
  for (const auto& p : results.probes()) {
    for (const auto& s : results.probe_samples(p.id)) EXPECT_FALSE(s.temperature_c.has_value());
  }
  const auto again = bosfuse("calibrate --clear");
  EXPECT_EQ(again.exit_code, 0);
  EXPECT_NE(again.output.find("nothing to clear"), std::string::npos) << again.output;
  EXPECT_NE(bosfuse("calibrate --clear --force").exit_code, 0) << "--clear takes no calibration options";
}

TEST_F(CalibrateCli, AReferenceFrame41msBeforeTheFirstReadingTakesTheNearestReading) {
  Layout layout = off_centre();
  layout.first_sample_t_s = layout.reference_t_s + 0.041;
  make_calibration_run(layout);
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto calibrate = bosfuse("calibrate");
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  EXPECT_NE(calibrate.output.find("the nearest reading, 0.041 s after the reference frame (tolerance 2 s)"),
            std::string::npos)
      << calibrate.output;
  const auto j = nlohmann::json::parse(storage::ProcessingStore(run_dir()).latest_calibration()->json);
  EXPECT_FALSE(j.at("forced").get<bool>());
  for (const auto& c : j.at("channels")) {
    EXPECT_TRUE(c.at("ok").get<bool>()) << c;
    EXPECT_NEAR(c.at("reference_temperature_c").get<double>(), 20, 0.2);
    EXPECT_GT(c.at("slope_c_per_px").get<double>(), 0);
  }
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  EXPECT_NE(conversions().at("tc2").get<std::string>().find("calibration stored"), std::string::npos);
}

TEST_F(CalibrateCli, AReferenceFrameFartherFromAnyReadingThanTheToleranceIsRefused) {
  Layout layout = off_centre();
  layout.first_sample_t_s = layout.reference_t_s + 3;
  make_calibration_run(layout);
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto refused = bosfuse("calibrate");
  EXPECT_EQ(refused.exit_code, app::kExitRefused) << refused.output;
  EXPECT_NE(refused.output.find("no reading within 2 s of the reference frame's time (the nearest is 3 s after it)"),
            std::string::npos)
      << refused.output;
  const auto wider = bosfuse("calibrate --reference-tolerance 3.5");
  EXPECT_EQ(wider.exit_code, 0) << wider.output;
  for (const char* wrong : {"--reference-tolerance -1", "--min-r2 2", "--shift-noise 0", "--flow warm"}) {
    const auto refused_option = bosfuse(std::string("calibrate ") + wrong);
    EXPECT_NE(refused_option.exit_code, 0) << wrong;
    EXPECT_NE(refused_option.output.find(std::string(wrong).substr(0, std::string(wrong).find(' '))), std::string::npos)
        << wrong << ": the option is named\n"
        << refused_option.output;
  }
}

// A geometry stating the room's ambient and its standard uncertainty.
std::string ambient_geometry(const testing::TempDir& dir) {
  const auto path = dir.path() / "ambient.toml";
  std::ofstream(path)
      << "[geometry]\nambient_temperature_c = 20\n[geometry.uncertainty]\nambient_temperature_c = 0.2\n";
  return "--geometry " + path.string();
}

// The demo's case: the reference image has no flow in it, but it is stamped
// when the thermocouples already read the hot air (50 °C). BOS measures from
// the reference image, the undisturbed air: the line starts at the ambient,
// and the hot reading is named as a check.
TEST_F(CalibrateCli, TheLineStartsAtTheAmbientWhenTheThermocouplesReadHotAtTheReferenceFrame) {
  Layout layout = off_centre();
  layout.reference_t_s = 0;
  make_calibration_run(layout);
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto calibrate = bosfuse("calibrate " + ambient_geometry(dir_));
  RecordProperty("calibrate_output", calibrate.output);
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  for (const char* text : {"anchored at 20.00 ± 0.2 degC, the ambient_temperature_c of the geometry",
                           "tc1: note: the thermocouple read 5", "from the ambient 20.00 degC (tolerance 0.6 degC",
                           "the reference image was not taken at ambient, or the thermocouple is not where the image "
                           "is undisturbed"}) {
    EXPECT_NE(calibrate.output.find(text), std::string::npos) << text << "\n" << calibrate.output;
  }
  const auto j = nlohmann::json::parse(storage::ProcessingStore(run_dir()).latest_calibration()->json);
  EXPECT_FALSE(j.at("forced").get<bool>());
  for (const auto& c : j.at("channels")) {
    EXPECT_TRUE(c.at("ok").get<bool>()) << c;
    EXPECT_DOUBLE_EQ(c.at("anchor_c").get<double>(), 20);
    EXPECT_DOUBLE_EQ(c.at("anchor_std_error_c").get<double>(), 0.2);
    // The peak shift is kPxPerDegree per °C of rise at both thermocouples.
    EXPECT_NEAR(c.at("slope_c_per_px").get<double>(), 1 / kPxPerDegree, 0.15 / kPxPerDegree) << c;
    const auto& check = c.at("reference_check");
    EXPECT_FALSE(check.at("within_tolerance").get<bool>()) << check;
    EXPECT_NEAR(check.at("difference_c").get<double>(), kRise, 0.3) << check;
  }
  // What the next processing makes of it: the thermocouples' temperatures.
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto store = storage::RunStore::open(run_dir());
  const storage::ProcessingStore results(run_dir());
  std::size_t compared = 0;
  for (const auto& p : results.probes()) {
    for (const auto& s : results.probe_samples(p.id)) {
      if (!s.valid) continue;
      ASSERT_TRUE(s.temperature_c.has_value());
      const double t_s = static_cast<double>(s.t_ns - kOriginNs) * 1e-9;
      EXPECT_NEAR(*s.temperature_c, 20 + rise_c(t_s), 1.5) << p.name << " at t = " << t_s << " s";
      ++compared;
    }
  }
  EXPECT_GE(compared, 14u);
}

TEST_F(CalibrateCli, AThermocoupleAtAmbientAtTheReferenceFrameIsWithinTheCheck) {
  make_calibration_run(off_centre());
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto calibrate = bosfuse("calibrate " + ambient_geometry(dir_));
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  EXPECT_EQ(calibrate.output.find("note:"), std::string::npos) << calibrate.output;
  const auto j = nlohmann::json::parse(storage::ProcessingStore(run_dir()).latest_calibration()->json);
  for (const auto& c : j.at("channels")) {
    EXPECT_TRUE(c.at("reference_check").at("within_tolerance").get<bool>()) << c;
    EXPECT_NEAR(c.at("slope_c_per_px").get<double>(), 1 / kPxPerDegree, 0.15 / kPxPerDegree) << c;
  }
}

// Without an ambient in the geometry the physics conversion takes the
// thermocouples at the reference frame as the ambient, and so does the
// calibration: the hot reference reading then gives the wrong sign.
TEST_F(CalibrateCli, WithoutAnAmbientTheLineStartsAtTheThermocouplesReadingAtTheReferenceFrame) {
  Layout layout = off_centre();
  layout.reference_t_s = 0;
  make_calibration_run(layout);
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto refused = bosfuse("calibrate");
  EXPECT_EQ(refused.exit_code, app::kExitRefused) << refused.output;
  EXPECT_NE(refused.output.find("the thermocouple's reading at the reference frame (the geometry states no "
                                "ambient_temperature_c)"),
            std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("has the wrong sign"), std::string::npos) << refused.output;
}

TEST_F(CalibrateCli, AnOffsetTheCentrelineRecordCannotFixIsNotEstimated) {
  make_calibration_run(centreline());
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto calibrate = bosfuse("calibrate --estimate-offset 3");
  EXPECT_EQ(calibrate.exit_code, app::kExitRefused) << calibrate.output;
  EXPECT_NE(calibrate.output.find("tc1: clock offset not estimated"), std::string::npos) << calibrate.output;
  EXPECT_NE(calibrate.output.find("the configured 0 s is used"), std::string::npos) << calibrate.output;
}

}  // namespace
}  // namespace bosfuse
