#pragma once
// A ThermocoupleSource is one device that yields readings for a fixed list
// of channels: a Modbus module, a USB-HID thermometer, a raw USB logger, or a
// virtual or replayed one. The DevicePoller drives it on a schedule and owns
// timing, retries and events; a source only knows its protocol. Sources are
// used from one thread at a time.

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/modbus_channel.h"
#include "storage/records.h"

namespace bosfuse::acquisition {

// A failed poll. By default a transport failure (no answer, connection
// lost, device gone): the poller marks the poll's samples timed out and
// reconnects. A device that answered with something other than readings (a
// Modbus exception, a malformed frame) says so with kBadReply and, where
// there is one, the code it sent in `raw`; the samples carry both. Either
// way the poller records one event per outage and backs off while it lasts.
class DeviceError : public std::runtime_error {
 public:
  explicit DeviceError(const std::string& what, storage::SampleStatus status = storage::SampleStatus::kTimeout,
                       std::optional<double> raw = std::nullopt)
      : std::runtime_error(what), status_(status), raw_(raw) {}

  storage::SampleStatus status() const { return status_; }
  std::optional<double> raw() const { return raw_; }
  // A reply arrived, so the link itself is fine and need not be reopened.
  bool link_alive() const { return status_ == storage::SampleStatus::kBadReply; }

 private:
  storage::SampleStatus status_;
  std::optional<double> raw_;
};

class ThermocoupleSource {
 public:
  virtual ~ThermocoupleSource() = default;

  virtual storage::DeviceInfo device_info() const = 0;
  virtual std::vector<storage::ChannelInfo> channel_infos() const = 0;

  virtual void connect() = 0;     // throws DeviceError
  virtual void disconnect() = 0;  // never throws
  // One reading per channel, in channel_infos() order. Throws DeviceError
  // when the device cannot be read at all; a channel-level problem (burnout,
  // bad value) is a reading status instead.
  virtual std::vector<ChannelReading> read() = 0;

  // What the device noticed on its own since the last call, such as a USB
  // unplug or replug; the poller records each as a "hotplug" event.
  // Thread-safe: a source may gather notices on a thread of its own.
  virtual std::vector<std::string> take_notices() { return {}; }
};

}  // namespace bosfuse::acquisition
