// The real hidapi path (hidraw backend, libudev enumeration) against USB-HID
// thermometers emulated by umockdev: devices are configured from TOML as a
// user would, found by vendor, product and interface, and every report the
// reader writes must match the device's script byte for byte.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <thread>

#include "acquisition/device_poller.h"
#include "acquisition/config/experiment_config.h"
#include "tests/support/temp_dir.h"
#include "tests/support/umockdev_bed.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;
using storage::SampleStatus;
using testing::EmulatedHid;
using testing::expect_write;
using testing::reply;
using testing::ScriptStep;
using testing::UmockdevBed;

const EmulatedHid kUsbTc{0x09db, 0x0090, 0, "MCC", "USB-TC", "01A2B3C4"};
const EmulatedHid kTemperKeyboard{0x0c45, 0x7401, 0, "RDing", "TEMPerV1.4", ""};
const EmulatedHid kTemperSensor{0x0c45, 0x7401, 1, "RDing", "TEMPerV1.4", ""};

std::vector<std::uint8_t> float_reply(std::uint8_t report_id, float value) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  return {report_id, std::uint8_t(bits), std::uint8_t(bits >> 8), std::uint8_t(bits >> 16), std::uint8_t(bits >> 24)};
}

HidDeviceConfig hid_config(const std::string& toml) {
  const ExperimentConfig config = parse_experiment(toml, "test.toml");
  EXPECT_EQ(config.hid_devices.size(), 1u);
  return config.hid_devices.at(0);
}

std::unique_ptr<HidDevice> make_device(const HidDeviceConfig& d) {
  return std::make_unique<HidDevice>(d.name, d.profile, d.match, d.protocol, d.timeout);
}

constexpr const char* kUsbTcToml = R"(
[[devices]]
name = "usb-tc"
kind = "hid"
profile = "mcc-usb-tc"
timeout_s = 0.5
  [[devices.channels]]
  name = "plume"
  input = 0
  tc_type = "K"
  [[devices.channels]]
  name = "ambient"
  input = 3
  tc_type = "J"
  [[devices.channels]]
  name = "cjc"
  input = "cold-junction-0"
)";

// Set-up: the thermocouple types, sent once after opening.
std::vector<ScriptStep> usb_tc_setup() {
  return {expect_write({0x49, 0x00, 0x10, 0x01}),   // input 0: K
          expect_write({0x49, 0x01, 0x11, 0x00})};  // input 3: J
}

// One poll: three TIN exchanges, then the burnout bitmap.
std::vector<ScriptStep> usb_tc_poll(float plume_c, float ambient_c, float cjc_c, std::uint8_t burnout) {
  return {expect_write({0x18, 0x00, 0x00}), reply(float_reply(0x18, plume_c)),
          expect_write({0x18, 0x03, 0x00}), reply(float_reply(0x18, ambient_c)),
          expect_write({0x18, 0x80, 0x00}), reply(float_reply(0x18, cjc_c)),
          expect_write({0x4C, 0x00}),       reply({0x4C, burnout})};
}

template <typename... Parts>
std::vector<ScriptStep> join(Parts... parts) {
  std::vector<ScriptStep> all;
  (all.insert(all.end(), parts.begin(), parts.end()), ...);
  return all;
}

TEST(UmockdevHid, MccUsbTcIsFoundConfiguredAndRead) {
  UmockdevBed bed;
  bed.add_hid(kUsbTc, 0, 1);
  bed.script(0, join(usb_tc_setup(), usb_tc_poll(81.25f, 21.5f, 23.0f, 0x00)));

  auto device = make_device(hid_config(kUsbTcToml));
  ASSERT_NO_THROW(device->connect());
  const auto readings = device->read();
  ASSERT_EQ(readings.size(), 3u);
  EXPECT_EQ(readings[0].status, SampleStatus::kOk);
  EXPECT_DOUBLE_EQ(readings[0].value.value_or(NAN), 81.25);
  EXPECT_DOUBLE_EQ(readings[1].value.value_or(NAN), 21.5);
  EXPECT_DOUBLE_EQ(readings[2].value.value_or(NAN), 23.0);
  EXPECT_EQ(device->channel_infos()[2].kind, "cold-junction");
  EXPECT_EQ(device->device_info().address, "09db:0090");
}

TEST(UmockdevHid, BurnoutBitmapNanAndShortRepliesBecomeStatuses) {
  UmockdevBed bed;
  bed.add_hid(kUsbTc, 0, 1);
  const std::vector<ScriptStep> bad_poll = {
      expect_write({0x18, 0x00, 0x00}), reply({0x18, 0x00, 0x00}),        // two bytes short
      expect_write({0x18, 0x03, 0x00}), reply(float_reply(0x18, NAN)),    // not a number
      expect_write({0x18, 0x80, 0x00}), reply(float_reply(0x18, 22.0f)),  //
      expect_write({0x4C, 0x00}),       reply({0x4C, 0x00})};
  bed.script(0, join(usb_tc_setup(), usb_tc_poll(300.0f, 21.0f, 22.0f, 0x01), bad_poll));

  auto device = make_device(hid_config(kUsbTcToml));
  device->connect();
  const auto burnt = device->read();
  EXPECT_EQ(burnt[0].status, SampleStatus::kOpenCircuit);  // bit 0: input 0 is open
  EXPECT_FALSE(burnt[0].value.has_value());
  EXPECT_EQ(burnt[1].status, SampleStatus::kOk);
  const auto bad = device->read();
  EXPECT_EQ(bad[0].status, SampleStatus::kBadReply);
  EXPECT_EQ(bad[1].status, SampleStatus::kInvalidValue);
  EXPECT_FALSE(bad[1].value.has_value());
  EXPECT_EQ(bad[2].status, SampleStatus::kOk);
}

TEST(UmockdevHid, TemperIsReadOnItsSecondInterface) {
  UmockdevBed bed;
  bed.add_hid(kTemperKeyboard, 0, 2);  // the keyboard interface must not be chosen
  bed.add_hid(kTemperSensor, 1, 2);
  // 0x1A80 / 256 = 26.5 degC; hidapi passes report id 0 through to hidraw.
  bed.script(1, {expect_write({0x00, 0x01, 0x80, 0x33, 0x01, 0x00, 0x00, 0x00, 0x00}),
                 reply({0x80, 0x02, 0x1A, 0x80, 0x4E, 0x20, 0x00, 0x00}),
                 expect_write({0x00, 0x01, 0x80, 0x33, 0x01, 0x00, 0x00, 0x00, 0x00}),
                 reply({0x80, 0x02, 0xFF, 0x00, 0x4E, 0x20, 0x00, 0x00})});  // -1.0 degC
  auto device = make_device(hid_config(R"(
[[devices]]
name = "room"
kind = "hid"
profile = "temper"
  [[devices.channels]]
  name = "air"
)"));
  device->connect();
  EXPECT_DOUBLE_EQ(device->read().at(0).value.value_or(NAN), 26.5);
  EXPECT_DOUBLE_EQ(device->read().at(0).value.value_or(NAN), -1.0);
}

TEST(UmockdevHid, AbsentDeviceIsADeviceErrorNamingIt) {
  UmockdevBed bed;
  auto device = make_device(hid_config(kUsbTcToml));
  try {
    device->connect();
    FAIL() << "connected to a device that is not there";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("09db:0090"), std::string::npos) << e.what();
  }
}

// Unplugged mid-run, plugged back in: the poller records both and reads on.
TEST(UmockdevHid, UnplugAndReplugAreEventsAndTheRunGoesOn) {
  UmockdevBed bed;
  const std::string usb = bed.add_hid(kUsbTc, 0, 1);
  bed.script(0, join(usb_tc_setup(), usb_tc_poll(80.0f, 21.0f, 22.0f, 0), usb_tc_poll(79.0f, 21.0f, 22.0f, 0)));

  testing::TempDir dir;
  auto store = storage::RunStore::create(dir / "run", {0, "t", 0, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                         storage::RunStore::CreateMode::kNew);
  const HidDeviceConfig config = hid_config(kUsbTcToml);
  auto device = make_device(config);
  const std::int64_t device_id = store.add_device(device->device_info());
  std::vector<std::int64_t> channel_ids;
  for (auto channel : device->channel_infos()) {
    channel.device_id = device_id;
    channel_ids.push_back(store.add_channel(channel));
  }
  {
    storage::RunWriter writer(store, {20ms, 10'000});
    DevicePollerOptions options{100ms, 50ms, 200ms, {}};
    // One poll is scripted after the replug: it ends the outage here (the
    // debounce of several good polls is tested in device_poller_test.cc).
    options.recovery_polls = 1;
    const auto shared_poller =
        std::make_shared<DevicePoller>(std::move(device), device_id, channel_ids, writer, options);
    DevicePoller& poller = *shared_poller;
    poller.start();
    // Two polls are scripted; after them the device hangs up. Unplug it.
    for (int i = 0; i < 100 && poller.stats().polls_ok < 2; ++i) std::this_thread::sleep_for(20ms);
    bed.remove(usb);
    for (int i = 0; i < 100 && poller.stats().polls_failed == 0; ++i) std::this_thread::sleep_for(20ms);
    EXPECT_FALSE(poller.stats().connected);

    bed.add_hid(kUsbTc, 1, 3);  // plugged back in, into another port
    bed.script(1, join(usb_tc_setup(), usb_tc_poll(70.5f, 21.0f, 22.0f, 0)));
    for (int i = 0; i < 150 && poller.stats().reconnects == 0; ++i) std::this_thread::sleep_for(20ms);
    for (int i = 0; i < 100 && poller.stats().polls_ok < 3; ++i) std::this_thread::sleep_for(20ms);
    poller.stop();
    writer.flush();
    EXPECT_EQ(poller.stats().reconnects, 1);
    EXPECT_GE(poller.stats().polls_ok, 3);
  }
  std::vector<std::string> kinds;
  for (const auto& e : store.events()) kinds.push_back(e.kind);
  EXPECT_NE(std::find(kinds.begin(), kinds.end(), "disconnect"), kinds.end());
  EXPECT_NE(std::find(kinds.begin(), kinds.end(), "reconnect"), kinds.end());
  std::vector<double> plume;
  for (const auto& s : store.read_samples(channel_ids[0])) {
    if (s.value) plume.push_back(*s.value);
  }
  EXPECT_EQ(plume, (std::vector<double>{80.0, 79.0, 70.5}));
}

}  // namespace
}  // namespace bosfuse::acquisition
