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
// back as invalid-value. The devices are polled at the recorded poll periods
// (the mean interval between samples, outages left out) and frames are
// served at their times divided by the speed-up; once recorded, every
// sample and frame is stamped with its recorded time, scaled
// (stamp_from_recording), so the replayed run keeps the recording's timing
// between devices exactly, whatever the host's load did to the polls.

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
ModbusSimServerOptions replay_module_options(const ReplayDevice& device, int port);

// The experiment file of a replay at `speed` with the devices' modules on
// `ports` (same order as run.devices). It keeps what makes the replay the
// same experiment: what processing reads of the recorded run's file (its
// [geometry], [alignment] and [agreement], each channel's time_constant_s),
// its declared origin, and its time scale times `speed` (a run recorded at
// 16× replayed at 10× is 160 experiment seconds per recorded second).
std::string replay_experiment_toml(const RecordedRun& run, const std::vector<int>& ports, double speed);

// What stamp_from_recording did: how many samples and frames it stamped,
// how far the largest of them moved (wall seconds: how late the logger had
// polled or stored it), and what it could not match, in words.
struct RecordingTimes {
  std::size_t samples = 0;
  std::size_t frames = 0;
  double largest_move_s = 0;
  std::vector<std::string> problems;
};

// Sets the times of what a replay of `recorded` at `speed` recorded in the
// run at `replayed_dir` (created at `started_ns`, from which the replay's
// markers count too) to the recording's: started_ns + (t − the recorded
// run's start) / speed. A channel's samples are matched to the recorded ones
// in order (the modules serve sample k at poll k); a failed poll (timeout,
// bad-reply), which drew no sample, keeps its poll's time. A channel with
// more served samples than recorded keeps its poll times, and says so. A
// frame's recorded time is its device_t_ns (the replayed camera's own
// time). One transaction: all or none.
RecordingTimes stamp_from_recording(const RecordedRun& recorded, const std::filesystem::path& replayed_dir,
                                    std::int64_t started_ns, double speed);

}  // namespace bosfuse::sim
