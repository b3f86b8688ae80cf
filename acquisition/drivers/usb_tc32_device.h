#pragma once
// UsbTc32Device reads a Measurement Computing USB-TC-32 over raw USB with
// libusb: vendor control transfers on endpoint 0, one per channel and poll
// (see usb_tc32_protocol.h). On connect it writes the configured
// thermocouple types. Where libusb supports hot-plug (Linux does), it
// watches for the device leaving and arriving: an unplug fails the next read
// at once instead of after a time-out, and both become notices the poller
// records as events; the poller's reconnection then resumes reading.

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/alarm_limits.h"
#include "acquisition/thermocouple_source.h"
#include "acquisition/drivers/usb_tc32_protocol.h"

// libusb's handles, declared as <libusb.h> declares them, so that only
// usb_tc32_device.cc includes the C header.
struct libusb_context;
struct libusb_device_handle;
typedef struct libusb_context libusb_context;
typedef struct libusb_device_handle libusb_device_handle;

namespace bosfuse::acquisition {

struct UsbTc32Channel {
  std::string name;
  int input = 0;               // 0-63
  bool cold_junction = false;  // the CJC sensor serving `input`
  char tc_type = 'K';
  std::optional<double> image_x_px;
  std::optional<double> image_y_px;
  std::optional<double> time_constant_s;  // the sensor's first-order response time (agreement removes its lag)
  std::optional<double> resolution;       // the experiment file's `resolution` in °C (the device sends floats)
  AlarmLimits alarms{};
};

struct LibusbContextFree {
  void operator()(libusb_context* context) const noexcept;  // libusb_exit
};
struct LibusbHandleClose {
  void operator()(libusb_device_handle* handle) const noexcept;  // libusb_close
};
using LibusbHandle = std::unique_ptr<libusb_device_handle, LibusbHandleClose>;

class UsbTc32Device : public ThermocoupleSource {
 public:
  UsbTc32Device(std::string name, std::optional<std::string> serial, std::vector<UsbTc32Channel> channels,
                std::chrono::milliseconds timeout);
  ~UsbTc32Device() override;

  storage::DeviceInfo device_info() const override;
  std::vector<storage::ChannelInfo> channel_infos() const override;
  void connect() override;
  void disconnect() override;
  std::vector<ChannelReading> read() override;
  std::vector<std::string> take_notices() override;

  // What libusb's hot-plug callback (in the .cc, where libusb's types are)
  // reports, on libusb's event thread.
  void on_hotplug(bool arrived, const std::string& where);

 private:
  void start_hotplug_watch();
  void notice(std::string text);
  LibusbHandle open_matching();
  std::vector<std::uint8_t> transfer(const ControlRequest& request);

  std::string name_;
  std::optional<std::string> serial_;
  std::vector<UsbTc32Channel> channels_;
  std::chrono::milliseconds timeout_;

  std::unique_ptr<libusb_context, LibusbContextFree> context_;
  LibusbHandle handle_;
  int hotplug_ = 0;  // libusb_hotplug_callback_handle, an int
  std::atomic<bool> watching_{false};
  std::atomic<bool> unplugged_{false};
  std::thread event_thread_;
  std::mutex notices_mutex_;
  std::vector<std::string> notices_;
};

}  // namespace bosfuse::acquisition
