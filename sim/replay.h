#pragma once
// Replay of a recorded run through the real device paths: each thermocouple
// device of the run becomes a simulated Modbus module on loopback serving its
// recorded samples in order (one per poll, whatever the timing), each camera
// a replayed frame source, and an experiment file describes them so the
// logger records a new run exactly as it would a live one. Replays are how
// tests reproduce a real experiment.
//
// What a replay keeps: every sample's value, in order, per channel; the
// statuses open-circuit and out-of-range (served as their codes); every
// frame's pixels and reference flag, with its original time as the camera's
// own time. Other statuses (timeout, bad-reply, invalid-value, disabled) come
// back as invalid-value, and timing follows the recorded poll periods (the
// mean interval between samples, outages left out) and frame times divided
// by the speed-up.

#include <filesystem>
#include <string>
#include <vector>

#include "sim/modbus_server.h"
#include "storage/records.h"

namespace bosfuse::sim {

struct ReplayDevice {
  std::string name;
  std::vector<storage::ChannelInfo> channels;
  std::vector<std::vector<storage::Sample>> samples;         // per channel, in time order
  std::chrono::nanoseconds period{std::chrono::seconds(1)};  // mean recorded interval, outages left out
};

struct RecordedRun {
  std::filesystem::path dir;
  storage::RunInfo run;
  std::vector<ReplayDevice> devices;
  std::vector<std::string> cameras;   // cameras with at least one frame whose file exists
  std::vector<std::string> problems;  // what is missing or damaged, in words
  std::int64_t last_offset_ns = 0;    // the latest sample or frame, from the run's start
};

// Reads what a run holds and says what is unsound: a run never closed, frame
// files missing, devices without samples. Throws if it is no run at all.
RecordedRun inspect_recorded_run(const std::filesystem::path& dir);

// The module that serves `device`'s samples: float32 holding registers, two
// per channel, -9999 for open-circuit, -8888 for out-of-range, NaN otherwise.
ModbusSimServer::Options replay_module_options(const ReplayDevice& device, int port);

// The experiment file of a replay at `speed` with the devices' modules on
// `ports` (same order as run.devices). It keeps what makes the replay the
// same experiment: what processing reads of the recorded run's file (its
// [geometry], [alignment] and [agreement], each channel's time_constant_s),
// its declared origin, and its time scale times `speed` (a run recorded at
// 16× replayed at 10× is 160 experiment seconds per recorded second).
std::string replay_experiment_toml(const RecordedRun& run, const std::vector<int>& ports, double speed);

}  // namespace bosfuse::sim
