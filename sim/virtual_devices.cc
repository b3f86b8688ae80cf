#include "sim/virtual_devices.h"

#include <cmath>

#include "acquisition/clock.h"
#include "sim/cooling_signal.h"

namespace bosfuse::sim {
namespace {

constexpr double kStepS = 0.05;  // scene time between tabulated readings

}  // namespace

SceneThermocoupleTable::SceneThermocoupleTable(const ConvectionScene& scene,
                                               std::vector<SceneThermocouple> thermocouples, double speed,
                                               std::uint64_t seed)
    : thermocouples_(std::move(thermocouples)), speed_(speed), seed_(seed) {
  if (!(speed_ > 0)) throw std::invalid_argument("speed-up must be positive");
  std::vector<double> times;
  for (double t = 0; t <= scene.options().duration_s; t += kStepS) times.push_back(t);
  for (SceneThermocouple tc : thermocouples_) {
    tc.noise_c = 0;  // noise is added per request, so every draw differs
    lagged_c_.push_back(scene.thermocouple_readings(tc, times, seed));
  }
}

double SceneThermocoupleTable::temperature_c(int channel, double t_s, std::uint64_t draw) const {
  const auto& series = lagged_c_.at(static_cast<std::size_t>(channel));
  const double position = std::clamp(t_s * speed_ / kStepS, 0.0, static_cast<double>(series.size() - 1));
  const auto i = std::min(static_cast<std::size_t>(position), series.size() - 2);
  const double f = position - static_cast<double>(i);
  const double mean = series[i] + f * (series[i + 1] - series[i]);
  return mean + thermocouples_[static_cast<std::size_t>(channel)].noise_c *
                    hashed_normal(seed_, static_cast<std::uint64_t>(channel), draw);
}

ModbusSimServerOptions scene_module_options(std::shared_ptr<const SceneThermocoupleTable> table,
                                              const std::string& profile, double ambient_c, int port,
                                              std::optional<std::chrono::steady_clock::time_point> scene_start) {
  ModbusSimServerOptions options;
  options.endpoint.host = "127.0.0.1";
  options.endpoint.port = port;
  options.channels = module_channels(profile, static_cast<int>(table->size()), "K");
  use_profile_register_map(options, profile);
  const auto inputs = static_cast<int>(table->size());
  options.temperature_c = [table, inputs, ambient_c, scene_start](int channel, double t_s, std::uint64_t draw) {
    if (channel >= inputs) return ambient_c;
    // The server's t_s counts from its own start(); the scene's from scene_start.
    const double since_start_s =
        scene_start ? std::chrono::duration<double>(std::chrono::steady_clock::now() - *scene_start).count() : t_s;
    return table->temperature_c(channel, since_start_s, draw);
  };
  return options;
}

SceneCamera::SceneCamera(std::shared_ptr<const ConvectionScene> scene, BackgroundPattern pattern, CameraModel camera,
                         double speed, int reference_frames,
                         std::optional<std::chrono::steady_clock::time_point> scene_start)
    : scene_(std::move(scene)),
      pattern_(std::move(pattern)),
      camera_(camera),
      speed_(speed),
      reference_frames_(reference_frames),
      started_(scene_start) {
  if (!(speed_ > 0)) throw std::invalid_argument("speed-up must be positive");
}

void SceneCamera::connect() {
  if (!started_) started_ = std::chrono::steady_clock::now();
}

std::optional<acquisition::CapturedFrame> SceneCamera::next(std::chrono::milliseconds) {
  const double scene_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_.value()).count() * speed_;
  if (scene_s > scene_->options().duration_s) throw acquisition::EndOfFrames("the simulated experiment has ended");
  const bool reference = taken_ < static_cast<std::uint64_t>(reference_frames_);
  acquisition::CapturedFrame frame;
  frame.t_ns = acquisition::utc_now_ns();
  frame.image = scene_->render_frame(pattern_, camera_, scene_s, !reference, taken_);
  frame.device_t_ns = static_cast<std::int64_t>(std::llround(scene_s * 1e9));  // scene time since switch-off
  frame.origin = "scene t = " + std::to_string(scene_s) + " s";
  frame.is_reference = reference;
  ++taken_;
  return frame;
}

}  // namespace bosfuse::sim
