#pragma once
// The simulated experiment's devices, so the logger records it through the
// same paths as a real one: a Modbus thermocouple module whose inputs read
// the scene's thermocouples, and a camera that renders the scene's frames.
// Both run on scene time = time since start × speed-up, so a few minutes of
// cooling can be recorded in seconds.
//
// The start is one instant shared by both devices, the scene's t = 0 (the
// demo's "heater off" marker): each device's own start (the server's
// start(), the camera's connect(), tens to hundreds of ms apart on a loaded
// machine) would put the frames' and the readings' time stamps that far
// behind the scene they show, a clock error of 16× as many experiment
// seconds at the demo's speed-up (issue 29: T0 of BOS and thermocouple
// differed by −0.37..+0.12 °C with it). Without a start given, each device
// starts its clock when it starts.

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "acquisition/cameras/frame_source.h"
#include "sim/convection_scene.h"
#include "sim/modbus_server.h"

namespace bosfuse::sim {

// What each input of the simulated module reads: the scene's thermocouples
// (lagged and noisy) in order, tabulated once so serving a request is cheap.
class SceneThermocoupleTable {
 public:
  SceneThermocoupleTable(const ConvectionScene& scene, std::vector<SceneThermocouple> thermocouples, double speed,
                         std::uint64_t seed);
  // Temperature of input `channel` at `t_s` seconds since start (real time).
  double temperature_c(int channel, double t_s, std::uint64_t draw) const;
  std::size_t size() const { return thermocouples_.size(); }

 private:
  std::vector<SceneThermocouple> thermocouples_;
  std::vector<std::vector<double>> lagged_c_;  // per thermocouple, every kStepS of scene time
  double speed_;
  std::uint64_t seed_;
};

// An ADAM-6018-like module on loopback serving the table; its cold junction
// (when the profile has one) reads the ambient temperature.
// `scene_start`: the instant of the scene's t = 0; none: the server's start.
ModbusSimServerOptions scene_module_options(
    std::shared_ptr<const SceneThermocoupleTable> table, const std::string& profile, double ambient_c, int port,
    std::optional<std::chrono::steady_clock::time_point> scene_start = std::nullopt);

// A camera looking at the scene's background through the plume. The first
// `reference_frames` frames show the background without flow (taken before
// the heater was switched on); each frame after that is the scene at the
// moment it is taken. Ends when the scene's duration is reached.
class SceneCamera : public acquisition::FrameSource {
 public:
  // `scene_start`: the instant of the scene's t = 0; none: connect().
  SceneCamera(std::shared_ptr<const ConvectionScene> scene, BackgroundPattern pattern, CameraModel camera, double speed,
              int reference_frames, std::optional<std::chrono::steady_clock::time_point> scene_start = std::nullopt);

  std::string kind() const override { return "virtual"; }
  std::string describe() const override { return "virtual camera"; }
  void connect() override;
  void disconnect() override {}
  std::optional<acquisition::CapturedFrame> next(std::chrono::milliseconds wait) override;

 private:
  std::shared_ptr<const ConvectionScene> scene_;
  BackgroundPattern pattern_;
  CameraModel camera_;
  double speed_;
  int reference_frames_;
  std::uint64_t taken_ = 0;
  std::optional<std::chrono::steady_clock::time_point> started_;
};

}  // namespace bosfuse::sim
