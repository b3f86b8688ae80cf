#pragma once
// The synthetic run the `process` command-line tests work on: frames
// rendered with a known hot-spot displacement whose amplitude follows
// Newton's law, and two thermocouples on the same law at known image
// positions; and what a processing stored, comparable between runs.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "sim/synthetic_pair.h"
#include "storage/database.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::process_testing {

using testing::kBosfuse;
inline constexpr std::int64_t kOriginNs = 1'800'000'000'000'000'000;
inline constexpr double kRate = 0.05;         // k, 1/s
inline constexpr double kRise = 30;           // °C at t = 0
inline constexpr double kPxPerDegree = 0.02;  // peak shift per °C of rise
inline constexpr double kCentreX = 127.5, kCentreY = 95.5, kRadius = 40;

inline double rise_c(double t_s) { return t_s < 0 ? 0 : kRise * std::exp(-kRate * t_s); }

inline std::int64_t at_ns(double t_s) { return kOriginNs + static_cast<std::int64_t>(std::llround(t_s * 1e9)); }

inline sim::DisplacementModel hot_spot(double t_s) {
  // Negative peak: features move towards the centre, as a hot spot makes them (bos_geometry.h).
  return sim::DisplacementModel::bump_gradient(kCentreX, kCentreY, kRadius, -kPxPerDegree * rise_c(t_s));
}

class ProcessCli : public ::testing::Test {
 protected:
  void SetUp() override { make_run(true); }

  // `frames` measurements spread over the first 35 s after the origin.
  void make_run(bool with_reference, int frames = 8) {
    auto store = create_run_store();
    const auto device = store.add_device({0, "daq", "modbus-tcp", "generic", "sim"});
    for (const auto& [name, x, y] :
         {std::tuple{"tc1", kCentreX + kRadius, kCentreY}, std::tuple{"tc2", kCentreX, kCentreY - kRadius}}) {
      channels_.push_back(store.add_channel({0, device, name, "thermocouple", "degC", "K", x, y}));
      points_.emplace_back(x, y);
    }
    write_readings(store, -15);
    add_frame(store, -10, with_reference, 0);
    for (int i = 0; i < frames; ++i) add_frame(store, 35.0 * i / (frames - 1), false, i + 1);
    store.finish(storage::RunStatus::kComplete, at_ns(41));
  }

  // Samples begin 15 s before the heater is switched off: the run declares that moment its origin.
  storage::RunStore create_run_store() const {
    storage::RunInfo info{0, "synthetic", at_ns(-15), std::nullopt, "", {}, 1.0, "heater off"};
    auto store = storage::RunStore::create(run_dir(), info, storage::RunStore::CreateMode::kNew);
    const storage::Event heater_off{0, std::nullopt, kOriginNs, "marker", "heater off"};
    store.write_events({&heater_off, 1});
    std::filesystem::create_directories(run_dir() / "frames");
    return store;
  }

  // One reading a second of every channel from `first_t_s` to 40 s, on Newton's law with noise.
  void write_readings(storage::RunStore& store, double first_t_s) const {
    std::mt19937 random(11);
    std::normal_distribution<double> noise(0, 0.05);
    std::vector<storage::Sample> samples;
    for (double t = first_t_s; t <= 40; t += 1) {
      for (const auto channel : channels_) {
        samples.push_back({channel, at_ns(t), std::nullopt, 20 + rise_c(t) + noise(random), std::nullopt, {}});
      }
    }
    store.write_samples(samples);
  }

  // A frame of the hot spot at `t_s` (the reference image of a pair when `reference`).
  void add_frame(storage::RunStore& store, double t_s, bool reference, int index) const {
    sim::PairOptions pair;
    pair.pattern.width_px = 256;
    pair.pattern.height_px = 192;
    pair.field = hot_spot(t_s);
    pair.noise_seed = static_cast<std::uint64_t>(100 + index);
    const auto images = sim::render_pair(pair);
    const std::string path = "frames/f" + std::to_string(index) + ".png";
    cv::imwrite((run_dir() / path).string(), reference ? images.reference : images.measurement);
    store.add_frame({0, std::nullopt, at_ns(t_s), std::nullopt, path, 256, 192, 8, reference});
  }

  std::filesystem::path run_dir() const { return dir_.path() / "run"; }
  testing::CommandResult bosfuse(const std::string& args) {
    return testing::run_command(kBosfuse + " " + args + " " + run_dir().string(), 120);
  }
  static double json_k(const std::string& text) {
    return nlohmann::json::parse(text).at("parameters").at("k_per_s").at("value").get<double>();
  }

  testing::TempDir dir_;
  std::vector<std::int64_t> channels_;
  std::vector<cv::Point2d> points_;
  const std::string grid_ = "--window 16 --step 8 --passes 2";
};

// Everything a processing stored, comparable (field files by content).
struct StoredResults {
  std::vector<std::vector<storage::ProbeSampleRecord>> samples;
  std::vector<std::string> fits, agreements, fields;

  explicit StoredResults(const std::filesystem::path& run) {
    const storage::ProcessingStore results(run);
    for (const auto& p : results.probes()) samples.push_back(results.probe_samples(p.id));
    for (const auto& f : results.fits()) fits.push_back(f.json);
    for (const auto& a : results.agreements()) agreements.push_back(a.json);
    for (const auto& f : results.fields()) {
      std::ifstream in(run / f.path);
      fields.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  }
  bool operator==(const StoredResults& o) const {
    auto same_samples = [](const auto& a, const auto& b) {
      return a.frame_id == b.frame_id && a.u_px == b.u_px && a.v_px == b.v_px && a.temperature_c == b.temperature_c;
    };
    if (samples.size() != o.samples.size()) return false;
    for (std::size_t p = 0; p < samples.size(); ++p) {
      if (!std::equal(samples[p].begin(), samples[p].end(), o.samples[p].begin(), o.samples[p].end(), same_samples)) {
        return false;
      }
    }
    return fits == o.fits && agreements == o.agreements && fields == o.fields;
  }
};

inline std::int64_t staged_frames(const std::filesystem::path& run) {
  storage::Database db((run / "run.sqlite").string(), storage::Database::Mode::kReadOnly);
  auto stmt = db.prepare("SELECT COUNT(*) FROM staged_frames");
  stmt.step();
  return stmt.column_int64(0);
}

// A processing slow enough (full fields on a 2 px grid, ~0.1 s a frame) to be
// caught in the middle.
inline const std::vector<std::string> kSlowOptions = {"--mode", "full", "--step", "2", "-q"};

inline testing::BackgroundProcess start_slow_process(const std::filesystem::path& run) {
  std::vector<std::string> argv{kBosfuse, "process", run.string()};
  argv.insert(argv.end(), kSlowOptions.begin(), kSlowOptions.end());
  return testing::BackgroundProcess(argv);
}

}  // namespace bosfuse::process_testing
