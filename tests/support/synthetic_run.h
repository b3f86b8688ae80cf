#pragma once
// A small synthetic run on disk for the report, pipeline and CLI tests: two thermocouple
// channels following known Newton curves with noise (and a few samples
// without a temperature), and, optionally, a reference frame and two
// measurement frames rendered by sim/synthetic_pair.h with a known
// displacement (the gradient of a Gaussian bump, a hot spot seen in BOS).

#include <filesystem>
#include <optional>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/synthetic_pair.h"
#include "storage/run_store.h"

namespace bosfuse::testrun {

struct Truth {
  std::int64_t start_ns = 1'795'000'000'000'000'000;  // 2026-11-18T11:06:40Z
  double k_per_s[2] = {0.01, 0.015};
  double t0_c[2] = {80.0, 65.0};
  double ambient_c = 22.0;
  double noise_c = 0.05;
  int samples = 300;    // one per second per channel
  int bad_samples = 3;  // per channel, status timeout
  cv::Point2d tc_px[2] = {{96, 64}, {176, 64}};
  cv::Size image{256, 192};
  cv::Point2d bump_centre{128, 110};
  double bump_radius_px = 36;
  double frame_times_s[2] = {10, 60};
  double frame_peak_px[2] = {1.0, 0.5};
  cv::Rect holder_px{104, 150, 48, 42};  // the heater's holder, hidden by the mask (as in the paper)
  std::string config_toml;               // the run's stored experiment config
  double time_scale = 1;                 // experiment seconds per recorded second
  std::optional<std::string> origin_event;  // declared origin (a marker the test writes), else the first sample
  // The channels' resolution: values are quantised to it, as a module's
  // register is, and it is stored; none: full doubles, resolution unknown.
  std::optional<double> resolution;
};

// The holder mask as an 8-bit PNG of the frames' size: 255 under the holder.
inline cv::Mat holder_mask(const Truth& truth = {}) {
  cv::Mat mask = cv::Mat::zeros(truth.image, CV_8U);
  mask(truth.holder_px).setTo(255);
  return mask;
}

inline void create_run(const std::filesystem::path& dir, bool with_frames, const Truth& truth = {}) {
  storage::RunInfo info{0,
                        "synthetic cooling",
                        truth.start_ns,
                        std::nullopt,
                        truth.config_toml,
                        storage::RunStatus::kRunning,
                        truth.time_scale,
                        truth.origin_event};
  auto store = storage::RunStore::create(dir, info, storage::RunStore::CreateMode::kNew);
  const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", "127.0.0.1:502"});
  std::mt19937 random(11);
  std::normal_distribution<double> noise(0, truth.noise_c);
  for (int c = 0; c < 2; ++c) {
    const auto channel = store.add_channel(
        {0, device, "tc" + std::to_string(c), "thermocouple", "degC", "K", truth.tc_px[c].x, truth.tc_px[c].y,
         truth.resolution});
    std::vector<storage::Sample> samples;
    for (int i = 0; i < truth.samples; ++i) {
      storage::Sample s;
      s.channel_id = channel;
      s.t_ns = truth.start_ns + static_cast<std::int64_t>(i) * 1'000'000'000 + c * 1'000'000;
      if (i % (truth.samples / truth.bad_samples) == 7) {
        s.status = storage::SampleStatus::kTimeout;
      } else {
        const double t = (s.t_ns - truth.start_ns) * 1e-9;
        s.value = truth.ambient_c + (truth.t0_c[c] - truth.ambient_c) * std::exp(-truth.k_per_s[c] * t) + noise(random);
        if (truth.resolution) s.value = std::round(*s.value / *truth.resolution) * *truth.resolution;
      }
      samples.push_back(s);
    }
    store.write_samples(samples);
  }
  if (with_frames) {
    std::filesystem::create_directories(dir / "frames");
    sim::PairOptions pair;
    pair.pattern.width_px = truth.image.width;
    pair.pattern.height_px = truth.image.height;
    pair.pattern.dot_diameter_px = 3;
    pair.pattern.seed = 5;
    for (int f = 0; f < 2; ++f) {
      pair.field = sim::DisplacementModel::bump_gradient(truth.bump_centre.x, truth.bump_centre.y, truth.bump_radius_px,
                                                         truth.frame_peak_px[f]);
      pair.noise_seed = 100 + f;
      const auto images = sim::render_pair(pair);
      if (f == 0) {
        if (!cv::imwrite((dir / "frames/reference.png").string(), images.reference)) {
          throw std::runtime_error("cannot write the reference frame");
        }
        store.add_frame({0, std::nullopt, truth.start_ns, std::nullopt, "frames/reference.png", truth.image.width,
                         truth.image.height, 8, true});
      }
      const std::string name = "frames/frame" + std::to_string(f) + ".png";
      if (!cv::imwrite((dir / name).string(), images.measurement)) throw std::runtime_error("cannot write " + name);
      store.add_frame({0, std::nullopt,
                       truth.start_ns + static_cast<std::int64_t>(truth.frame_times_s[f] * 1e9) + 3'000'000,
                       std::nullopt, name, truth.image.width, truth.image.height, 8, false});
    }
  }
  store.finish(storage::RunStatus::kComplete,
               truth.start_ns + static_cast<std::int64_t>(truth.samples) * 1'000'000'000);
}

}  // namespace bosfuse::testrun
