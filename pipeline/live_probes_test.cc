#include "pipeline/live_probes.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "pipeline/process.h"
#include "sim/demo_setup.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kStartNs = 1'795'000'000'000'000'000;
// The demo's scene (a plume in the middle of a 480×440 image at 8 px/mm)
// and its two thermocouples, seen at one frame.
struct SceneRun {
  sim::DemoSetup demo = sim::demo_setup(sim::DemoOptions{}.experiment_s);
  double frame_t_s = 15;
  const sim::ConvectionScene& scene() const { return *demo.model; }
};

std::string geometry_toml(const sim::DemoSetup& demo) {
  const sim::SceneOptions& s = demo.scene;
  return fmt::format(
      "[geometry]\nz_d_m = {}\ndepth_m = {}\nmagnification = {}\npixel_pitch_um = {}\n"
      "ambient_temperature_c = {}\nopen_edges = [\"top\"]\n",
      s.z_d_m, s.depth_m, s.px_per_mm * demo.pixel_pitch_um * 1e-3, demo.pixel_pitch_um, s.ambient_c);
}

void write_frame(storage::RunStore& store, const fs::path& dir, const std::string& name, const cv::Mat& image,
                 double t_s, bool reference) {
  ASSERT_TRUE(cv::imwrite((dir / name).string(), image));
  store.add_frame({0, std::nullopt, kStartNs + static_cast<std::int64_t>(t_s * 1e9), std::nullopt, name, image.cols,
                   image.rows, 8, reference});
}

// A run of the scene: two positioned thermocouples, a reference frame and,
// when asked, one frame of the plume.
void create_scene_run(const fs::path& dir, const SceneRun& run, bool with_reference, bool with_frame) {
  storage::RunInfo info;
  info.name = "scene";
  info.started_ns = kStartNs;
  info.config_toml = geometry_toml(run.demo);
  auto store = storage::RunStore::create(dir, info, storage::RunStore::CreateMode::kNew);
  const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", "127.0.0.1:502"});
  for (std::size_t i = 0; i < run.demo.thermocouples.size(); ++i) {
    const sim::SceneThermocouple& tc = run.demo.thermocouples[i];
    const cv::Point2d at = run.scene().image_position_px(tc.x_m, tc.z_m);
    store.add_channel({0, device, "tc" + std::to_string(i), "thermocouple", "degC", "K", at.x, at.y});
  }
  fs::create_directories(dir / "frames");
  sim::PatternOptions pattern;
  pattern.width_px = run.scene().options().width_px;
  pattern.height_px = run.scene().options().height_px;
  pattern.seed = 3;
  const auto background = sim::generate_pattern(pattern);
  const sim::CameraModel camera;
  if (with_reference) {
    write_frame(store, dir, "frames/reference.png", run.scene().render_frame(background, camera, 0, false, 0), 0, true);
  }
  if (with_frame) {
    write_frame(store, dir, "frames/plume.png", run.scene().render_frame(background, camera, run.frame_t_s, true, 1),
                run.frame_t_s, false);
  }
  store.finish(storage::RunStatus::kComplete, kStartNs + static_cast<std::int64_t>(run.frame_t_s * 1e9));
}

storage::FrameRecord measurement_frame(const fs::path& dir) {
  for (const auto& f : storage::RunStore::open(dir).frames()) {
    if (!f.is_reference) return f;
  }
  throw std::runtime_error("no measurement frame");
}

// The live page and `process` run one chain (the target: within
// 0.05 °C at the demo's frames): the same shift and temperature at every
// thermocouple, to rounding, and near the scene's truth.
TEST(LiveProbes, GiveWhatProcessStoresAtEachThermocouple) {
  testing::TempDir dir;
  const SceneRun run;
  create_scene_run(dir.path(), run, true, true);
  const LiveProbes live(dir.path());
  EXPECT_EQ(live.temperature_source(), "physical model");
  const LiveFrame result = live.evaluate(measurement_frame(dir.path()));
  ProcessOptions options;
  options.frames_at_once = 1;
  ASSERT_TRUE(process_run(dir.path(), options).complete);
  const storage::ProcessingStore stored(dir.path());
  const auto probes = stored.probes();
  ASSERT_EQ(result.probes.size(), 2u);
  ASSERT_EQ(probes.size(), 2u);
  for (std::size_t i = 0; i < result.probes.size(); ++i) {
    const LiveProbe& probe = result.probes[i];
    const auto series = std::find_if(probes.begin(), probes.end(), [&](auto& p) { return p.name == probe.name; });
    ASSERT_NE(series, probes.end()) << probe.name;
    const auto samples = stored.probe_samples(series->id);
    ASSERT_EQ(samples.size(), 1u);
    ASSERT_TRUE(probe.valid && samples[0].valid) << probe.name;
    ASSERT_TRUE(probe.temperature_c && samples[0].temperature_c) << probe.name;
    EXPECT_NEAR(*probe.temperature_c, *samples[0].temperature_c, 1e-9) << probe.name;
    EXPECT_NEAR(probe.u_px, samples[0].u_px, 1e-12) << probe.name;
    EXPECT_NEAR(probe.v_px, samples[0].v_px, 1e-12) << probe.name;
    const sim::SceneThermocouple& tc = run.demo.thermocouples[i];
    const double truth_c = run.scene().temperature_c(tc.x_m, tc.z_m, run.frame_t_s);
    const double excess_c = truth_c - run.scene().options().ambient_c;
    ASSERT_GT(excess_c, 5.0) << "the scene must heat the probe for the test to mean anything";
    EXPECT_NEAR(*probe.temperature_c, truth_c, 0.1 * excess_c) << probe.name;
  }
}

TEST(LiveProbes, QualityIndexAndThumbnailComeFromTheSameDecoding) {
  testing::TempDir dir;
  create_scene_run(dir.path(), SceneRun{}, true, true);
  LiveProbeOptions options;
  options.thumbnail_width_px = 240;
  const LiveFrame result = LiveProbes(dir.path(), options).evaluate(measurement_frame(dir.path()));
  EXPECT_EQ(result.thumbnail.cols, 240);
  EXPECT_EQ(result.thumbnail.rows, 220);
  EXPECT_EQ(result.thumbnail.type(), CV_8UC1);
  // The same camera and pattern: the index of a good set-up (the paper's K-5: 0.70).
  EXPECT_GT(result.quality.q_mod, 0.9);
  EXPECT_LE(result.quality.q_mod, 1.0);
  EXPECT_GT(result.decode_seconds, 0.0);
  EXPECT_GT(result.evaluate_seconds, 0.0);
}

TEST(LiveProbes, ARunWithoutAReferenceFrameSaysItIsWaitingForOne) {
  testing::TempDir dir;
  create_scene_run(dir.path(), SceneRun{}, false, false);
  try {
    LiveProbes live(dir.path());
    FAIL() << "constructed without a reference frame";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("reference frame"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace bosfuse::pipeline
