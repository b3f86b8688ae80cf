#pragma once
// The demo's recording: the demo's scene (sim/demo_setup.h) logged through
// the real device paths into a new run, its thermocouples served by a
// simulated ADAM-6018 on loopback and its frames by the virtual camera (or,
// with DemoOptions::camera "genicam", by a simulated GigE Vision camera on
// 127.0.0.1 read through the GenICam source), a few minutes of cooling in a
// few seconds. The run's declared origin, the
// "heater off" marker, is the scene's t = 0. What the command adds (its
// progress display, its live page, Ctrl-C) comes in through the hooks.

#include <atomic>
#include <filesystem>
#include <functional>
#include <string>

#include "acquisition/logger.h"
#include "sim/demo_setup.h"

namespace bosfuse::sim {

struct DemoRecordingHooks {
  std::function<void(const std::string& line)> note;  // the logger's progress and the demo's own lines
  // Called once the run's store and logger exist, before recording starts
  // (a live page of the run starts here); none: nothing.
  std::function<void()> run_created;
  const std::atomic<bool>* stop = nullptr;  // set: the recording ends early; none: it runs its time
};

// Records options.experiment_s of the scene at options.speed into the new run
// `run_dir`. Throws std::invalid_argument on invalid options.
acquisition::Logger::Summary record_demo(const DemoOptions& options, const DemoSetup& setup,
                                         const std::filesystem::path& run_dir, const DemoRecordingHooks& hooks);

}  // namespace bosfuse::sim
