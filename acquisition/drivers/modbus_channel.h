#pragma once
// A ModbusChannel says where one measurement lives in a device's registers
// and how to turn those registers into a value with a status: function code,
// address, data type and word order, then either scale and offset or a
// linear raw-to-range mapping, plus the raw codes a device uses for an open
// thermocouple or an out-of-range input. decode() never invents a value: a
// reading that is not a temperature gets a status and no value. encode() is
// the inverse, used by the simulator so it serves exactly what the reader
// decodes.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "acquisition/alarm_limits.h"
#include "acquisition/device_reading.h"
#include "acquisition/drivers/register_codec.h"
#include "storage/records.h"

namespace bosfuse::acquisition {

enum class RegisterKind { kHolding = 3, kInput = 4 };  // Modbus function codes 3 and 4

struct LinearMapping {
  double raw_low = 0;
  double raw_high = 65535;
  double value_low = 0;
  double value_high = 1;
};

struct ModbusChannel {
  // What it measures.
  std::string name;
  std::string kind = "thermocouple";  // thermocouple, cold-junction, voltage, ...
  std::string unit = "degC";
  std::optional<std::string> tc_type;
  std::optional<double> image_x_px;
  std::optional<double> image_y_px;
  std::optional<double> time_constant_s;  // the sensor's first-order response time (agreement removes its lag)
  std::optional<double> resolution;       // the experiment file's `resolution`, in `unit`

  // Where and how it is encoded.
  RegisterKind function = RegisterKind::kHolding;
  int address = 0;  // 0-based protocol address (40001 in a manual is 0)
  DataType type = DataType::kUint16;
  WordOrder order = WordOrder::kABCD;
  double scale = 1.0;
  double offset = 0.0;
  std::optional<LinearMapping> linear;  // replaces scale/offset when set
  std::vector<double> open_circuit_codes;
  std::vector<double> out_of_range_codes;
  std::optional<double> valid_min;  // engineering units; outside is out-of-range
  std::optional<double> valid_max;

  AlarmLimits alarms{};  // judged on the decoded value, not on the registers

  std::string Validate() const;  // empty when valid, else what is wrong
  int register_count() const { return acquisition::register_count(type); }

  ChannelReading decode(std::span<const std::uint16_t> registers) const;
  double to_value(double raw) const;
  // The step of one register count in `unit` (|scale|, or the linear
  // mapping's slope); none for a float register, which has no fixed step.
  std::optional<double> register_step() const;
  // What is stored as the channel's resolution: the file's, else the step.
  std::optional<double> stored_resolution() const { return resolution ? resolution : register_step(); }
  double to_raw(double value) const;
  std::vector<std::uint16_t> encode(double value) const;
  std::vector<std::uint16_t> encode_raw(double raw) const;
};

}  // namespace bosfuse::acquisition
