// The live page's figures (docs/BENCHMARKS.md, "Live view"), measured in
// one run of this program on an otherwise idle machine:
//   latency  a sample's commit (RunStore::write_samples returned) to its SSE
//            event read by an HTTP client of the viewer, 300 samples 50 ms
//            apart; median and 95th percentile
//   probes   LiveProbes::evaluate on a 16-megapixel frame (4928×3264, the
//            paper's camera, 8-bit PNG as the logger records it:
//            acquisition/cameras/frame_png.h) with 4 thermocouples: decoding,
//            the full field and its temperature field (as `process`),
//            quality index and view; median of 5
//   jitter   the logger's poll schedule (a simulated Modbus TCP module
//            polled every 20 ms for 10 s): interval deviations without a
//            viewer, and with a viewer and 10 clients doing what a page
//            does (/, /chart.js, /api/run, then /events throughout)
//   build/bench/live_bench [latency|probes|jitter]   (all three by default)

#include <fmt/format.h>
#include <httplib.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>
#include <vector>

#include "acquisition/config/experiment_config.h"
#include "acquisition/cameras/frame_png.h"
#include "acquisition/logger.h"
#include "pipeline/live_probes.h"
#include "sim/convection_scene.h"
#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "view/live_server.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct ScratchDir {
  fs::path path = fs::temp_directory_path() / ("bosfuse-live-bench-" + std::to_string(::getpid()));
  ScratchDir() { fs::create_directories(path); }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const double at = p * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(at));
  const auto above = std::min(below + 1, values.size() - 1);
  return values[below] + (at - below) * (values[above] - values[below]);
}

// A viewer of `run` on a free loopback port, serving on its own thread.
struct Viewer {
  explicit Viewer(const fs::path& run)
      : server(run, [] {
          view::ViewOptions o;
          o.port = 0;
          return o;
        }()) {
    port = server.listen();
    thread = std::thread([this] { server.serve(); });
  }
  ~Viewer() {
    server.stop();
    thread.join();
  }
  view::LiveServer server;
  int port = 0;
  std::thread thread;
};

// Reads /events until `stop`, calling `on_data` with every chunk.
void follow_events(int port, const std::atomic<bool>& stop, const std::function<void(std::string_view)>& on_data) {
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(2, 0);
  while (!stop) {
    client.Get("/events", [&](const char* data, std::size_t length) {
      on_data({data, length});
      return !stop.load();
    });
  }
}

void latency() {
  ScratchDir dir;
  const fs::path run = dir.path / "run";
  auto store = storage::RunStore::create(run, {.name = "latency", .started_ns = 1'000'000'000},
                                         storage::RunStore::CreateMode::kNew);
  const auto device = store.add_device({.name = "daq", .kind = "modbus-tcp"});
  const auto channel = store.add_channel({.device_id = device, .name = "tc", .kind = "thermocouple", .unit = "degC"});
  Viewer viewer(run);
  constexpr int kSamples = 300;
  std::vector<Clock::time_point> committed(kSamples), received(kSamples);
  std::atomic<int> seen{0};
  std::atomic<bool> stop{false};
  std::thread reader([&] {
    std::string pending;
    follow_events(viewer.port, stop, [&](std::string_view data) {
      const auto now = Clock::now();
      pending.append(data);
      for (std::size_t end; (end = pending.find("\n\n")) != std::string::npos; pending.erase(0, end + 2)) {
        const std::string message = pending.substr(0, end);
        if (message.rfind("event: sample", 0) != 0) continue;
        const auto j = nlohmann::json::parse(message.substr(message.find("data: ") + 6));
        const int index = static_cast<int>(j.at("value").get<double>());
        if (index >= 0 && index < kSamples) received[index] = now, ++seen;
      }
    });
  });
  std::this_thread::sleep_for(500ms);  // the stream is open
  for (int i = 0; i < kSamples; ++i) {
    const storage::Sample s{channel, 2'000'000'000LL + i * 50'000'000LL, {}, static_cast<double>(i), {}, {}};
    store.write_samples({&s, 1});
    committed[i] = Clock::now();
    std::this_thread::sleep_for(50ms);
  }
  for (int i = 0; i < 100 && seen < kSamples; ++i) std::this_thread::sleep_for(20ms);
  stop = true;
  reader.join();
  std::vector<double> ms;
  for (int i = 0; i < kSamples; ++i) {
    if (received[i] != Clock::time_point{})
      ms.push_back(std::chrono::duration<double, std::milli>(received[i] - committed[i]).count());
  }
  fmt::print(
      "latency: {} of {} samples received; commit -> SSE event median {:.1f} ms, p95 {:.1f} ms, max {:.1f} ms "
      "(viewer poll period 100 ms)\n",
      ms.size(), kSamples, percentile(ms, 0.5), percentile(ms, 0.95), percentile(ms, 1.0));
}

// A 16 MP run of the convection scene at the paper's 30 px/mm with four
// thermocouples in the plume, a reference and one frame.
constexpr double kFrameTimeS = 20;

struct SceneRun {
  fs::path dir;
  std::shared_ptr<const sim::ConvectionScene> scene;
};

SceneRun sixteen_megapixel_run(const fs::path& dir) {
  sim::SceneOptions s;
  s.width_px = 4928;
  s.height_px = 3264;
  s.px_per_mm = 30;
  s.cylinder_x_px = 2464;
  s.cylinder_y_px = 3000;
  s.pure_exponential = true;
  const auto shared_scene = std::make_shared<const sim::ConvectionScene>(s);
  const sim::ConvectionScene& scene = *shared_scene;
  const fs::path run = dir / "run16";
  constexpr double kPitchUm = 5;
  storage::RunInfo info{.name = "16 MP", .started_ns = 1'000'000'000};
  info.config_toml = fmt::format(
      "[geometry]\nz_d_m = {}\ndepth_m = {}\nmagnification = {}\npixel_pitch_um = {}\n"
      "ambient_temperature_c = {}\n",
      s.z_d_m, s.depth_m, s.px_per_mm * kPitchUm * 1e-3, kPitchUm, s.ambient_c);
  auto store = storage::RunStore::create(run, info, storage::RunStore::CreateMode::kNew);
  const auto device = store.add_device({.name = "daq", .kind = "modbus-tcp"});
  const std::vector<cv::Point2d> tcs_m{{0, 0.035}, {0, 0.045}, {0.004, 0.045}, {0, 0.055}};
  for (std::size_t i = 0; i < tcs_m.size(); ++i) {
    const auto at = scene.image_position_px(tcs_m[i].x, tcs_m[i].y);
    store.add_channel({.device_id = device,
                       .name = fmt::format("tc{}", i),
                       .kind = "thermocouple",
                       .unit = "degC",
                       .image_x_px = at.x,
                       .image_y_px = at.y});
  }
  sim::PatternOptions pattern;
  pattern.width_px = s.width_px;
  pattern.height_px = s.height_px;
  pattern.dot_diameter_px = 8;  // the paper's dots covered 8×8 px
  const auto background = sim::generate_pattern(pattern);
  fs::create_directories(run / "frames");
  for (int f = 0; f < 2; ++f) {
    const std::string path = fmt::format("frames/{:06d}.png", f);
    acquisition::write_frame_png(run / path, scene.render_frame(background, {}, kFrameTimeS * f, f == 1, f));
    store.add_frame({.t_ns = 1'000'000'000 + f * static_cast<std::int64_t>(kFrameTimeS * 1e9),
                     .path = path,
                     .width_px = s.width_px,
                     .height_px = s.height_px,
                     .bit_depth = 8,
                     .is_reference = f == 0});
  }
  store.finish(storage::RunStatus::kComplete, 21'000'000'000);
  return {run, shared_scene};
}

void probes() {
  ScratchDir dir;
  const SceneRun run = sixteen_megapixel_run(dir.path);
  const pipeline::LiveProbes live(run.dir);
  const auto frame = storage::RunStore::open(run.dir).frames().back();
  std::vector<double> decode, evaluate, total;
  pipeline::LiveFrame last;
  for (int i = 0; i < 5; ++i) {
    last = live.evaluate(frame);
    decode.push_back(last.decode_seconds * 1e3);
    evaluate.push_back(last.evaluate_seconds * 1e3);
    total.push_back(decode.back() + evaluate.back());
  }
  fmt::print(
      "probes: 16 MP (4928x3264, 8-bit PNG {:.1f} MB), 4 probes, temperatures from {}: median of 5: "
      "decode {:.0f} ms + evaluate {:.0f} ms = {:.0f} ms per frame\n",
      fs::file_size(run.dir / frame.path) / 1e6, live.temperature_source(), percentile(decode, 0.5),
      percentile(evaluate, 0.5), percentile(total, 0.5));
  const sim::ConvectionScene& scene = *run.scene;
  for (const auto& p : last.probes) {
    const cv::Point2d at_m = scene.flow_position_m(p.position_px.x, p.position_px.y);
    fmt::print("  {} at ({:.0f}, {:.0f}) px: |d| {:.3f} px, {:.1f} degC (the scene: {:.1f} degC)\n", p.name,
               p.position_px.x, p.position_px.y, p.shift_px, p.temperature_c.value_or(NAN),
               scene.temperature_c(at_m.x, at_m.y, kFrameTimeS));
  }
  // What the frame's format costs: the same pixels as an uncompressed TIFF.
  const cv::Mat image = cv::imread((run.dir / frame.path).string(), cv::IMREAD_UNCHANGED);
  const fs::path tiff = dir.path / "frame.tif";
  cv::imwrite(tiff.string(), image, {cv::IMWRITE_TIFF_COMPRESSION, 1});
  std::vector<double> tiff_ms;
  for (int i = 0; i < 5; ++i) {
    const auto start = Clock::now();
    const cv::Mat decoded = cv::imread(tiff.string(), cv::IMREAD_UNCHANGED);
    tiff_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  fmt::print("  the same frame as an uncompressed TIFF decodes in {:.0f} ms (median of 5)\n", percentile(tiff_ms, 0.5));
}

struct Jitter {
  std::size_t polls = 0;
  double rms_ms = 0, median_ms = 0, p99_ms = 0, max_ms = 0;
};

// Polls a simulated module every 20 ms for 10 s; with `clients` > 0, a
// viewer and that many page-like clients follow the run meanwhile.
Jitter poll_jitter(const fs::path& run, int clients) {
  sim::ModbusSimServer module(sim::module_server_options({}, [] {
    acquisition::ModbusEndpoint e;
    e.port = 0;
    return e;
  }()));
  module.start();
  const auto config = acquisition::parse_experiment(
      fmt::format("[run]\nname = \"jitter\"\n[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\nhost = "
                  "\"127.0.0.1\"\nport = {}\npoll_period_s = 0.02\ntimeout_s = 0.2\n[[devices.channels]]\nname = "
                  "\"tc0\"\ninput = 0\n",
                  module.port()),
      "jitter.toml");
  auto store =
      storage::RunStore::create(run, acquisition::run_info(config, 1'000'000'000), storage::RunStore::CreateMode::kNew);
  acquisition::LoggerOptions options;
  options.duration = 10s;
  acquisition::Logger logger(store, options);
  logger.add_devices(config);
  std::optional<Viewer> viewer;
  std::atomic<bool> stop{false};
  std::vector<std::thread> pages;
  if (clients > 0) {
    viewer.emplace(run);
    for (int i = 0; i < clients; ++i) {
      pages.emplace_back([&, port = viewer->port] {
        httplib::Client page("127.0.0.1", port);
        for (const char* path : {"/", "/chart.js", "/api/run"}) page.Get(path);
        follow_events(port, stop, [](std::string_view) {});
      });
    }
  }
  std::this_thread::sleep_for(1s);  // every client connected: the steady state is measured
  std::atomic<bool> never{false};
  logger.run(never);
  stop = true;
  for (auto& t : pages) t.join();
  viewer.reset();
  std::vector<double> deviation_ms;
  const auto samples = store.read_samples(1);
  for (std::size_t i = 1; i < samples.size(); ++i) {
    deviation_ms.push_back(std::abs((samples[i].t_ns - samples[i - 1].t_ns) * 1e-6 - 20.0));
  }
  double sum2 = 0;
  for (double d : deviation_ms) sum2 += d * d;
  return {samples.size(), std::sqrt(sum2 / std::max<std::size_t>(deviation_ms.size(), 1)),
          percentile(deviation_ms, 0.5), percentile(deviation_ms, 0.99), percentile(deviation_ms, 1.0)};
}

// Rounds alternate, so a passing disturbance of the machine hits both
// cases alike; the medians over rounds are what docs/BENCHMARKS.md quotes.
void jitter() {
  ScratchDir dir;
  constexpr int kRounds = 3;
  std::map<int, std::vector<Jitter>> by_clients;
  for (int round = 0; round < 2 * kRounds; ++round) {
    const int clients = round % 2 ? 10 : 0;
    const Jitter j = poll_jitter(dir.path / fmt::format("jitter{}", round), clients);
    fmt::print(
        "jitter: {:>2} page clients: {} polls in 10 s, |interval - 20 ms|: median {:.2f} ms, rms {:.2f} ms, "
        "p99 {:.2f} ms, max {:.2f} ms\n",
        clients, j.polls, j.median_ms, j.rms_ms, j.p99_ms, j.max_ms);
    by_clients[clients].push_back(j);
  }
  for (const auto& [clients, rounds] : by_clients) {
    const auto median_of = [&](double Jitter::*field) {
      std::vector<double> v;
      for (const auto& j : rounds) v.push_back(j.*field);
      return percentile(v, 0.5);
    };
    fmt::print(
        "jitter: median of {} rounds, {:>2} page clients: median {:.2f} ms, rms {:.2f} ms, p99 {:.2f} ms, max "
        "{:.2f} ms\n",
        rounds.size(), clients, median_of(&Jitter::median_ms), median_of(&Jitter::rms_ms), median_of(&Jitter::p99_ms),
        median_of(&Jitter::max_ms));
  }
}

}  // namespace
}  // namespace bosfuse

int main(int argc, char** argv) {
  const std::string which = argc > 1 ? argv[1] : "all";
  try {
    if (which == "all" || which == "latency") bosfuse::latency();
    if (which == "all" || which == "probes") bosfuse::probes();
    if (which == "all" || which == "jitter") bosfuse::jitter();
  } catch (const std::exception& e) {
    std::cerr << "live_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
