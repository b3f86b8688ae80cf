// bosfuse demo: the main job, runnable without hardware. A simulated
// thermocouple module serves a cooling curve on loopback and the logger
// records it through the real Modbus path into a new run folder.

#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "acquisition/clock.h"
#include "acquisition/experiment_config.h"
#include "acquisition/logger.h"
#include "app/command.h"
#include "app/run_control.h"
#include "sim/modbus_server.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct DemoArgs {
  std::string out = "demo-run";
  std::string duration = "10s";
  double poll_period_s = 0.2;
};

std::string demo_experiment(int port, int inputs, double poll_period_s) {
  std::string text = fmt::format(
      "# Written by 'bosfuse demo': a simulated ADAM-6018 on loopback.\n"
      "[run]\nname = \"demo\"\ndescription = \"simulated cylinder cooling, logged over Modbus TCP\"\n\n"
      "[[devices]]\nname = \"sim-adam\"\nprofile = \"adam-6018\"\nhost = \"127.0.0.1\"\nport = {}\n"
      "poll_period_s = {}\ntimeout_s = 0.5\n",
      port, poll_period_s);
  for (int i = 0; i < inputs; ++i) {
    text += fmt::format("\n  [[devices.channels]]\n  name = \"tc{}\"\n  input = {}\n  tc_type = \"K\"\n", i, i);
  }
  return text;
}

void run_demo(const DemoArgs& args) {
  const std::int64_t started_ns = acquisition::utc_now_ns();
  // A new folder per demo, so running it again never touches an earlier run.
  const std::filesystem::path run_dir = std::filesystem::path(args.out) / acquisition::format_compact_utc(started_ns);

  sim::SimulatedModule module;
  module.signal = {22.0, 80.0, 0.02, 0.05, static_cast<std::uint64_t>(started_ns)};
  acquisition::ModbusEndpoint endpoint;
  endpoint.port = 0;  // any free loopback port
  sim::ModbusSimServer server(sim::module_server_options(module, endpoint));
  server.start();

  const std::string toml = demo_experiment(server.port(), module.inputs, args.poll_period_s);
  const auto config = acquisition::parse_experiment(toml, "demo.toml");
  auto store =
      storage::RunStore::create(run_dir, {0, "demo", started_ns, std::nullopt, toml, storage::RunStatus::kRunning},
                                storage::RunStore::CreateMode::kNew);
  acquisition::Logger::Options options;
  options.duration = parse_duration(args.duration);
  acquisition::Logger logger(store, options);
  logger.add_devices(config);
  std::cout << fmt::format(
      "demo: simulated ADAM-6018 on 127.0.0.1:{} cooling from {} to {} degC (k = {} 1/s); "
      "logging for {}\n",
      server.port(), module.signal.initial_c, module.signal.ambient_c, module.signal.k_per_s, args.duration);
  const auto summary = logger.run(stop_requested_by_signal());
  std::cout << summary.BriefReport() << "\n\n"
            << "data:    " << (run_dir / storage::RunStore::kDatabaseFileName).string() << "\n"
            << "inspect: bosfuse runs " << run_dir.string() << "\n"
            << "export:  bosfuse export " << run_dir.string() << " --csv -o demo.csv\n";
}

void add_demo(CLI::App& root) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = root.add_subcommand("demo", "Simulate a cooling experiment and log it through the real device path");
  cmd->add_option("--out,-o", args->out, "Folder for demo runs (each run gets a new timestamped folder)")
      ->capture_default_str();
  cmd->add_option("--duration", args->duration, "How long to log")->capture_default_str();
  cmd->add_option("--poll-period", args->poll_period_s, "Seconds between polls")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->callback([args] { run_demo(*args); });
}

BOSFUSE_COMMAND(add_demo);

}  // namespace
}  // namespace bosfuse::app
