#include "sim/replay.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "storage/run_store.h"

namespace bosfuse::sim {
namespace fs = std::filesystem;
namespace {

using storage::SampleStatus;

constexpr double kOpenCircuitCode = -9999;
constexpr double kOutOfRangeCode = -8888;

double served_value(const storage::Sample& sample) {
  switch (sample.status) {
    case SampleStatus::kOk:
      return sample.value.value_or(std::nan(""));
    case SampleStatus::kOpenCircuit:
      return kOpenCircuitCode;
    case SampleStatus::kOutOfRange:
      return kOutOfRangeCode;
    default:
      return std::nan("");
  }
}

std::chrono::nanoseconds median_interval(const std::vector<storage::Sample>& samples) {
  std::vector<std::int64_t> gaps;
  for (std::size_t i = 1; i < samples.size(); ++i) gaps.push_back(samples[i].t_ns - samples[i - 1].t_ns);
  if (gaps.empty()) return std::chrono::seconds(1);
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
  return std::chrono::nanoseconds(std::max<std::int64_t>(gaps[gaps.size() / 2], 1'000'000));
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) out += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
  return out + "\"";
}

std::string number(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

void inspect_frames(const storage::RunStore& store, RecordedRun& recorded) {
  for (const auto& device : store.devices()) {
    if (device.kind != "camera") continue;
    std::size_t present = 0, missing = 0;
    for (const auto& frame : store.frames()) {
      if (frame.device_id != device.id) continue;
      (fs::exists(recorded.dir / frame.path) ? present : missing) += 1;
      recorded.last_offset_ns = std::max(recorded.last_offset_ns, frame.t_ns - recorded.run.started_ns);
    }
    if (missing > 0) {
      recorded.problems.push_back("camera " + device.name + ": " + std::to_string(missing) + " of " +
                                  std::to_string(missing + present) + " frame files are missing; they are skipped");
    }
    if (present > 0) recorded.cameras.push_back(device.name);
  }
}

}  // namespace

RecordedRun inspect_recorded_run(const fs::path& dir) {
  const storage::RunStore store = storage::RunStore::open(dir);
  RecordedRun recorded{dir, store.run(), {}, {}, {}, 0};
  if (recorded.run.status == storage::RunStatus::kRunning) {
    recorded.problems.push_back("the run is still being recorded; replaying what it has committed so far");
  } else if (recorded.run.status == storage::RunStatus::kInterrupted) {
    recorded.problems.push_back("the run was interrupted (see its events); replaying what it committed");
  }
  const auto channels = store.channels();
  for (const auto& device : store.devices()) {
    if (device.kind == "camera") continue;
    ReplayDevice replay{device.name, {}, {}, {}};
    for (const auto& channel : channels) {
      if (channel.device_id != device.id) continue;
      replay.channels.push_back(channel);
      replay.samples.push_back(store.read_samples(channel.id));
      if (!replay.samples.back().empty()) {
        recorded.last_offset_ns =
            std::max(recorded.last_offset_ns, replay.samples.back().back().t_ns - recorded.run.started_ns);
      }
    }
    if (replay.channels.empty() || replay.samples.front().empty()) {
      recorded.problems.push_back("device " + device.name + " has no samples; not replayed");
      continue;
    }
    replay.period = median_interval(replay.samples.front());
    recorded.devices.push_back(std::move(replay));
  }
  inspect_frames(store, recorded);
  return recorded;
}

ModbusSimServer::Options replay_module_options(const ReplayDevice& device, int port) {
  ModbusSimServer::Options options;
  options.endpoint.host = "127.0.0.1";
  options.endpoint.port = port;
  for (std::size_t i = 0; i < device.channels.size(); ++i) {
    acquisition::ModbusChannel map;
    map.name = device.channels[i].name;
    map.function = acquisition::RegisterKind::kHolding;
    map.address = static_cast<int>(2 * i);
    map.type = acquisition::DataType::kFloat32;
    map.open_circuit_codes = {kOpenCircuitCode};
    map.out_of_range_codes = {kOutOfRangeCode};
    options.channels.push_back(map);
  }
  // Served by draw, not by time: poll k of the new run gets sample k.
  options.temperature_c = [samples = device.samples](int channel, double, std::uint64_t draw) {
    const auto& series = samples[static_cast<std::size_t>(channel)];
    return draw < series.size() ? served_value(series[draw]) : std::nan("");
  };
  return options;
}

std::string replay_experiment_toml(const RecordedRun& run, const std::vector<int>& ports, double speed) {
  std::ostringstream toml;
  toml << "# Replay of " << run.dir.string() << " at " << number(speed) << "x, written by bosfuse replay.\n"
       << "[run]\nname = " << quoted("replay of " + run.run.name) << "\n";
  for (std::size_t d = 0; d < run.devices.size(); ++d) {
    const ReplayDevice& device = run.devices[d];
    const double period_s = std::chrono::duration<double>(device.period).count() / speed;
    toml << "\n[[devices]]\nname = " << quoted(device.name) << "\nprofile = \"generic\"\ntransport = \"tcp\"\n"
         << "host = \"127.0.0.1\"\nport = " << ports.at(d) << "\npoll_period_s = " << number(std::max(period_s, 0.001))
         << "\ntimeout_s = 1.0\npoll_count = " << device.samples.front().size() << "\n";
    for (std::size_t c = 0; c < device.channels.size(); ++c) {
      const storage::ChannelInfo& channel = device.channels[c];
      toml << "  [[devices.channels]]\n  name = " << quoted(channel.name) << "\n  kind = " << quoted(channel.kind)
           << "\n  unit = " << quoted(channel.unit) << "\n  register = \"holding\"\n  address = " << 2 * c
           << "\n  type = \"float32\"\n  open_circuit_codes = [" << number(kOpenCircuitCode)
           << "]\n  out_of_range_codes = [" << number(kOutOfRangeCode) << "]\n";
      if (channel.tc_type) toml << "  tc_type = " << quoted(*channel.tc_type) << "\n";
      if (channel.image_x_px && channel.image_y_px) {
        toml << "  position_px = [" << number(*channel.image_x_px) << ", " << number(*channel.image_y_px) << "]\n";
      }
    }
  }
  for (const std::string& camera : run.cameras) {
    toml << "\n[[cameras]]\nname = " << quoted(camera) << "\nsource = \"replay\"\nrun = " << quoted(run.dir.string())
         << "\ncamera = " << quoted(camera) << "\nspeed = " << number(speed) << "\nreference_frames = 0\n";
  }
  return toml.str();
}

}  // namespace bosfuse::sim
