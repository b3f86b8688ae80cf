#pragma once
// The words every device speaks, whatever its protocol: a ChannelReading is
// one channel's value with its status (storage::SampleStatus, the status a
// sample is stored with), and a DeviceError is a poll that failed. Drivers
// (Modbus, USB-HID, raw USB), cameras and the simulator's devices all
// include this header and nothing of each other's.

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "storage/records.h"

namespace bosfuse::acquisition {

// One channel's reading: a value only when its status is ok; `raw` is what
// the device sent (a register code, an ADC count), kept for the record.
struct ChannelReading {
  std::optional<double> value;  // only when status is ok
  double raw = 0;
  storage::SampleStatus status = storage::SampleStatus::kOk;
};

// Whether `raw` is one of the codes a device sends in place of a value
// (an open input's -9999, a module's out-of-range code).
inline bool is_one_of_codes(const std::vector<double>& codes, double raw) {
  return std::find(codes.begin(), codes.end(), raw) != codes.end();
}

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

}  // namespace bosfuse::acquisition
