// bosfuse process / calibrate on a small synthetic run (process_test_run.h).

#include <signal.h>

#include "app/process_test_run.h"

namespace bosfuse {
namespace {

using namespace process_testing;

TEST_F(ProcessCli, ProbesOnlyStoresShiftsFitsAndAgreement) {
  const auto run = bosfuse("process --mode probes " + grid_);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("8/8 "), std::string::npos) << "progress on stderr: " << run.output;
  const storage::ProcessingStore results(run_dir());
  const auto probes = results.probes();
  ASSERT_EQ(probes.size(), 2u);
  for (std::size_t p = 0; p < probes.size(); ++p) {
    EXPECT_EQ(probes[p].channel_id, channels_[p]);
    const auto samples = results.probe_samples(probes[p].id);
    ASSERT_EQ(samples.size(), 8u);
    for (const auto& s : samples) {
      ASSERT_TRUE(s.valid);
      const double t_s = static_cast<double>(s.t_ns - kOriginNs) * 1e-9;
      const cv::Point2d truth = hot_spot(t_s).window_mean(points_[p].x, points_[p].y, 16);
      EXPECT_NEAR(s.shift_px, std::hypot(truth.x, truth.y), 0.03) << "t = " << t_s;
      EXPECT_FALSE(s.temperature_c.has_value()) << "no calibration, no field: no temperature";
    }
  }
  const auto fits = results.fits();
  ASSERT_EQ(fits.size(), 4u);
  for (const auto& fit : fits) {
    ASSERT_TRUE(fit.ok) << fit.json;
    EXPECT_NEAR(json_k(fit.json), kRate, (fit.subject == storage::FitSubject::kChannel ? 0.05 : 0.15) * kRate)
        << fit.json;
    EXPECT_EQ(fit.origin_t_ns, kOriginNs);
  }
  ASSERT_EQ(results.agreements().size(), 2u);
  const auto agreement = nlohmann::json::parse(results.agreements()[0].json);
  EXPECT_FALSE(agreement.at("k").is_null());
  EXPECT_EQ(agreement.at("probe_quantity"), "shift_px");
  EXPECT_TRUE(results.fields().empty());
}

TEST_F(ProcessCli, AdaptiveRefinementIsStoredWithTheSettings) {
  const auto run = bosfuse("process --adaptive-refinement on --adaptive-threshold 5 " + grid_);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto processing = storage::ProcessingStore(run_dir()).current_processing();
  ASSERT_TRUE(processing.has_value());
  const auto settings = nlohmann::json::parse(processing->settings_json);
  EXPECT_EQ(settings.at("adaptive_refinement"), true);
  EXPECT_EQ(settings.at("adaptive_threshold"), 5);
  const auto wrong = bosfuse("process --adaptive-refinement yes");
  EXPECT_NE(wrong.exit_code, 0);
  EXPECT_NE(wrong.output.find("--adaptive-refinement"), std::string::npos) << wrong.output;
}

// The ROI parser is evaluate's (app/evaluator_arguments.h): a usage mistake.
TEST_F(ProcessCli, ARoiOfNoWidthIsRefusedAsAUsageMistake) {
  const auto run = bosfuse("process --roi 0,0,0,10 " + grid_);
  EXPECT_EQ(run.exit_code, 105) << run.output;
  EXPECT_NE(run.output.find("--roi '0,0,0,10': expected x,y,width,height in pixels"), std::string::npos)
      << run.output;
  EXPECT_FALSE(storage::ProcessingStore(run_dir()).current_processing().has_value());
}

TEST_F(ProcessCli, PreprocessingIsStoredWithTheSettingsAndUsedAgain) {
  const auto run = bosfuse("process --mode probes --preprocess normalize " + grid_);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto processing = storage::ProcessingStore(run_dir()).current_processing();
  ASSERT_TRUE(processing.has_value());
  EXPECT_EQ(nlohmann::json::parse(processing->settings_json).at("preprocess"), "normalize");
  // The shifts still follow the hot spot with the filter.
  const storage::ProcessingStore results(run_dir());
  for (const auto& probe : results.probes()) {
    for (const auto& s : results.probe_samples(probe.id)) EXPECT_TRUE(s.valid);
  }
  // Without options the stored setting is used again.
  const auto again = bosfuse("process");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(nlohmann::json::parse(storage::ProcessingStore(run_dir()).current_processing()->settings_json)
                .at("preprocess"),
            "normalize");
  const auto wrong = bosfuse("process --preprocess sharpen");
  EXPECT_EQ(wrong.exit_code, 105) << wrong.output;
  EXPECT_NE(wrong.output.find("none, normalize, highpass, minmax"), std::string::npos) << wrong.output;
}

TEST_F(ProcessCli, FullFieldsEqualProbesAtTheProbePointsAndWriteFieldFiles) {
  auto probe_samples = [&](const std::string& args) {
    EXPECT_EQ(bosfuse("process --mode probes " + args).exit_code, 0);
    std::vector<std::vector<storage::ProbeSampleRecord>> samples;
    const storage::ProcessingStore results(run_dir());
    for (const auto& p : results.probes()) samples.push_back(results.probe_samples(p.id));
    return samples;
  };
  const auto probe_mode = probe_samples(grid_ + " --probe-context -1");
  const auto fast_probe_mode = probe_samples(grid_ + " --probe-context 1");
  const auto run = bosfuse("process --mode full " + grid_);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("degC per px"), std::string::npos) << "the set-up's sensitivity is printed";
  const storage::ProcessingStore results(run_dir());
  const auto probes = results.probes();
  ASSERT_EQ(probes.size(), probe_mode.size());
  for (std::size_t p = 0; p < probes.size(); ++p) {
    const auto full = results.probe_samples(probes[p].id);
    ASSERT_EQ(full.size(), probe_mode[p].size());
    for (std::size_t i = 0; i < full.size(); ++i) {
      EXPECT_NEAR(full[i].u_px, probe_mode[p][i].u_px, 1e-4);
      EXPECT_NEAR(full[i].v_px, probe_mode[p][i].v_px, 1e-4);
      // Measured: up to 0.011 px at 0.6 px shifts (window 16, step 8, 2 passes).
      EXPECT_NEAR(full[i].u_px, fast_probe_mode[p][i].u_px, 0.02) << "one node of context";
      EXPECT_NEAR(full[i].v_px, fast_probe_mode[p][i].v_px, 0.02) << "one node of context";
      ASSERT_TRUE(full[i].temperature_c.has_value()) << "full fields give the model's temperature";
      EXPECT_GT(*full[i].temperature_c, 20) << "a hot spot";
    }
  }
  const auto fields = results.fields();
  ASSERT_EQ(fields.size(), 16u);
  for (const auto& f : fields) EXPECT_TRUE(std::filesystem::exists(run_dir() / f.path)) << f.path;
}

TEST_F(ProcessCli, AMaskedHolderIsNotEvaluatedAndTheTemperatureFieldIsFilledThere) {
  cv::Mat mask(192, 256, CV_8U, cv::Scalar(0));
  mask(cv::Rect(112, 104, 32, 40)).setTo(255);  // a holder below the hot spot's centre
  cv::imwrite((run_dir() / "mask.png").string(), mask);
  const auto run = bosfuse("process " + grid_ + " --mask mask.png");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const storage::ProcessingStore results(run_dir());
  std::size_t temperature_files = 0;
  for (const auto& f : results.fields()) {
    const auto summary = nlohmann::json::parse(f.json);
    if (f.kind == "displacement") {
      EXPECT_GT(summary.at("masked").get<int>(), 0) << f.json;
    }
    if (f.kind != "temperature") continue;
    ++temperature_files;
    EXPECT_GT(summary.at("unmeasured_nodes").get<int>(), 0) << f.json;
    std::ifstream csv(run_dir() / f.path);
    std::string header;
    std::getline(csv, header);
    EXPECT_EQ(header, "x,y,temperature_c,measured,sigma_c");
  }
  EXPECT_EQ(temperature_files, 8u);
  for (const auto& p : results.probes()) {
    for (const auto& s : results.probe_samples(p.id)) EXPECT_GT(s.temperature_c.value_or(0), 20);
  }
  const auto missing = bosfuse("process " + grid_ + " --mask nope.png");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("mask 'nope.png': no such file in the run folder"), std::string::npos)
      << missing.output;
}

TEST_F(ProcessCli, CalibrationGivesDegreesPerPixelAndProbeTemperatures) {
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const auto calibrate = bosfuse("calibrate");
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  double slope = 0;
  {
    const storage::ProcessingStore results(run_dir());
    const auto record = results.latest_calibration();
    ASSERT_TRUE(record.has_value());
    const auto j = nlohmann::json::parse(record->json);
    ASSERT_EQ(j.at("channels").size(), 2u);
    for (const auto& c : j.at("channels")) {
      ASSERT_TRUE(c.at("ok").get<bool>()) << c;
      slope = c.at("slope_c_per_px").get<double>();
      // The window mean of the bump is a little below its peak, so the slope a little above 1/0.02.
      EXPECT_NEAR(slope, 1 / kPxPerDegree, 0.1 / kPxPerDegree) << c;
      EXPECT_GT(c.at("slope_std_error_c_per_px").get<double>(), 0);
      EXPECT_NEAR(c.at("reference_temperature_c").get<double>(), 20, 0.2);
    }
  }
  const auto again = bosfuse("process --mode probes " + grid_);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  RecordProperty("calibrate_output", calibrate.output);  // readable with --gtest_output=xml
  RecordProperty("process_output", again.output);
  const storage::ProcessingStore results(run_dir());
  for (const auto& p : results.probes()) {
    for (const auto& s : results.probe_samples(p.id)) {
      ASSERT_TRUE(s.temperature_c.has_value());
      EXPECT_NEAR(*s.temperature_c, 20 + rise_c(static_cast<double>(s.t_ns - kOriginNs) * 1e-9), 1.5);
    }
  }
  for (const auto& fit : results.fits()) EXPECT_NEAR(json_k(fit.json), kRate, 0.15 * kRate) << fit.json;
  const auto agreement = nlohmann::json::parse(results.agreements().at(0).json);
  EXPECT_EQ(agreement.at("probe_quantity"), "temperature_c");
  EXPECT_FALSE(agreement.at("series").is_null());
}

TEST_F(ProcessCli, AnOffsetThatTheRecordCannotFixIsNotEstimated) {
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  // The frames see only the smooth decay: shifting it in time only rescales it.
  const auto calibrate = bosfuse("calibrate --estimate-offset 2");
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  EXPECT_NE(calibrate.output.find("not estimated"), std::string::npos) << calibrate.output;
  const storage::ProcessingStore results(run_dir());
  const auto j = nlohmann::json::parse(results.latest_calibration()->json);
  for (const auto& c : j.at("channels")) {
    EXPECT_FALSE(c.at("offset_estimate").at("ok").get<bool>());
    EXPECT_EQ(c.at("camera_offset_s").get<double>(), 0.0) << "the configured offset is kept";
  }
}

TEST_F(ProcessCli, CalibrateBeforeProcessAndARunWithoutReferenceAreExplained) {
  const auto calibrate = bosfuse("calibrate");
  EXPECT_NE(calibrate.exit_code, 0);
  EXPECT_NE(calibrate.output.find("run `bosfuse process RUN` first"), std::string::npos) << calibrate.output;
  std::filesystem::remove_all(run_dir());
  channels_.clear();
  points_.clear();
  make_run(false);
  const auto run = bosfuse("process --mode probes");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("no reference frame"), std::string::npos) << run.output;
}

// Frame f3 (id 4) moved out of the run, a valid image still; its row names
// it by `stored`, or a symlink in its place leads to it.
void move_frame_out(const std::filesystem::path& run, const std::string& stored, bool symlink) {
  std::filesystem::rename(run / "frames/f3.png", run.parent_path() / "outside.png");
  if (symlink) {
    std::filesystem::create_symlink(run.parent_path() / "outside.png", run / "frames/f3.png");
    return;
  }
  storage::Database db((run / "run.sqlite").string(), storage::Database::Mode::kReadWrite);
  db.prepare("UPDATE frames SET path = ? WHERE path = 'frames/f3.png'").bind_all(stored).run();
}

TEST_F(ProcessCli, AFramePathLeadingOutOfTheRunIsRefusedByName) {
  for (const std::string stored : {"../outside.png", "/etc/passwd", ""}) {
    std::filesystem::remove_all(dir_.path());
    std::filesystem::create_directories(dir_.path());
    channels_.clear();
    points_.clear();
    make_run(true);
    move_frame_out(run_dir(), stored, stored.empty());
    const auto run = bosfuse("process --mode probes " + grid_);
    EXPECT_NE(run.exit_code, 0) << stored << ": " << run.output;
    const std::string named = stored.empty() ? "frame 4: stored path 'frames/f3.png' refused: a symlink along it leads"
                                             : "frame 4: stored path '" + stored + "' refused";
    EXPECT_NE(run.output.find(named), std::string::npos) << run.output;
    EXPECT_TRUE(storage::ProcessingStore(run_dir()).probes().empty()) << "nothing stored from a refused run";
  }
}

TEST_F(ProcessCli, TheCameraOffsetMovesProbeTimesOntoTheHostClock) {
  auto probe_t0 = [&](const std::string& extra) {
    EXPECT_EQ(bosfuse("process --mode probes " + grid_ + extra).exit_code, 0);
    const storage::ProcessingStore results(run_dir());
    for (const auto& fit : results.fits()) {
      if (fit.subject == storage::FitSubject::kProbe) {
        return nlohmann::json::parse(fit.json).at("parameters").at("T0_c").at("value").get<double>();
      }
    }
    return 0.0;
  };
  const double t0 = probe_t0("");
  const auto alignment = dir_.path() / "alignment.toml";
  std::ofstream(alignment) << "[alignment]\ncamera_offset_s = 3.0\n";
  // The same shifts 3 s later on the fits' time axis: extrapolated back to t = 0 they are e^(3k) larger.
  EXPECT_NEAR(probe_t0(" --geometry " + alignment.string()), t0 * std::exp(3 * kRate), 0.03 * t0);
}

TEST_F(ProcessCli, GeometryFileIsUsedAndItsMistakesAreNamed) {
  const std::string example = std::string(BOSFUSE_SOURCE_DIR) + "/examples/geometry.toml";
  const auto run = bosfuse("process " + grid_ + " --geometry " + example);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("geometry from " + example), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("Z_D = 0.5 m"), std::string::npos) << run.output;
  const auto bad = dir_.path() / "bad.toml";
  std::ofstream(bad) << "[geometry]\nz_d_m = 0.5\ndepht_m = 0.1\n";
  const auto typo = bosfuse("process " + grid_ + " --geometry " + bad.string());
  EXPECT_NE(typo.exit_code, 0);
  EXPECT_NE(typo.output.find("bad.toml:3"), std::string::npos) << typo.output;
  EXPECT_NE(typo.output.find("depht_m"), std::string::npos) << typo.output;
  std::ofstream(bad) << "[geometry]\nz_d_m = -1\n";
  const auto negative = bosfuse("process " + grid_ + " --geometry " + bad.string());
  EXPECT_NE(negative.exit_code, 0);
  EXPECT_NE(negative.output.find("z_d_m"), std::string::npos) << negative.output;
}

TEST_F(ProcessCli, AKilledProcessLeavesThePreviousResultsAndResumeCompletesThem) {
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const StoredResults previous(run_dir());
  std::filesystem::copy(run_dir(), dir_.path() / "copy", std::filesystem::copy_options::recursive);

  auto process = start_slow_process(run_dir());
  ASSERT_TRUE(testing::wait_for([&] { return staged_frames(run_dir()) >= 2; }, std::chrono::seconds(60)));
  process.send_signal(SIGKILL);
  EXPECT_EQ(process.wait_exit(std::chrono::seconds(5)), -1) << "killed by the signal";
  ASSERT_LT(staged_frames(run_dir()), 8) << "it finished before it could be killed";
  EXPECT_TRUE(StoredResults(run_dir()) == previous) << "the previous results changed";

  const auto resumed = bosfuse("process --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("done before the resume"), std::string::npos) << resumed.output;
  std::string options;
  for (const auto& o : kSlowOptions) options += " " + o;
  ASSERT_EQ(testing::run_command(kBosfuse + " process " + (dir_.path() / "copy").string() + options, 120).exit_code, 0);
  EXPECT_TRUE(StoredResults(run_dir()) == StoredResults(dir_.path() / "copy"))
      << "a resumed processing differs from an uninterrupted one";
}

TEST_F(ProcessCli, CtrlCStopsProcessingPromptlyAndResumeIsOffered) {
  ASSERT_EQ(bosfuse("process --mode probes " + grid_).exit_code, 0);
  const StoredResults previous(run_dir());
  auto process = start_slow_process(run_dir());
  ASSERT_TRUE(testing::wait_for([&] { return staged_frames(run_dir()) >= 1; }, std::chrono::seconds(60)));
  const auto interrupted = std::chrono::steady_clock::now();
  process.send_signal(SIGINT);
  EXPECT_EQ(process.wait_exit(std::chrono::seconds(10)), 5) << "kExitStopped";
  EXPECT_LT(std::chrono::steady_clock::now() - interrupted, std::chrono::seconds(3)) << "not prompt";
  EXPECT_TRUE(StoredResults(run_dir()) == previous);
  EXPECT_EQ(bosfuse("process --resume").exit_code, 0);
}

}  // namespace
}  // namespace bosfuse
