#pragma once
// A SimulatedGenicamCamera is a GigE Vision camera that shows the convection
// scene: libaravis' in-process fake camera (the one arv-fake-gv-camera-0.8
// serves) on a loopback address, with a fill pattern that renders the scene
// at the moment each frame is taken, so the simulator's frames reach the
// recorder through the real camera protocol and the GenICam source
// (acquisition/cameras/genicam_source.h). Scene time runs as for the
// virtual camera (sim/virtual_devices.h): time since the scene's start ×
// speed-up. The first `reference_frames` frames show the background without
// flow. Every frame is stamped, once it is rendered and just before it
// goes out, from the camera's own clock: the host's UTC clock with a known
// offset and drift (clock_offset_s, clock_drift_ppm; 0 and 0 make it the
// host's), so a test knows each timestamp's true host time
// (host_ns_at). The scene is rendered for that instant as predicted from
// the last renderings' duration, so the stamp and the scene agree to the
// rendering time's jitter. The fake camera has no timestamp latch: a
// client maps this clock from frame arrivals.
//
// GigE Vision's control port is fixed (GVCP, 3956): one simulated camera
// per address at a time.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "sim/background_pattern.h"
#include "sim/convection_scene.h"

namespace bosfuse::sim {

struct SimulatedGenicamCameraOptions {
  std::string serial = "BOSSIM01";    // the camera's serial number (what `bosfuse cameras` lists it by)
  std::string address = "127.0.0.1";  // the IPv4 address it serves on
  double frame_rate_hz = 1;           // the camera's free-run rate (the fake camera offers 1..100)
  double speed = 1;                   // scene time per second of real time
  int reference_frames = 1;           // the first frames show no flow
  // The camera clock: camera = host + clock_offset_s + (host − start) · clock_drift_ppm · 1e-6,
  // the start being the camera's construction.
  double clock_offset_s = 0;
  double clock_drift_ppm = 0;
  std::string Validate() const;  // empty when valid
};

class SimulatedGenicamCamera {
 public:
  // Starts serving at once. `scene_start`: the instant of the scene's t = 0;
  // none: now. Throws std::invalid_argument for invalid options and
  // std::runtime_error when the camera cannot serve (the address is not a
  // local one, or its GVCP port is taken).
  SimulatedGenicamCamera(std::shared_ptr<const ConvectionScene> scene, BackgroundPattern pattern, CameraModel camera,
                         SimulatedGenicamCameraOptions options,
                         std::optional<std::chrono::steady_clock::time_point> scene_start = std::nullopt);
  ~SimulatedGenicamCamera();
  SimulatedGenicamCamera(const SimulatedGenicamCamera&) = delete;
  SimulatedGenicamCamera& operator=(const SimulatedGenicamCamera&) = delete;

  const SimulatedGenicamCameraOptions& options() const;
  std::uint64_t frames_rendered() const;  // frames the camera has filled so far
  // The camera's clock at host UTC time `host_ns`, and its inverse: the
  // true host time of a camera timestamp.
  std::int64_t camera_ns_at(std::int64_t host_ns) const;
  std::int64_t host_ns_at(std::int64_t camera_ns) const;

  struct Impl;  // public so the fill callback (a C function) can reach it

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace bosfuse::sim
