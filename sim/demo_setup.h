#pragma once
// The demo's experiment: the paper's set-up at a scale that runs in seconds
// (a 20 mm heater tube cooling from 120 °C, the plume seen at 8 px/mm in a
// 480×440 image, two thermocouples 35 and 45 mm above the cylinder on the
// plume's axis), and the experiment file that describes it to the logger
// and the processing. `bosfuse demo` records it (sim/demo_recording.h); use
// demo_setup() wherever a test or benchmark wants the demo's scene, so they
// all look at the same plume.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/convection_scene.h"

namespace bosfuse::sim {

// The demo processing's final correlation window: the demo processes with
// it, and its truth (sim/demo_truth.h) averages the plume over it.
constexpr int kDemoWindowPx = 16;

// A Newton fit with a free ambient has 3 parameters and needs one point
// more (fitting/newton_fit.h); the reference frame is not a point.
constexpr int kFramesForABosFit = 4;

// What a demo simulates and how fast it records it.
struct DemoOptions {
  double experiment_s = 240;     // cooling time simulated
  double speed = 16;             // times faster than real time
  double frame_interval_s = 10;  // experiment time between frames
  // The background pattern's and the thermocouples' noise seed; unset: the
  // start time, so that every demo is a new run.
  std::optional<std::uint64_t> seed;
  // How the frames reach the recorder: "virtual" (the scene camera, in
  // process) or "genicam" (a simulated GigE Vision camera on 127.0.0.1 read
  // by the GenICam source, sim/simulated_genicam_camera.h), which streams at
  // speed / frame_interval_s and so needs that within 1..100 frames/s.
  std::string camera = "virtual";

  std::string Validate() const;        // empty when valid
  int frames_after_reference() const;  // the frames the camera takes of the cooling
  // The camera's frames per second of real time.
  double frame_rate_hz() const { return speed / frame_interval_s; }
};

struct DemoSetup {
  SceneOptions scene;
  std::shared_ptr<const ConvectionScene> model;  // the scene built once from `scene`
  std::vector<SceneThermocouple> thermocouples;
  double pixel_pitch_um = 5;
  double wavelength_nm = 550;  // the illumination the experiment file states
};

// The demo's scene, tabulated over `experiment_s` and a margin.
DemoSetup demo_setup(double experiment_s);

// The experiment file of a demo recorded at `speed`: its geometry with a
// well-equipped lab's uncertainties, and one simulated ADAM-6018 on
// loopback `port`, polled every `poll_period_s`, whose inputs are the
// thermocouples placed at their image positions.
std::string demo_experiment(const DemoSetup& setup, int port, double poll_period_s, double speed);

}  // namespace bosfuse::sim
