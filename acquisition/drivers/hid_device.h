#pragma once
// HidDevice reads a USB-HID thermometer through hidapi (hidraw backend):
// it finds the device by vendor and product id (and interface number and
// serial when given), sends the protocol's set-up reports once after
// opening, and for each poll writes each channel's request report and reads
// its reply. A device that vanishes makes read() throw DeviceError, so the
// poller records the disconnect and reopens it when it returns.

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "acquisition/drivers/hid_protocol.h"
#include "acquisition/thermocouple_source.h"

// hidapi's device, declared as <hidapi/hidapi.h> declares it, so that only
// hid_device.cc includes the C header.
struct hid_device_;
typedef struct hid_device_ hid_device;

namespace bosfuse::acquisition {

struct HidMatch {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::optional<int> interface_number;
  std::optional<std::string> serial;
  std::string describe() const;  // 09db:0090 if 1 serial ABC
};

struct HidClose {
  void operator()(hid_device* device) const noexcept;  // hid_close
};
using HidHandle = std::unique_ptr<hid_device, HidClose>;

class HidDevice : public ThermocoupleSource {
 public:
  HidDevice(std::string name, std::string profile, HidMatch match, HidProtocol protocol,
            std::chrono::milliseconds timeout);

  storage::DeviceInfo device_info() const override;
  std::vector<storage::ChannelInfo> channel_infos() const override;
  void connect() override;
  void disconnect() override;
  std::vector<ChannelReading> read() override;

 private:
  std::string find_path() const;
  std::vector<std::uint8_t> exchange(const std::vector<std::uint8_t>& request);

  std::string name_;
  std::string profile_;
  HidMatch match_;
  HidProtocol protocol_;
  std::chrono::milliseconds timeout_;
  HidHandle device_;
};

}  // namespace bosfuse::acquisition
