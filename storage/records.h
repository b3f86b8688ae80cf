#pragma once
// The plain records a run store holds: what a run, device, channel, sample,
// frame and event are, independent of how SQLite stores them. Times are
// `t_ns`, nanoseconds since the Unix epoch (UTC) from the host clock taken at
// acquisition; a device's own clock, when it has one, is kept in
// `device_t_ns`. Ids are the run store's row ids.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace bosfuse::storage {

enum class RunStatus { kRunning, kComplete, kInterrupted };
std::string_view to_string(RunStatus status);
RunStatus run_status_from_string(std::string_view text);

// Why a sample carries no temperature. A non-ok sample stores no value: a
// burnt-out thermocouple must never look like a temperature.
enum class SampleStatus : int {
  kOk = 0,
  kOpenCircuit = 1,   // burnout / open thermocouple reported by the device
  kOutOfRange = 2,    // reading outside the channel's measurable range
  kTimeout = 3,       // the device did not answer this poll
  kBadReply = 4,      // the device answered with something we cannot decode
  kInvalidValue = 5,  // NaN/inf or a sentinel the device uses for "no value"
  kDisabled = 6,      // the device reports the channel as disabled
};
inline constexpr int kSampleStatusCount = 7;
std::string_view to_string(SampleStatus status);
// The status a stored code stands for. The schema's foreign key keeps codes
// valid, but a damaged or forged file need not honour it: a code no
// SampleStatus has throws StorageError.
SampleStatus sample_status_from_code(std::int64_t code);

struct RunInfo {
  std::int64_t id = 0;
  std::string name;
  std::int64_t started_ns = 0;
  std::optional<std::int64_t> ended_ns;
  std::string config_toml;
  RunStatus status = RunStatus::kRunning;
  // Seconds of the experiment per second of the record: N for a simulation
  // or replay recorded N times faster than it happened, else 1.
  double time_scale = 1;
  // The marker event (kind "marker", this message) that is the experiment's
  // t = 0, e.g. "heater off"; none: the run's first sample.
  std::optional<std::string> origin_event;
};

struct DeviceInfo {
  std::int64_t id = 0;
  std::string name;
  std::string kind;     // modbus-tcp, modbus-rtu, hid, usb, camera
  std::string profile;  // adam-6018, icpdas-m7018, generic, ...
  std::string address;  // 127.0.0.1:502, /dev/ttyUSB0@9600, 09db:0090, ...
};

struct ChannelInfo {
  std::int64_t id = 0;
  std::int64_t device_id = 0;
  std::string name;
  std::string kind;  // thermocouple, cold-junction, voltage, ...
  std::string unit;  // degC, mV, ...
  std::optional<std::string> tc_type;
  std::optional<double> image_x_px;
  std::optional<double> image_y_px;
  // The smallest step of its values, in `unit` (0.1 for a module reporting
  // tenths of a degree): from the experiment file, else from the driver (a
  // register's scale); none where neither says, as in runs before schema 6.
  // It sets the digits a value is printed with (storage/value_digits.h).
  std::optional<double> resolution = std::nullopt;
};

struct Sample {
  std::int64_t channel_id = 0;
  std::int64_t t_ns = 0;
  std::optional<std::int64_t> device_t_ns;
  std::optional<double> value;  // set only when status is kOk
  std::optional<double> raw;    // the undecoded reading, kept for diagnosis
  SampleStatus status = SampleStatus::kOk;
};

// One channel's samples as columns, for readers that want arrays (Python's
// Run.samples): a million rows cost three flat vectors, not a Sample each.
// value is NaN where status is not kOk.
struct SampleColumns {
  std::vector<std::int64_t> t_ns;
  std::vector<double> value;
  std::vector<SampleStatus> status;
};

struct FrameRecord {
  std::int64_t id = 0;
  std::optional<std::int64_t> device_id;
  std::int64_t t_ns = 0;
  std::optional<std::int64_t> device_t_ns;
  std::string path;  // relative to the run folder
  int width_px = 0;
  int height_px = 0;
  int bit_depth = 8;
  bool is_reference = false;
  // Host arrival time, where t_ns is a camera clock mapped to the host
  // (schema 6); unset where t_ns is itself the arrival. Written with the
  // frame; reads leave it unset (a run of schema 5 opened as found has no
  // such column): query frames.arrival_ns for it.
  std::optional<std::int64_t> arrival_ns;
};

struct Event {
  std::int64_t id = 0;
  std::optional<std::int64_t> device_id;
  std::int64_t t_ns = 0;
  // started, stopped, appended, marker, connect, disconnect, reconnect, hotplug, gap, error, skipped,
  // alarm, alarm-cleared (docs/SCHEMA.md)
  std::string kind;
  std::string message;
};

}  // namespace bosfuse::storage
