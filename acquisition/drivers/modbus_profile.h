#pragma once
// Built-in register maps of thermocouple modules, so a configuration names a
// module and its inputs instead of spelling out registers:
//   adam-6018     Advantech ADAM-6018, Modbus TCP: holding registers 0-7
//                 (40001-40008), uint16 mapped linearly over the input
//                 type's range (K: 0-1370 degC); 0xFFFF means burnout.
//   icpdas-m7018  ICP DAS M-7018, Modbus RTU: input registers 0-7
//                 (30001-30008) in engineering format, int16 in 0.01 degC;
//                 cold-junction temperature at input register 128 (30129),
//                 also 0.01 degC. +32767 is over-range/open input, -32768
//                 under-range. (int16 in 0.01 degC limits this encoding to
//                 -327.68..327.67 degC.)
//   generic       nothing built in: every channel describes its registers.
// Check a real module's manual (and its configured data format) before
// relying on a profile.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/drivers/modbus_channel.h"

namespace bosfuse::acquisition {

enum class ModbusTransport { kTcp, kRtu };

struct ModbusProfile {
  std::string_view name;
  std::optional<ModbusTransport> usual_transport;
  int input_count = 0;  // thermocouple inputs; 0 for generic
  bool has_cold_junction = false;
};

const ModbusProfile* find_modbus_profile(std::string_view name);
std::vector<std::string_view> modbus_profile_names();

// Input range of a thermocouple type on the ADAM-6018 (degC), or nullopt.
std::optional<LinearMapping> adam6018_type_range(std::string_view tc_type);

// The register map of thermocouple input `input` (0-based) of `profile`;
// throws std::invalid_argument naming the problem.
ModbusChannel profile_input_channel(std::string_view profile, int input, const std::string& tc_type);
ModbusChannel profile_cold_junction_channel(std::string_view profile);

}  // namespace bosfuse::acquisition
