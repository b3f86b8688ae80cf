#pragma once
// ExperimentConfig is what an experiment TOML file describes (documented in
// docs/CONFIG.md, example in examples/): the run's name and the devices to
// log, each with its transport, profile, poll period and channels, and where
// each thermocouple sits in the camera image. Parsing checks everything a
// user can get wrong and names the key and line; the verbatim text is kept
// so a run stores exactly the configuration it was recorded with.

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/alarm_limits.h"
#include "acquisition/emf_conversion.h"
#include "acquisition/cameras/frame_recorder.h"
#include "acquisition/cameras/genicam_options.h"
#include "acquisition/drivers/hid_device.h"
#include "acquisition/drivers/modbus_device.h"
#include "acquisition/config/toml_reader.h"
#include "acquisition/drivers/usb_tc32_device.h"
#include "acquisition/cameras/watched_folder_source.h"
#include "storage/records.h"

namespace bosfuse::acquisition {

// A device is polled at most once a millisecond (poll_period_s) and at
// least once a year (TomlReader::kLongestSeconds).
constexpr double kShortestPollPeriodS = 0.001;

// [run] time_scale, experiment seconds per recorded second: from a record
// 1000 times slower than the experiment to one a million times faster. A
// millionfold run still times its experiment in microseconds of the
// record; beyond either end a scale is a typo, not a simulation.
constexpr double kSmallestTimeScale = 1e-3;
constexpr double kLargestTimeScale = 1e6;
// camera_clock_offset_s: a camera whose clock was never set (2000-01-01) is
// decades off. A century is more than any real offset and keeps a frame's
// time far inside what int64 nanoseconds hold (±292 years).
constexpr double kLargestClockOffsetS = 100 * 365.25 * 86400;

struct ModbusDeviceConfig {
  std::string name;
  std::string profile;
  ModbusEndpoint endpoint;
  std::string host_key;  // where `host` is in the file ("exp.toml:7: devices[0].host"), for check_hosts_resolve
  std::chrono::nanoseconds poll_period = std::chrono::seconds(1);
  std::optional<std::int64_t> poll_count;  // stop polling after this many polls
  std::chrono::milliseconds timeout{500};
  std::vector<ModbusChannel> channels;
  std::vector<std::optional<EmfInput>> emf_inputs;  // one per channel: set when it delivers millivolts
};

struct HidDeviceConfig {
  std::string name;
  std::string profile;  // mcc-usb-tc, temper or generic-hid
  HidMatch match;
  HidProtocol protocol;
  std::vector<std::optional<EmfInput>> emf_inputs;  // one per channel: set when it delivers millivolts
  std::chrono::nanoseconds poll_period = std::chrono::seconds(1);
  std::optional<std::int64_t> poll_count;  // stop polling after this many polls
  std::chrono::milliseconds timeout{500};
};

struct UsbDeviceConfig {
  std::string name;
  std::string profile;  // usb-tc-32
  std::optional<std::string> serial;
  std::vector<UsbTc32Channel> channels;
  std::chrono::nanoseconds poll_period = std::chrono::seconds(1);
  std::optional<std::int64_t> poll_count;  // stop polling after this many polls
  std::chrono::milliseconds timeout{500};
};

// A camera: a VideoCapture device/file/URL read at an interval, or a folder
// a tethered camera writes into.
struct CameraConfig {
  std::string name;
  std::string source;         // "video", "folder", "replay" or "genicam"
  std::string target;         // video: camera index, file or URL; replay: the recorded run's folder
  std::string replay_camera;  // replay: the camera's name in the recorded run
  std::string run_key;        // replay: where `run` is in the file, for check_replayed_runs
  double replay_speed = 1;
  WatchedFolderOptions folder;
  GenicamOptions genicam;
  std::string genicam_key;  // genicam: where `device` is, for check_genicam_cameras
  FrameRecorderOptions recorder;
  std::filesystem::path reference_flag;  // relative paths are relative to the run folder
};

// [agreement]: how far apart the thermocouple's and the BOS probe's curves
// may be and still agree (fitting/agreement.h; docs/CONFIG.md).
struct AgreementMargins {
  double margin_c = 1.0;            // T0 and T_amb, °C
  double margin_k_relative = 0.05;  // k, as a fraction of the two k's mean
};

struct ExperimentConfig {
  std::string run_name;
  std::string description;
  double time_scale = 1;                    // [run] time_scale: experiment seconds per recorded second
  std::optional<std::string> origin_event;  // [run] origin: the marker event that is t = 0
  // [run] min_free_mb: the free space (MB of 2^20 bytes) the run's disk
  // must have for logging to start, and below which the logger warns; 0:
  // neither. `min_free_key` says where it is set ("exp.toml:3:
  // run.min_free_mb"), or that it is the default.
  std::int64_t min_free_mb = 100;
  std::string min_free_key;
  std::vector<ModbusDeviceConfig> modbus_devices;
  std::vector<HidDeviceConfig> hid_devices;
  std::vector<UsbDeviceConfig> usb_devices;
  std::vector<CameraConfig> cameras;
  AgreementMargins agreement;
  std::string source_text;  // the file as written

  std::size_t device_count() const {
    return modbus_devices.size() + hid_devices.size() + usb_devices.size() + cameras.size();
  }
};

ExperimentConfig parse_experiment(std::string_view text, const std::string& source_name);
// Channel names are unique across the whole experiment file, compared in
// this form: letter case folded, runs of white space one space, none at
// either end. Exports, reports and the live page name a column or curve by
// the channel alone, and "T0", "t0" and "T0 " read as one thermocouple there.
std::string channel_name_key(std::string_view name);
// The run a logger records with this experiment file, started at `started_ns`.
storage::RunInfo run_info(const ExperimentConfig& config, std::int64_t started_ns);
ExperimentConfig load_experiment(const std::filesystem::path& path);  // throws ConfigError

// A channel's alarm limits with what a reader needs to show them.
struct ChannelAlarmLimits {
  std::string device;
  std::string channel;
  std::string unit;  // as recorded: °C for a millivolt channel with emf_type
  AlarmLimits limits;
};

// Every channel of `config` that has alarm limits: Modbus devices, then HID,
// then USB, each in file order. The live page reads them from a run's
// stored experiment file (parse_experiment(run.config_toml, ...)).
std::vector<ChannelAlarmLimits> alarm_limits(const ExperimentConfig& config);

// Each channel's time_constant_s where the file states one, keyed by
// channel_name_key(name): how processing finds a thermocouple's lag.
std::map<std::string, double> channel_time_constants(const ExperimentConfig& config);

// Throws ConfigError, naming the key and line, for a Modbus TCP host name
// that does not resolve: at the start of logging a name that does not
// resolve is a typo far more often than a passing DNS outage, and refusing
// it stops the run before it starts instead of retrying a device that can
// never be reached. Parsing itself never resolves names, so a stored run's
// experiment file reads the same anywhere, offline too.
void check_hosts_resolve(const ExperimentConfig& config);

// Throws ConfigError, naming the camera's `run` key and line, for a replay
// camera whose recorded run cannot be read or has no such camera. Like
// check_hosts_resolve it is for the start of logging, so that such a
// camera stops the start before a run is created, not an empty run after.
void check_replayed_runs(const ExperimentConfig& config);

// Throws ConfigError, naming the camera's key and line, for a GenICam
// camera that refuses one of its settings (a value outside its feature's
// range, named with the range; a feature it lacks; a frame rate it cannot
// deliver). A camera that cannot be reached is not refused: it is logged
// as a warning through `warn` and the recorder keeps trying to reach it,
// so a camera switched on late does not stop the thermocouples.
void check_genicam_cameras(const ExperimentConfig& config, const std::function<void(const std::string&)>& warn);

// Throws ConfigError, naming `[run] min_free_mb` and its line, when the file
// system that is to hold `run_dir` (or would, for a folder not made yet)
// has less free space than min_free_mb: a run begun on a nearly full disk
// loses its records within minutes, and it is better refused before it
// starts.
void check_free_space(const ExperimentConfig& config, const std::filesystem::path& run_dir);

}  // namespace bosfuse::acquisition
