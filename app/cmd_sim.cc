// bosfuse sim modbus: a simulated thermocouple module anyone can log from.

#include <spdlog/spdlog.h>

#include <iostream>
#include <thread>

#include "app/command.h"
#include "app/run_control.h"
#include "sim/modbus_server.h"

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
  double update_period_s = 0;
  std::string duration;
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

void serve(SimModbusArgs args) {
  args.module.update_period = std::chrono::nanoseconds(static_cast<std::int64_t>(args.update_period_s * 1e9));
  sim::ModbusSimServer server(sim::module_server_options(args.module, endpoint_of(args)));
  server.start();
  const std::string where =
      args.transport == "rtu" ? args.serial_port : args.host + ":" + std::to_string(server.port());
  std::cout << "simulated " << args.module.profile << " (unit " << args.unit_id << ") with " << args.module.inputs
            << " type " << args.module.tc_type << " inputs serving on " << where << "; Ctrl-C to stop" << std::endl;
  const auto& stop = stop_requested_by_signal();
  const auto end = args.duration.empty() ? std::chrono::steady_clock::time_point::max()
                                         : std::chrono::steady_clock::now() + parse_duration(args.duration);
  while (!stop.load() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::cout << "answered " << server.requests_answered() << " requests" << std::endl;
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
  cmd->add_option("--ambient", args->module.signal.ambient_c, "Ambient temperature, degC")->capture_default_str();
  cmd->add_option("--initial", args->module.signal.initial_c, "Temperature at start, degC")->capture_default_str();
  cmd->add_option("--k", args->module.signal.k_per_s, "Cooling rate k, 1/s")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--noise", args->module.signal.noise_c, "Noise standard deviation, degC")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--seed", args->module.signal.seed, "Noise seed")->capture_default_str();
  cmd->add_option("--update-period", args->update_period_s, "Seconds between value updates (0: every request)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--duration", args->duration, "Stop after this long (default: until Ctrl-C)");
  cmd->callback([args] { serve(*args); });
}

BOSFUSE_COMMAND(add_sim);

}  // namespace
}  // namespace bosfuse::app
