#include "acquisition/drivers/usb_tc32_device.h"

#include <libusb.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <type_traits>

namespace bosfuse::acquisition {
namespace {

constexpr int kInterface = 0;
constexpr auto kEventPollInterval = std::chrono::milliseconds(100);

std::string usb_failure(const std::string& what, int code) {
  return what + ": " + libusb_strerror(static_cast<libusb_error>(code));
}

std::string location(libusb_device* device) {
  char text[48];
  std::snprintf(text, sizeof text, "bus %d device %d", libusb_get_bus_number(device),
                libusb_get_device_address(device));
  return text;
}

std::string serial_of(libusb_device_handle* handle, const libusb_device_descriptor& descriptor) {
  unsigned char text[128] = {};
  if (descriptor.iSerialNumber == 0) return {};
  const int n = libusb_get_string_descriptor_ascii(handle, descriptor.iSerialNumber, text, sizeof text);
  return n > 0 ? std::string(reinterpret_cast<char*>(text), static_cast<std::size_t>(n)) : std::string();
}

struct DeviceListFree {
  void operator()(libusb_device** list) const noexcept { libusb_free_device_list(list, 1); }
};

static_assert(std::is_same_v<libusb_hotplug_callback_handle, int>, "usb_tc32_device.h keeps the handle as an int");

int hotplug_callback(libusb_context*, libusb_device* device, libusb_hotplug_event event, void* self) {
  static_cast<UsbTc32Device*>(self)->on_hotplug(event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED, location(device));
  return 0;  // stay registered
}

}  // namespace

void LibusbContextFree::operator()(libusb_context* context) const noexcept { libusb_exit(context); }
void LibusbHandleClose::operator()(libusb_device_handle* handle) const noexcept { libusb_close(handle); }

UsbTc32Device::UsbTc32Device(std::string name, std::optional<std::string> serial, std::vector<UsbTc32Channel> channels,
                             std::chrono::milliseconds timeout)
    : name_(std::move(name)), serial_(std::move(serial)), channels_(std::move(channels)), timeout_(timeout) {}

UsbTc32Device::~UsbTc32Device() {
  if (watching_.exchange(false)) {
    libusb_hotplug_deregister_callback(context_.get(), hotplug_);
    if (event_thread_.joinable()) event_thread_.join();
  }
  handle_.reset();
  context_.reset();
}

storage::DeviceInfo UsbTc32Device::device_info() const {
  return {0, name_, "usb", "usb-tc-32", "09db:0131" + (serial_ ? " serial " + *serial_ : std::string())};
}

std::vector<storage::ChannelInfo> UsbTc32Device::channel_infos() const {
  std::vector<storage::ChannelInfo> infos;
  for (const auto& c : channels_) {
    const std::optional<std::string> type = c.cold_junction ? std::nullopt : std::optional(std::string(1, c.tc_type));
    infos.push_back(
        {0,           0, c.name, c.cold_junction ? "cold-junction" : "thermocouple", "degC", type, c.image_x_px,
         c.image_y_px, c.resolution});
  }
  return infos;
}

void UsbTc32Device::on_hotplug(bool arrived, const std::string& where) {
  if (!arrived) unplugged_ = true;  // fail the next read now rather than after a time-out
  notice((arrived ? "USB-TC-32 plugged in at " : "USB-TC-32 unplugged from ") + where);
}

void UsbTc32Device::notice(std::string text) {
  std::lock_guard lock(notices_mutex_);
  notices_.push_back(std::move(text));
}

std::vector<std::string> UsbTc32Device::take_notices() {
  std::lock_guard lock(notices_mutex_);
  return std::exchange(notices_, {});
}

// Hot-plug callbacks run inside libusb's event handling, which needs a thread.
void UsbTc32Device::start_hotplug_watch() {
  if (watching_ || !libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) return;
  const int events = LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT;
  const int result = libusb_hotplug_register_callback(context_.get(), events, LIBUSB_HOTPLUG_NO_FLAGS, kUsbTc32VendorId,
                                                      kUsbTc32ProductId, LIBUSB_HOTPLUG_MATCH_ANY,
                                                      hotplug_callback, this, &hotplug_);
  if (result != LIBUSB_SUCCESS) {
    spdlog::warn("{}: {}; unplugging is noticed at the next read", name_, usb_failure("no hot-plug notices", result));
    return;
  }
  watching_ = true;
  event_thread_ = std::thread([this] {
    timeval interval{0, static_cast<long>(std::chrono::microseconds(kEventPollInterval).count())};
    while (watching_) libusb_handle_events_timeout_completed(context_.get(), &interval, nullptr);
  });
}

LibusbHandle UsbTc32Device::open_matching() {
  libusb_device** raw_list = nullptr;
  const ssize_t count = libusb_get_device_list(context_.get(), &raw_list);
  if (count < 0) throw DeviceError(usb_failure("cannot list USB devices", static_cast<int>(count)));
  const std::unique_ptr<libusb_device*, DeviceListFree> list(raw_list);
  std::string refused;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list.get()[i], &descriptor) != 0) continue;
    if (descriptor.idVendor != kUsbTc32VendorId || descriptor.idProduct != kUsbTc32ProductId) continue;
    libusb_device_handle* raw_handle = nullptr;
    if (const int result = libusb_open(list.get()[i], &raw_handle); result != 0) {
      refused = usb_failure(location(list.get()[i]), result);
      continue;
    }
    LibusbHandle handle(raw_handle);
    if (!serial_ || serial_of(handle.get(), descriptor) == *serial_) return handle;
  }
  throw DeviceError("no USB-TC-32 " + (serial_ ? "with serial " + *serial_ + " " : std::string()) + "is connected" +
                    (refused.empty() ? "" : " that can be opened (" + refused + ")"));
}

void UsbTc32Device::connect() {
  if (!context_) {
    libusb_context* context = nullptr;
    if (const int result = libusb_init(&context); result != 0) throw DeviceError(usb_failure("libusb", result));
    context_.reset(context);
    start_hotplug_watch();
  }
  unplugged_ = false;
  handle_ = open_matching();
  libusb_set_auto_detach_kernel_driver(handle_.get(), 1);
  if (const int result = libusb_claim_interface(handle_.get(), kInterface); result != 0) {
    handle_.reset();
    throw DeviceError(usb_failure("cannot claim the USB-TC-32's interface", result));
  }
  std::vector<std::pair<int, char>> types;
  for (const auto& c : channels_) {
    if (!c.cold_junction) types.emplace_back(c.input, c.tc_type);
  }
  transfer(tc32_type_config_request(types));
}

void UsbTc32Device::disconnect() { handle_.reset(); }

std::vector<std::uint8_t> UsbTc32Device::transfer(const ControlRequest& request) {
  if (unplugged_) throw DeviceError("USB-TC-32 was unplugged");
  if (!handle_) throw DeviceError("not connected to the USB-TC-32");
  std::vector<std::uint8_t> data = request.data;
  const int result = libusb_control_transfer(handle_.get(), request.request_type, request.request, request.value,
                                             request.index, data.data(), static_cast<std::uint16_t>(data.size()),
                                             static_cast<unsigned>(timeout_.count()));
  if (result < 0) throw DeviceError(usb_failure("USB-TC-32 request failed", result));
  data.resize(static_cast<std::size_t>(result));
  return data;
}

std::vector<ChannelReading> UsbTc32Device::read() {
  std::vector<ChannelReading> readings;
  for (const auto& c : channels_) {
    const ControlRequest request =
        c.cold_junction ? tc32_cold_junction_request(c.input) : tc32_temperature_request(c.input);
    readings.push_back(decode_tc32_reading(transfer(request)));
  }
  return readings;
}

}  // namespace bosfuse::acquisition
