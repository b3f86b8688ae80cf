// bosfuse sim modbus: a simulated thermocouple module anyone can log from;
// bosfuse sim camera --genicam: the demo's convection scene served by a
// simulated GigE Vision camera (sim/simulated_genicam_camera.h). A server
// has no data to print: where it serves and what it answered are messages,
// on standard error.

#include <spdlog/spdlog.h>

#include <thread>

#include "app/command.h"
#include "app/run_control.h"
#include "sim/demo_setup.h"
#include "sim/modbus_server.h"
#include "sim/simulated_genicam_camera.h"

namespace bosfuse::app {
namespace {

struct SimModbusArgs {
  sim::SimulatedModule module;
  std::string transport = "tcp";
  std::string host = "127.0.0.1";
  int port = 1502;
  std::string serial_port;
  int baud = 9600;
  int unit_id = 1;
  std::string update_period = "0";
  std::string duration;
  std::string heated_for;
};

acquisition::ModbusEndpoint endpoint_of(const SimModbusArgs& args) {
  acquisition::ModbusEndpoint endpoint;
  endpoint.unit_id = args.unit_id;
  if (args.transport == "rtu") {
    if (args.serial_port.empty()) throw std::invalid_argument("--transport rtu needs --serial PATH");
    endpoint.transport = acquisition::ModbusTransport::kRtu;
    endpoint.serial_port = args.serial_port;
    endpoint.baud = args.baud;
  } else {
    endpoint.host = args.host;
    endpoint.port = args.port;
  }
  return endpoint;
}

// Zero means every request here, where a duration must be positive: "0",
// "0s" and "0ms" all say so; anything else is a duration.
std::chrono::nanoseconds update_period(const std::string& text) {
  std::size_t used = 0;
  try {
    if (std::stod(text, &used) == 0.0) {
      const std::string unit = text.substr(used);
      if (unit.empty() || unit == "s" || unit == "ms" || unit == "m" || unit == "min" || unit == "h") return {};
    }
  } catch (const std::exception&) {
    // not a number: parse_duration names the text
  }
  return parse_duration(text);
}

void serve(SimModbusArgs args) {
  args.module.update_period = update_period(args.update_period);
  if (!args.heated_for.empty()) {
    args.module.signal.heated_s = std::chrono::duration<double>(parse_duration(args.heated_for)).count();
  }
  sim::ModbusSimServer server(sim::module_server_options(args.module, endpoint_of(args)));
  server.start();
  const std::string where =
      args.transport == "rtu" ? args.serial_port : args.host + ":" + std::to_string(server.port());
  spdlog::info("simulated {} (unit {}) with {} type {} inputs serving on {}; Ctrl-C to stop", args.module.profile,
               args.unit_id, args.module.inputs, args.module.tc_type, where);
  const auto& stop = stop_requested_by_signal();
  const auto end = args.duration.empty() ? std::chrono::steady_clock::time_point::max()
                                         : std::chrono::steady_clock::now() + parse_duration(args.duration);
  while (!stop.load() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  spdlog::info("answered {} requests", server.requests_answered());
}

struct SimCameraArgs {
  bool genicam = false;
  sim::SimulatedGenicamCameraOptions camera;
  std::uint64_t seed = 1;
  int width_px = 0;  // 0: the demo scene's
  int height_px = 0;
  double experiment_s = 600;
  std::string duration;
};

// Serves until Ctrl-C or --duration; past the scene's experiment time the
// plume holds still.
void serve_camera(const SimCameraArgs& args) {
  if (!args.genicam) throw std::invalid_argument("sim camera: only --genicam (a GigE Vision camera) is served");
  sim::DemoSetup setup = sim::demo_setup(args.experiment_s);
  if (args.width_px > 0 || args.height_px > 0) {
    if (args.width_px > 0) setup.scene.width_px = args.width_px;
    if (args.height_px > 0) setup.scene.height_px = args.height_px;
    setup.model = std::make_shared<const sim::ConvectionScene>(setup.scene);
  }
  sim::PatternOptions pattern;
  pattern.width_px = setup.scene.width_px;
  pattern.height_px = setup.scene.height_px;
  pattern.dot_diameter_px = 3;
  pattern.seed = args.seed;
  sim::SimulatedGenicamCamera camera(setup.model, sim::generate_pattern(pattern), sim::CameraModel{}, args.camera);
  spdlog::info(
      "simulated GigE Vision camera {} ({}x{} Mono8/Mono16, {:g} frames/s, scene at {:g}x) "
      "serving on {}; `bosfuse cameras --address {}` lists it; Ctrl-C to stop",
      args.camera.serial, setup.scene.width_px, setup.scene.height_px, args.camera.frame_rate_hz, args.camera.speed,
      args.camera.address, args.camera.address);
  const auto& stop = stop_requested_by_signal();
  const auto end = args.duration.empty() ? std::chrono::steady_clock::time_point::max()
                                         : std::chrono::steady_clock::now() + parse_duration(args.duration);
  while (!stop.load() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  spdlog::info("rendered {} frames", camera.frames_rendered());
}

void add_sim_camera(CLI::App& sim) {
  auto args = std::make_shared<SimCameraArgs>();
  CLI::App* cmd = sim.add_subcommand(
      "camera", "A simulated camera showing the demo's convection scene (--genicam: over GigE Vision, via Aravis)");
  cmd->add_flag("--genicam", args->genicam, "Serve it as a GigE Vision camera (libaravis' fake camera)");
  cmd->add_option("--serial", args->camera.serial, "Serial number (what `bosfuse cameras` lists it by)")
      ->capture_default_str();
  cmd->add_option("--address", args->camera.address, "IPv4 address to serve on")->capture_default_str();
  cmd->add_option("--frame-rate", args->camera.frame_rate_hz, "Frames per second, real time (1..100)")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--speed", args->camera.speed, "Scene time per second of real time")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Seed of the random background")->capture_default_str();
  cmd->add_option("--width", args->width_px, "Image width, px (default: the demo scene's)")
      ->check(CLI::Range(16, 2048));
  cmd->add_option("--height", args->height_px, "Image height, px (default: the demo scene's)")
      ->check(CLI::Range(16, 2048));
  cmd->add_option("--experiment-time", args->experiment_s, "Cooling simulated, scene seconds")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  cmd->add_option("--duration", args->duration, "Stop after this long (30s, 10m, 2h); default: until Ctrl-C");
  cmd->callback([args] { serve_camera(*args); });
}

void add_sim(CLI::App& root) {
  CLI::App* sim = root.add_subcommand("sim", "Simulated devices and experiments");
  sim->require_subcommand(1);
  auto args = std::make_shared<SimModbusArgs>();
  CLI::App* cmd = sim->add_subcommand(
      "modbus", "A simulated Modbus thermocouple module serving Newton's-law cooling curves with noise");
  cmd->add_option("--profile", args->module.profile, "Module profile")
      ->check(CLI::IsMember({"adam-6018", "icpdas-m7018"}))
      ->capture_default_str();
  cmd->add_option("--channels", args->module.inputs, "Thermocouple inputs served")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cmd->add_option("--tc-type", args->module.tc_type, "Thermocouple type of the inputs")->capture_default_str();
  cmd->add_option("--transport", args->transport, "tcp or rtu")
      ->check(CLI::IsMember({"tcp", "rtu"}))
      ->capture_default_str();
  cmd->add_option("--host", args->host, "Address to listen on (TCP)")->capture_default_str();
  cmd->add_option("--port", args->port, "TCP port (0: any free port)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  cmd->add_option("--serial", args->serial_port, "Serial device (RTU), e.g. one end of a socat pty pair");
  cmd->add_option("--baud", args->baud, "Baud rate (RTU)")->capture_default_str();
  cmd->add_option("--unit-id", args->unit_id, "Modbus unit id")->check(CLI::Range(0, 247))->capture_default_str();
  cmd->add_option("--ambient", args->module.signal.ambient_c, "Ambient temperature, °C")->capture_default_str();
  cmd->add_option("--initial", args->module.signal.initial_c, "Temperature at start, °C")->capture_default_str();
  cmd->add_option("--k", args->module.signal.k_per_s, "Cooling rate k, 1/s")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--noise", args->module.signal.noise_c, "Noise standard deviation, °C")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--seed", args->module.signal.seed, "Noise seed")->capture_default_str();
  cmd->add_option("--update-period", args->update_period, "Time between value updates (250ms, 1s; 0: every request)")
      ->capture_default_str();
  cmd->add_option("--duration", args->duration, "Stop after this long (30s, 10m, 2h); default: until Ctrl-C");
  cmd->add_option("--heated-for", args->heated_for,
                  "The heater is on for this long after the start (30s, 2min): the inputs rise to --initial, then "
                  "cool; default: they cool from the start");
  cmd->callback([args] { serve(*args); });
  add_sim_camera(*sim);
}

BOSFUSE_COMMAND(add_sim);

}  // namespace
}  // namespace bosfuse::app
