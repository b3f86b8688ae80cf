// The experiment TOML file. The input is the text of an experiment file
// (the seeds are the files in examples/, the dictionary holds the keys and
// values docs/CONFIG.md defines), given to parse_experiment(text, name) as
// `bosfuse acquire` does after reading the file.
// Invariants: parsing either returns or throws a std::exception whose
// message is not empty (never another exception type, a crash or a hang);
// an accepted configuration keeps the text verbatim in source_text, has a
// run name, a positive poll period for every device and only channels whose
// own Validate() accepts them (Modbus and HID), a time scale in its range,
// camera names that are folder names, channel names unique across devices,
// and parsing its source_text again gives the same devices and channels.

#include <chrono>
#include <cstdint>
#include <exception>
#include <set>
#include <string>
#include <string_view>

#include "acquisition/config/experiment_config.h"
#include "acquisition/config/folder_name.h"
#include "fuzz/fuzz_support.h"

using namespace bosfuse::acquisition;

namespace {

void check_config(const ExperimentConfig& config, std::string_view text) {
  FUZZ_CHECK(config.source_text == text);
  for (const auto& d : config.modbus_devices) {
    FUZZ_CHECK(d.poll_period.count() > 0);
    FUZZ_CHECK(d.emf_inputs.size() == d.channels.size());
    for (const auto& c : d.channels) FUZZ_CHECK(c.Validate().empty());
  }
  for (const auto& d : config.hid_devices) {
    FUZZ_CHECK(d.poll_period.count() > 0);
    FUZZ_CHECK(d.emf_inputs.size() == d.protocol.channels.size());
    for (const auto& c : d.protocol.channels) FUZZ_CHECK(c.Validate().empty());
  }
  for (const auto& d : config.usb_devices) {
    FUZZ_CHECK(d.poll_period.count() > 0);
  }
  FUZZ_CHECK(config.time_scale >= kSmallestTimeScale && config.time_scale <= kLargestTimeScale);
  for (const auto& c : config.cameras) FUZZ_CHECK(folder_name_problem(c.name).empty());
  std::set<std::string> channel_keys;
  const auto unique = [&](const std::string& name) { FUZZ_CHECK(channel_keys.insert(channel_name_key(name)).second); };
  for (const auto& d : config.modbus_devices) {
    for (const auto& c : d.channels) unique(c.name);
  }
  for (const auto& d : config.hid_devices) {
    for (const auto& c : d.protocol.channels) unique(c.name);
  }
  for (const auto& d : config.usb_devices) {
    for (const auto& c : d.channels) unique(c.name);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ExperimentConfig config;
  try {
    config = parse_experiment(text, "fuzz.toml");
  } catch (const std::exception& e) {
    FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0');
    return 0;
  }
  check_config(config, text);
  const ExperimentConfig again = parse_experiment(config.source_text, "fuzz.toml");
  FUZZ_CHECK(again.run_name == config.run_name);
  FUZZ_CHECK(again.device_count() == config.device_count());
  for (std::size_t i = 0; i < config.modbus_devices.size(); ++i) {
    FUZZ_CHECK(again.modbus_devices[i].channels.size() == config.modbus_devices[i].channels.size());
  }
  return 0;
}
