#pragma once
// ExperimentConfig is what an experiment TOML file describes (documented in
// docs/CONFIG.md, example in examples/): the run's name and the devices to
// log, each with its transport, profile, poll period and channels, and where
// each thermocouple sits in the camera image. Parsing checks everything a
// user can get wrong and names the key and line; the verbatim text is kept
// so a run stores exactly the configuration it was recorded with.

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/hid_device.h"
#include "acquisition/modbus_device.h"
#include "acquisition/toml_reader.h"
#include "acquisition/usb_tc32_device.h"

namespace bosfuse::acquisition {

struct ModbusDeviceConfig {
  std::string name;
  std::string profile;
  ModbusEndpoint endpoint;
  std::chrono::nanoseconds poll_period = std::chrono::seconds(1);
  std::chrono::milliseconds timeout{500};
  std::vector<ModbusChannel> channels;
};

struct HidDeviceConfig {
  std::string name;
  std::string profile;  // mcc-usb-tc, temper or generic-hid
  HidMatch match;
  HidProtocol protocol;
  std::chrono::nanoseconds poll_period = std::chrono::seconds(1);
  std::chrono::milliseconds timeout{500};
};

struct UsbDeviceConfig {
  std::string name;
  std::string profile;  // usb-tc-32
  std::optional<std::string> serial;
  std::vector<UsbTc32Channel> channels;
  std::chrono::nanoseconds poll_period = std::chrono::seconds(1);
  std::chrono::milliseconds timeout{500};
};

struct ExperimentConfig {
  std::string run_name;
  std::string description;
  std::vector<ModbusDeviceConfig> modbus_devices;
  std::vector<HidDeviceConfig> hid_devices;
  std::vector<UsbDeviceConfig> usb_devices;
  std::string source_text;  // the file as written

  std::size_t device_count() const { return modbus_devices.size() + hid_devices.size() + usb_devices.size(); }
};

ExperimentConfig parse_experiment(std::string_view text, const std::string& source_name);
ExperimentConfig load_experiment(const std::filesystem::path& path);  // throws ConfigError

}  // namespace bosfuse::acquisition
