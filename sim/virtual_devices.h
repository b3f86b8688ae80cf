#pragma once
// The simulated experiment's devices, so the logger records it through the
// same paths as a real one: a Modbus thermocouple module whose inputs read
// the scene's thermocouples, and a camera that renders the scene's frames.
// Both run on scene time = time since start × speed-up, so a few minutes of
// cooling can be recorded in seconds.

#include <chrono>
#include <memory>
#include <vector>

#include "acquisition/frame_source.h"
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
ModbusSimServer::Options scene_module_options(std::shared_ptr<const SceneThermocoupleTable> table,
                                              const std::string& profile, double ambient_c, int port);

// A camera looking at the scene's background through the plume. The first
// `reference_frames` frames show the background without flow (taken before
// the heater was switched on); each frame after that is the scene at the
// moment it is taken. Ends when the scene's duration is reached.
class SceneCamera : public acquisition::FrameSource {
 public:
  SceneCamera(std::shared_ptr<const ConvectionScene> scene, BackgroundPattern pattern, CameraModel camera, double speed,
              int reference_frames);

  std::string kind() const override { return "virtual"; }
  std::string describe() const override { return "virtual camera"; }
  void open() override;
  void close() override {}
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
