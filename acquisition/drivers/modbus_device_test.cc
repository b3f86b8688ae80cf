#include "acquisition/drivers/modbus_device.h"

#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <cerrno>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;

TEST(ModbusFailure, ExceptionRepliesAreBadRepliesCarryingTheirCode) {
  for (const int code : {MODBUS_EXCEPTION_ILLEGAL_FUNCTION, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS,
                         MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE, MODBUS_EXCEPTION_GATEWAY_TARGET}) {
    const DeviceError error = modbus_failure("reading", MODBUS_ENOBASE + code);
    EXPECT_EQ(error.status(), SampleStatus::kBadReply) << code;
    EXPECT_EQ(error.raw(), code);
    EXPECT_TRUE(error.link_alive());
  }
  const std::string what = modbus_failure("reading 8 registers at 0", EMBXILADD).what();
  EXPECT_EQ(what, "reading 8 registers at 0: Modbus exception 2 (Illegal data address)");
}

TEST(ModbusFailure, FramesLibmodbusRejectsAreBadRepliesWithoutCode) {
  for (const int error : {EMBBADDATA, EMBBADCRC, EMBBADSLAVE, EMBBADEXC, EMBMDATA}) {
    const DeviceError failure = modbus_failure("reading", error);
    EXPECT_EQ(failure.status(), SampleStatus::kBadReply) << modbus_strerror(error);
    EXPECT_FALSE(failure.raw().has_value());
    EXPECT_TRUE(failure.link_alive());
  }
}

TEST(ModbusFailure, EverythingElseIsATransportFailure) {
  for (const int error : {ETIMEDOUT, ECONNRESET, ECONNREFUSED, EPIPE, EBADF, EIO}) {
    const DeviceError failure = modbus_failure("reading", error);
    EXPECT_EQ(failure.status(), SampleStatus::kTimeout) << modbus_strerror(error);
    EXPECT_FALSE(failure.raw().has_value());
    EXPECT_FALSE(failure.link_alive());
  }
}

// A name that fails to resolve on this machine without a query to any DNS
// server: the resolver refuses a label over 63 characters before sending.
constexpr const char* kUnresolvableHost =
    "unresolvable-because-this-first-label-is-longer-than-sixty-three-chars.invalid";

TEST(ModbusEndpoint, NamesResolveAndUnresolvableNamesAreRefused) {
  ModbusEndpoint endpoint;
  endpoint.host = "localhost";
  EXPECT_NO_THROW(check_endpoint_resolves(endpoint));
  endpoint.host = "127.0.0.1";
  EXPECT_NO_THROW(check_endpoint_resolves(endpoint));
  endpoint.host = kUnresolvableHost;
  try {
    check_endpoint_resolves(endpoint);
    ADD_FAILURE() << "an unresolvable name passed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cannot resolve host \"" + std::string(kUnresolvableHost) + "\""),
              std::string::npos)
        << e.what();
  }
  endpoint.transport = ModbusTransport::kRtu;
  endpoint.serial_port = "/dev/ttyUSB0";
  EXPECT_NO_THROW(check_endpoint_resolves(endpoint)) << "a serial line has no host to resolve";
}

TEST(ModbusDevice, UnresolvableNameSaysSoWhenConnecting) {
  ModbusEndpoint endpoint;
  endpoint.host = kUnresolvableHost;
  ModbusChannel channel;
  channel.name = "t";
  ModbusDevice device("a", "generic", endpoint, {channel}, std::chrono::milliseconds(100));
  try {
    device.connect();
    ADD_FAILURE() << "connected to a name that does not resolve";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot resolve host \"" + std::string(kUnresolvableHost) + "\""),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace bosfuse::acquisition
