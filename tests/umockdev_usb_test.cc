// The libusb path of the USB-TC-32 reader against umockdev. Debian 12's
// umockdev (0.17) cannot complete a control transfer through libusb (a
// synchronous transfer never returns), so the readings themselves are tested
// on recorded bytes in acquisition/drivers/usb_tc32_protocol_test.cc; here libusb's
// real enumeration and hot-plug notices are exercised.

#include <gtest/gtest.h>

#include <thread>

#include "acquisition/drivers/usb_tc32_device.h"
#include "tests/support/umockdev_bed.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;

std::vector<std::string> notices_within(UsbTc32Device& device, std::size_t count, std::chrono::milliseconds limit) {
  std::vector<std::string> all;
  for (auto waited = 0ms; waited < limit && all.size() < count; waited += 20ms) {
    for (auto& n : device.take_notices()) all.push_back(std::move(n));
    std::this_thread::sleep_for(20ms);
  }
  return all;
}

UsbTc32Device make_device() { return UsbTc32Device("tc32", std::nullopt, {{"plume", 0, false, 'K', {}, {}}}, 200ms); }

TEST(UmockdevUsb, AbsentDeviceIsADeviceErrorNamingIt) {
  testing::UmockdevBed bed;
  UsbTc32Device device = make_device();
  try {
    device.connect();
    FAIL() << "connected to a device that is not there";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("no USB-TC-32"), std::string::npos) << e.what();
  }
}

TEST(UmockdevUsb, PlugAndUnplugBecomeNotices) {
  testing::UmockdevBed bed;
  UsbTc32Device device = make_device();
  EXPECT_THROW(device.connect(), DeviceError);  // starts watching for the device
  const std::string usb = bed.add_usb(kUsbTc32VendorId, kUsbTc32ProductId, 7, 4);
  const auto arrived = notices_within(device, 1, 3000ms);
  ASSERT_EQ(arrived.size(), 1u);
  EXPECT_EQ(arrived[0], "USB-TC-32 plugged in at bus 1 device 7");
  bed.unplug_usb(usb);
  const auto left = notices_within(device, 1, 3000ms);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0], "USB-TC-32 unplugged from bus 1 device 7");
}

}  // namespace
}  // namespace bosfuse::acquisition
