#pragma once
// Some readers deliver a thermocouple's EMF in millivolts instead of a
// temperature (a Modbus voltage input, a generic HID device). EmfConvertingSource
// wraps such a source and turns those channels into °C with the ITS-90
// reference functions, compensating the cold junction in voltage: from
// another channel of the same device (its terminal-block sensor, read in the
// same poll) or from a fixed temperature. Declared per channel in the
// experiment file with `emf_type` and `cold_junction` / `cold_junction_c`.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/thermocouple.h"
#include "acquisition/thermocouple_source.h"

namespace bosfuse::acquisition {

// A channel that delivers millivolts from a `type` thermocouple.
struct EmfInput {
  ThermocoupleType type = ThermocoupleType::kK;
  std::string cold_junction_channel;      // a channel of the same device, in °C ...
  std::optional<double> cold_junction_c;  // ... or a fixed cold-junction temperature
  // The converted channel's resolution in °C, from the experiment file; the
  // millivolt register's step is no °C step (the EMF curve is not linear).
  std::optional<double> resolution_c;
};

struct EmfConversion {
  std::size_t channel = 0;  // index in the source's channels
  EmfInput input;
  std::optional<std::size_t> cold_junction_index;
};

// Converts `readings` in place. A channel whose cold junction has no valid
// reading this poll gets kInvalidValue; an EMF outside the type's range
// kOutOfRange; neither carries a value.
void convert_emf_readings(const std::vector<EmfConversion>& conversions, std::vector<ChannelReading>& readings);

class EmfConvertingSource : public ThermocoupleSource {
 public:
  // Throws std::invalid_argument when a cold-junction channel does not exist.
  EmfConvertingSource(std::unique_ptr<ThermocoupleSource> inner, const std::vector<std::optional<EmfInput>>& inputs);

  storage::DeviceInfo device_info() const override { return inner_->device_info(); }
  std::vector<storage::ChannelInfo> channel_infos() const override;
  void connect() override { inner_->connect(); }
  void disconnect() override { inner_->disconnect(); }
  std::vector<ChannelReading> read() override;
  std::vector<std::string> take_notices() override { return inner_->take_notices(); }

 private:
  std::unique_ptr<ThermocoupleSource> inner_;
  std::vector<EmfConversion> conversions_;
};

// `source` wrapped when any of `inputs` (one per channel) is set, else as is.
std::unique_ptr<ThermocoupleSource> with_emf_conversion(std::unique_ptr<ThermocoupleSource> source,
                                                        const std::vector<std::optional<EmfInput>>& inputs);

}  // namespace bosfuse::acquisition
