#include "sim/demo_recording.h"

#include <fmt/format.h>

#include <stdexcept>

#include "acquisition/cameras/genicam_source.h"
#include "acquisition/clock.h"
#include "acquisition/config/experiment_config.h"
#include "sim/simulated_genicam_camera.h"
#include "sim/virtual_devices.h"
#include "storage/run_store.h"

namespace bosfuse::sim {
namespace {

std::chrono::nanoseconds wall_time(double experiment_s, double speed) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(experiment_s / speed));
}

BackgroundPattern demo_background(const DemoSetup& setup, std::uint64_t seed) {
  PatternOptions pattern;
  pattern.width_px = setup.scene.width_px;
  pattern.height_px = setup.scene.height_px;
  pattern.dot_diameter_px = 3;
  pattern.seed = seed;
  return generate_pattern(pattern);
}

void add_scene_camera(acquisition::Logger& logger, const DemoOptions& options, const DemoSetup& setup,
                      std::uint64_t seed, std::chrono::steady_clock::time_point scene_start) {
  acquisition::FrameRecorderOptions camera;
  camera.interval = wall_time(options.frame_interval_s, options.speed);
  logger.add_camera(std::make_unique<SceneCamera>(setup.model, demo_background(setup, seed), CameraModel{},
                                                  options.speed, 1, scene_start),
                    "camera", camera);
}

// The scene served by a simulated GigE Vision camera on 127.0.0.1 at the
// demo's frame rate, and the GenICam source reading it: frames are taken as
// the camera streams them (its free-run rate is the demo's frame interval),
// each with the camera's timestamp and its arrival.
std::unique_ptr<SimulatedGenicamCamera> add_genicam_camera(acquisition::Logger& logger, const DemoOptions& options,
                                                           const DemoSetup& setup, std::uint64_t seed,
                                                           std::chrono::steady_clock::time_point scene_start) {
  SimulatedGenicamCameraOptions served;
  served.frame_rate_hz = options.frame_rate_hz();
  served.speed = options.speed;
  auto simulated = std::make_unique<SimulatedGenicamCamera>(setup.model, demo_background(setup, seed), CameraModel{},
                                                            served, scene_start);
  acquisition::GenicamOptions source;
  source.device = served.address;
  source.pixel_format = "Mono8";  // the scene renders 8-bit frames, as the virtual camera's
  source.frame_rate_hz = served.frame_rate_hz;
  logger.add_camera(std::make_unique<acquisition::GenicamSource>(source), "camera",
                    acquisition::FrameRecorderOptions{});
  return simulated;
}

}  // namespace

acquisition::Logger::Summary record_demo(const DemoOptions& options, const DemoSetup& setup,
                                         const std::filesystem::path& run_dir, const DemoRecordingHooks& hooks) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  const auto note = [&](const std::string& line) {
    if (hooks.note) hooks.note(line);
  };
  // The scene's t = 0 (heater off), on the wall clock the run's time stamps
  // use and on the steady clock both simulated devices run from, taken together.
  const std::int64_t started_ns = acquisition::utc_now_ns();
  const auto scene_start = std::chrono::steady_clock::now();
  const std::uint64_t seed = options.seed.value_or(static_cast<std::uint64_t>(started_ns));
  const auto table =
      std::make_shared<const SceneThermocoupleTable>(*setup.model, setup.thermocouples, options.speed, seed);
  ModbusSimServer server(scene_module_options(table, "adam-6018", setup.scene.ambient_c, 0, scene_start));
  server.start();
  const double poll_period_s = 1.0 / options.speed;  // one reading per second of experiment time
  const auto config =
      acquisition::parse_experiment(demo_experiment(setup, server.port(), poll_period_s, options.speed), "demo.toml");
  auto store = storage::RunStore::create(run_dir, acquisition::run_info(config, started_ns),
                                         storage::RunStore::CreateMode::kNew);
  // The scene's t = 0, when the heater is switched off: the run's declared origin.
  const storage::Event heater_off{0, std::nullopt, started_ns, "marker", "heater off"};
  store.write_events({&heater_off, 1});
  acquisition::LoggerOptions logger_options;
  logger_options.duration = wall_time(options.experiment_s, options.speed);
  logger_options.on_progress = note;
  // Served before the logger starts and stopped after it has let go of it.
  std::unique_ptr<SimulatedGenicamCamera> genicam;
  acquisition::Logger logger(store, logger_options);
  logger.add_devices(config);
  if (hooks.run_created) hooks.run_created();
  if (options.camera == "genicam") {
    genicam = add_genicam_camera(logger, options, setup, seed, scene_start);
  } else {
    add_scene_camera(logger, options, setup, seed, scene_start);
  }
  note(
      fmt::format("demo: simulating {:.0f} s of cooling ({:.0f} -> {:.0f} °C, k = {:.5f} 1/s at the cylinder) at {}x, "
                  "logging thermocouples over Modbus TCP (127.0.0.1:{}) and frames from {}",
                  options.experiment_s, setup.scene.initial_c, setup.scene.ambient_c,
                  setup.model->initial_cooling_rate_per_s(), options.speed, server.port(),
                  genicam ? "the simulated GigE Vision camera (127.0.0.1) over Aravis" : "the virtual camera"));
  const std::atomic<bool> never{false};
  const acquisition::Logger::Summary summary = logger.run(hooks.stop ? *hooks.stop : never);
  server.stop();
  return summary;
}

}  // namespace bosfuse::sim
