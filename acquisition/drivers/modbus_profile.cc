#include "acquisition/drivers/modbus_profile.h"

#include <array>
#include <stdexcept>
#include <string>

namespace bosfuse::acquisition {
namespace {

constexpr std::array<ModbusProfile, 3> kProfiles = {{
    {"adam-6018", ModbusTransport::kTcp, 8, false},
    {"icpdas-m7018", ModbusTransport::kRtu, 8, true},
    {"generic", std::nullopt, 0, false},
}};

struct TypeRange {
  std::string_view type;
  double low_c;
  double high_c;
};
// ADAM-6018 input ranges by thermocouple type (Advantech type codes 0E-14).
constexpr std::array<TypeRange, 7> kAdamRanges = {{{"J", 0, 760},
                                                   {"K", 0, 1370},
                                                   {"T", -100, 400},
                                                   {"E", 0, 1000},
                                                   {"R", 500, 1750},
                                                   {"S", 500, 1750},
                                                   {"B", 500, 1800}}};

constexpr int kM7018ColdJunctionRegister = 128;  // 30129 in the manual

void check_input(const ModbusProfile& profile, int input) {
  if (input < 0 || input >= profile.input_count) {
    throw std::invalid_argument("profile " + std::string(profile.name) + " has inputs 0.." +
                                std::to_string(profile.input_count - 1) + ", not " + std::to_string(input));
  }
}

const ModbusProfile& require_profile(std::string_view name) {
  const ModbusProfile* profile = find_modbus_profile(name);
  if (!profile) throw std::invalid_argument("unknown Modbus profile '" + std::string(name) + "'");
  return *profile;
}

ModbusChannel m7018_register(int address) {
  ModbusChannel channel;
  channel.function = RegisterKind::kInput;
  channel.address = address;
  channel.type = DataType::kInt16;
  channel.scale = 0.01;
  channel.out_of_range_codes = {-32768};
  return channel;
}

}  // namespace

const ModbusProfile* find_modbus_profile(std::string_view name) {
  for (const ModbusProfile& profile : kProfiles) {
    if (profile.name == name) return &profile;
  }
  return nullptr;
}

std::vector<std::string_view> modbus_profile_names() {
  std::vector<std::string_view> names;
  for (const ModbusProfile& profile : kProfiles) names.push_back(profile.name);
  return names;
}

std::optional<LinearMapping> adam6018_type_range(std::string_view tc_type) {
  for (const TypeRange& range : kAdamRanges) {
    if (range.type == tc_type) return LinearMapping{0, 65535, range.low_c, range.high_c};
  }
  return std::nullopt;
}

ModbusChannel profile_input_channel(std::string_view profile_name, int input, const std::string& tc_type) {
  const ModbusProfile& profile = require_profile(profile_name);
  if (profile.input_count == 0) {
    throw std::invalid_argument("profile " + std::string(profile.name) + " has no built-in inputs");
  }
  check_input(profile, input);
  ModbusChannel channel;
  if (profile.name == "adam-6018") {
    const auto range = adam6018_type_range(tc_type);
    if (!range) throw std::invalid_argument("adam-6018 has no range for thermocouple type '" + tc_type + "'");
    channel.function = RegisterKind::kHolding;
    channel.address = input;
    channel.type = DataType::kUint16;
    channel.linear = range;
    channel.open_circuit_codes = {65535};
  } else {
    channel = m7018_register(input);
    channel.open_circuit_codes = {32767};
  }
  channel.tc_type = tc_type;
  return channel;
}

ModbusChannel profile_cold_junction_channel(std::string_view profile_name) {
  const ModbusProfile& profile = require_profile(profile_name);
  if (!profile.has_cold_junction) {
    throw std::invalid_argument("profile " + std::string(profile.name) + " has no cold-junction register");
  }
  ModbusChannel channel = m7018_register(kM7018ColdJunctionRegister);
  channel.kind = "cold-junction";
  return channel;
}

}  // namespace bosfuse::acquisition
