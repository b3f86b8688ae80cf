#pragma once
// A ThermocoupleSource is one device that yields readings for a fixed list
// of channels: a Modbus module, a USB-HID thermometer, a raw USB logger, or a
// virtual or replayed one. The DevicePoller drives it on a schedule and owns
// timing, retries and events; a source only knows its protocol. Sources are
// used from one thread at a time.

#include <string>
#include <vector>

#include "acquisition/device_reading.h"
#include "storage/records.h"

namespace bosfuse::acquisition {

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
