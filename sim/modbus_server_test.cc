// A ModbusDevice against a simulated module that misbehaves on purpose: each
// fault class must reach the poller as the right kind of DeviceError, and a
// fault must not leave bytes behind that spoil the next poll.

#include "sim/modbus_server.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::sim {
namespace {

using namespace std::chrono_literals;
using acquisition::DeviceError;
using acquisition::ModbusDevice;
using acquisition::ModbusEndpoint;
using acquisition::ModbusTransport;
using storage::SampleStatus;
using Malformed = ModbusSimServer::MalformedReply;

constexpr auto kTimeout = 200ms;

ModbusEndpoint loopback(int port = 0) {
  ModbusEndpoint endpoint;
  endpoint.host = "127.0.0.1";
  endpoint.port = port;
  return endpoint;
}

ModbusSimServerOptions adam_options(ModbusEndpoint endpoint = loopback()) {
  SimulatedModule module;
  module.signal = CoolingSignal{22.0, 85.0, 0.2, 0.3, 7};
  return module_server_options(module, std::move(endpoint));
}

ModbusDevice adam_reader(ModbusEndpoint endpoint, int inputs = 2) {
  return ModbusDevice("adam", "adam-6018", std::move(endpoint), module_channels("adam-6018", inputs, "K"), kTimeout);
}

// The error one read fails with; fails the test when the read succeeds.
DeviceError read_error(ModbusDevice& device) {
  try {
    device.read();
  } catch (const DeviceError& e) {
    return e;
  }
  ADD_FAILURE() << "the read succeeded";
  return DeviceError("none");
}

void expect_good_read(ModbusDevice& device, std::size_t channels) {
  const auto readings = device.read();
  ASSERT_EQ(readings.size(), channels);
  for (const auto& r : readings) {
    EXPECT_EQ(r.status, SampleStatus::kOk);
    EXPECT_NEAR(r.value.value_or(0), 85.0, 3.0);
  }
}

class MisbehavingModule : public ::testing::Test {
 protected:
  void SetUp() override {
    server_.start();
    reader_ = std::make_unique<ModbusDevice>(adam_reader(loopback(server_.port())));
    reader_->connect();
  }
  ModbusSimServer server_{adam_options()};
  std::unique_ptr<ModbusDevice> reader_;  // once the server has its port
  ModbusDevice& device() { return *reader_; }
};

TEST_F(MisbehavingModule, ExceptionReplyIsABadReplyCarryingItsCode) {
  for (const int code : {2, 4, 1, 6}) {
    server_.set_exception_reply(code);
    const DeviceError error = read_error(device());
    EXPECT_EQ(error.status(), SampleStatus::kBadReply) << error.what();
    EXPECT_EQ(error.raw(), code) << error.what();
    EXPECT_NE(std::string(error.what()).find("Modbus exception " + std::to_string(code)), std::string::npos)
        << error.what();
  }
  server_.set_exception_reply(std::nullopt);
  expect_good_read(device(), 2);
}

TEST_F(MisbehavingModule, MalformedRepliesAreBadRepliesAndLeaveNothingBehind) {
  for (const Malformed kind : {Malformed::kWrongTransactionId, Malformed::kWrongByteCount,
                               Malformed::kWrongFunctionCode}) {
    SCOPED_TRACE(static_cast<int>(kind));
    server_.set_malformed_reply(kind);
    for (int poll = 0; poll < 3; ++poll) {
      const DeviceError error = read_error(device());
      EXPECT_EQ(error.status(), SampleStatus::kBadReply) << error.what();
      EXPECT_FALSE(error.raw().has_value()) << error.what();
      EXPECT_TRUE(error.link_alive());
    }
    server_.set_malformed_reply(Malformed::kNone);
    // The same connection: a bad reply does not mean a dead link.
    expect_good_read(device(), 2);
    expect_good_read(device(), 2);
  }
}

TEST_F(MisbehavingModule, SilenceIsATimeoutAfterTheResponseTimeout) {
  server_.set_silent(true);
  const auto start = std::chrono::steady_clock::now();
  const DeviceError error = read_error(device());
  const auto elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(error.status(), SampleStatus::kTimeout) << error.what();
  EXPECT_FALSE(error.link_alive());
  EXPECT_GE(elapsed, kTimeout - 10ms);
  EXPECT_LT(elapsed, kTimeout + 300ms);
}

TEST_F(MisbehavingModule, SlowRepliesAreReadWithinTheTimeoutAndTimeOutBeyondIt) {
  server_.set_reply_delay(kTimeout / 4);
  expect_good_read(device(), 2);
  server_.set_reply_delay(kTimeout * 2);
  EXPECT_EQ(read_error(device()).status(), SampleStatus::kTimeout);
}

TEST(SimulatedModule, ServesTheWholeRegisterMapOfItsProfile) {
  EXPECT_EQ(SimulatedModule{}.inputs, acquisition::find_modbus_profile(SimulatedModule{}.profile)->input_count);
  for (const std::string profile : {"adam-6018", "icpdas-m7018"}) {
    SimulatedModule module;
    module.profile = profile;
    module.inputs = 2;  // fewer simulated inputs than the module has
    ModbusSimServer server(module_server_options(module, loopback()));
    server.start();
    const auto& p = *acquisition::find_modbus_profile(profile);
    // A reader of every input (and the cold junction) of the real module.
    ModbusDevice device(profile, profile, loopback(server.port()), module_channels(profile, p.input_count, "K"),
                        kTimeout);
    device.connect();
    EXPECT_EQ(device.read().size(), static_cast<std::size_t>(p.input_count + (p.has_cold_junction ? 1 : 0)))
        << profile;
  }
}

TEST(SimulatedModule, HostNamesResolve) {
  ModbusSimServer server(adam_options());
  server.start();
  ModbusEndpoint by_name = loopback(server.port());
  by_name.host = "localhost";
  ModbusDevice device = adam_reader(by_name);
  device.connect();
  expect_good_read(device, 2);
}

TEST(SimulatedModule, MalformedRepliesAreForTcpOnly) {
  ModbusEndpoint serial;
  serial.transport = ModbusTransport::kRtu;
  serial.serial_port = "/dev/null";
  ModbusSimServer server(adam_options(serial));
  EXPECT_THROW(server.set_malformed_reply(Malformed::kWrongByteCount), std::logic_error);
  EXPECT_THROW(server.set_exception_reply(12), std::invalid_argument);
}

TEST(SimulatedModule, ExceptionRepliesOverRtu) {
  testing::TempDir dir;
  const std::string server_end = (dir / "module").string();
  const std::string reader_end = (dir / "reader").string();
  testing::BackgroundProcess socat({"socat", "pty,raw,echo=0,link=" + server_end, "pty,raw,echo=0,link=" + reader_end});
  ASSERT_TRUE(
      testing::wait_for([&] { return std::filesystem::exists(server_end) && std::filesystem::exists(reader_end); }, 5s))
      << "socat did not create the pseudo-terminal pair";
  ModbusEndpoint endpoint;
  endpoint.transport = ModbusTransport::kRtu;
  endpoint.serial_port = server_end;
  endpoint.baud = 115200;
  ModbusSimServer server(adam_options(endpoint));
  server.start();
  server.set_exception_reply(4);
  endpoint.serial_port = reader_end;
  ModbusDevice device = adam_reader(endpoint);
  device.connect();
  const DeviceError error = read_error(device);
  EXPECT_EQ(error.status(), SampleStatus::kBadReply) << error.what();
  EXPECT_EQ(error.raw(), 4);
  server.set_exception_reply(std::nullopt);
  expect_good_read(device, 2);
}

}  // namespace
}  // namespace bosfuse::sim
