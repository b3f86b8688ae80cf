// A peer check with a Modbus client nobody here wrote: mbpoll (Debian's
// package) reads the simulated module and must see the very registers the
// logger decoded and recorded.

#include <gtest/gtest.h>

#include <regex>

#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace testing;

// mbpoll prints one "[ref]: value" line per register.
std::map<int, std::uint16_t> parse_mbpoll(const std::string& output) {
  std::map<int, std::uint16_t> registers;
  const std::regex line(R"(\[(\d+)\]:\s+(-?\d+))");
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    registers[std::stoi((*it)[1])] = static_cast<std::uint16_t>(std::stoi((*it)[2]));
  }
  return registers;
}

TEST(MbpollPeer, IndependentClientSeesWhatTheLoggerRecorded) {
  TempDir dir;
  constexpr int kInputs = 4;
  // Values hold for an hour, so the logger and mbpoll read the same ones.
  auto options = module_options("adam-6018", kInputs, loopback_tcp());
  options.update_period = std::chrono::hours(1);
  sim::ModbusSimServer server(options);
  server.start();
  const std::string toml = tcp_device_toml("adam", server.port(), kInputs, 0.1);
  const auto config = acquisition::parse_experiment(toml, "peer.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  log_for(store, config, 500ms);

  const auto result = run_command("mbpoll -m tcp -a 1 -t 4 -0 -r 0 -c " + std::to_string(kInputs) + " -1 -o 2 -p " +
                                  std::to_string(server.port()) + " 127.0.0.1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto registers = parse_mbpoll(result.output);
  ASSERT_EQ(registers.size(), std::size_t(kInputs)) << result.output;

  const auto stored = samples_by_channel(store);
  for (int i = 0; i < kInputs; ++i) {
    const auto& channel = config.modbus_devices[0].channels[static_cast<std::size_t>(i)];
    const auto& samples = stored.at(channel.name);
    ASSERT_FALSE(samples.empty());
    const std::uint16_t reg = registers.at(i);
    const auto peer = channel.decode(std::span(&reg, 1));
    for (const auto& s : samples) {
      EXPECT_EQ(s.raw, peer.raw) << channel.name;
      EXPECT_EQ(s.value, peer.value) << channel.name;
    }
    // And the value is the cooling curve's start, not a decoding accident.
    EXPECT_NEAR(*peer.value, 85.0, 1.5) << channel.name;
  }
}

// A client that reads a real module's whole map (all 8 inputs, and the
// cold junction of a module that has one) must get every register; the
// simulator used to serve only the channels it simulated and answered
// "Illegal data address" past them.
TEST(MbpollPeer, SimulatedModulesServeTheirWholeRegisterMap) {
  struct Read {
    std::string profile;
    std::string mbpoll_type;  // 4: holding registers, 3: input registers
    int first;
    int count;
  };
  for (const Read& read : {Read{"adam-6018", "4", 0, 8}, Read{"icpdas-m7018", "3", 0, 8},
                           Read{"icpdas-m7018", "3", 128, 1}}) {
    SCOPED_TRACE(read.profile + " from " + std::to_string(read.first));
    sim::SimulatedModule module;
    module.profile = read.profile;
    module.signal = sim::CoolingSignal{22.0, 85.0, 0.2, 0.3, 7};
    sim::ModbusSimServer server(sim::module_server_options(module, loopback_tcp()));
    server.start();
    const auto result = run_command("mbpoll -m tcp -a 1 -t " + read.mbpoll_type + " -0 -r " +
                                    std::to_string(read.first) + " -c " + std::to_string(read.count) + " -1 -o 2 -p " +
                                    std::to_string(server.port()) + " 127.0.0.1");
    ASSERT_EQ(result.exit_code, 0) << result.output;
    const auto registers = parse_mbpoll(result.output);
    ASSERT_EQ(registers.size(), std::size_t(read.count)) << result.output;
    // Each register is a temperature of the cooling curve (or the ambient
    // one at the cold junction), decoded with the profile's own map.
    for (const auto& [address, value] : registers) {
      const auto channel = read.first == 128 ? acquisition::profile_cold_junction_channel(read.profile)
                                             : acquisition::profile_input_channel(read.profile, address, "K");
      const auto reading = channel.decode(std::span(&value, 1));
      ASSERT_TRUE(reading.value.has_value()) << address;
      EXPECT_NEAR(*reading.value, read.first == 128 ? 22.0 : 85.0, 1.5) << address;
    }
  }
}

}  // namespace
}  // namespace bosfuse
