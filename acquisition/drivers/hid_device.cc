#include "acquisition/drivers/hid_device.h"

#include <hidapi/hidapi.h>

#include <array>
#include <cstdio>
#include <cwchar>
#include <mutex>

namespace bosfuse::acquisition {
namespace {

constexpr std::size_t kMaxReportBytes = 64;

std::string narrow(const wchar_t* text) {
  std::string out;
  for (; text && *text; ++text) out += *text < 128 ? static_cast<char>(*text) : '?';
  return out;
}

std::string hid_failure(hid_device* device) {
  const wchar_t* message = hid_error(device);
  return message ? narrow(message) : "unknown hidapi error";
}

// hid_init is not thread-safe; every device thread goes through here.
void ensure_hidapi() {
  static std::once_flag once;
  std::call_once(once, [] { hid_init(); });
}

struct EnumerationFree {
  void operator()(hid_device_info* list) const noexcept { hid_free_enumeration(list); }
};

bool matches(const hid_device_info& info, const HidMatch& match) {
  if (match.interface_number && info.interface_number != *match.interface_number) return false;
  return !match.serial || narrow(info.serial_number) == *match.serial;
}

}  // namespace

void HidClose::operator()(hid_device* device) const noexcept { hid_close(device); }

std::string HidMatch::describe() const {
  char ids[16];
  std::snprintf(ids, sizeof ids, "%04x:%04x", vendor_id, product_id);
  std::string text = ids;
  if (interface_number) text += " if " + std::to_string(*interface_number);
  if (serial) text += " serial " + *serial;
  return text;
}

HidDevice::HidDevice(std::string name, std::string profile, HidMatch match, HidProtocol protocol,
                     std::chrono::milliseconds timeout)
    : name_(std::move(name)),
      profile_(std::move(profile)),
      match_(std::move(match)),
      protocol_(std::move(protocol)),
      timeout_(timeout) {}

storage::DeviceInfo HidDevice::device_info() const { return {0, name_, "hid", profile_, match_.describe()}; }

std::vector<storage::ChannelInfo> HidDevice::channel_infos() const {
  std::vector<storage::ChannelInfo> infos;
  for (const auto& c : protocol_.channels) {
    infos.push_back({0, 0, c.name, c.kind, c.unit, c.tc_type, c.image_x_px, c.image_y_px, c.stored_resolution()});
  }
  return infos;
}

std::string HidDevice::find_path() const {
  ensure_hidapi();
  std::unique_ptr<hid_device_info, EnumerationFree> list(hid_enumerate(match_.vendor_id, match_.product_id));
  for (const hid_device_info* info = list.get(); info; info = info->next) {
    if (matches(*info, match_)) return info->path;
  }
  throw DeviceError("no HID device " + match_.describe() + " is connected");
}

void HidDevice::connect() {
  const std::string path = find_path();
  device_.reset(hid_open_path(path.c_str()));
  if (!device_) throw DeviceError("cannot open " + path + ": " + hid_failure(nullptr));
  for (const auto& request : protocol_.setup_requests) {
    if (hid_write(device_.get(), request.data(), request.size()) < 0) {
      const std::string message = "set-up report to " + path + " failed: " + hid_failure(device_.get());
      device_.reset();
      throw DeviceError(message);
    }
  }
}

void HidDevice::disconnect() { device_.reset(); }

std::vector<std::uint8_t> HidDevice::exchange(const std::vector<std::uint8_t>& request) {
  if (hid_write(device_.get(), request.data(), request.size()) < 0) {
    throw DeviceError(match_.describe() + ": write failed: " + hid_failure(device_.get()));
  }
  std::array<std::uint8_t, kMaxReportBytes> reply{};
  const int n = hid_read_timeout(device_.get(), reply.data(), reply.size(), static_cast<int>(timeout_.count()));
  if (n < 0) throw DeviceError(match_.describe() + ": read failed: " + hid_failure(device_.get()));
  if (n == 0) throw DeviceError(match_.describe() + ": no reply within " + std::to_string(timeout_.count()) + " ms");
  return {reply.begin(), reply.begin() + n};
}

std::vector<ChannelReading> HidDevice::read() {
  if (!device_) throw DeviceError("not connected to " + match_.describe());
  std::vector<ChannelReading> readings;
  for (const HidChannel& channel : protocol_.channels) readings.push_back(channel.decode(exchange(channel.request)));
  if (protocol_.burnout_request) protocol_.apply_burnout(exchange(*protocol_.burnout_request), readings);
  return readings;
}

}  // namespace bosfuse::acquisition
