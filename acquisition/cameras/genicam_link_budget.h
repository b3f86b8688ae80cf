#pragma once
// A GenicamLinkBudget is whether a camera's link can carry the frames asked
// of it: the requested frame rate × the camera's payload size (bytes a
// frame, PayloadSize) against the throughput the camera reports for its
// link. Cameras say it in different features, and the source reads
// whichever it has (genicam_source.cc): DeviceLinkThroughputLimit (SFNC,
// bytes/s: a cap the camera enforces when DeviceLinkThroughputLimitMode is
// On or absent), DeviceLinkSpeed (bytes/s) and GevLinkSpeed (GigE Vision,
// Mbit/s); the smallest applies. A camera that reports none is not checked
// here (its AcquisitionFrameRate bound still is). The payload excludes
// protocol headers (GigE Vision: about 3 % at 1500-byte packets), so a rate
// just under the limit may still drop frames; one above it cannot work and
// is refused at start, naming the figures.

#include <cstdint>
#include <string>

namespace bosfuse::acquisition {

struct GenicamLinkBudget {
  double frame_rate_hz = 0;        // the rate asked for (0: none asked, nothing to check)
  std::int64_t payload_bytes = 0;  // PayloadSize with every setting applied
  double link_bytes_per_s = 0;     // what the camera reports its link carries (0: it reports none)
  std::string link_feature;        // the feature that said so, e.g. "DeviceLinkThroughputLimit"

  double required_bytes_per_s() const { return frame_rate_hz * static_cast<double>(payload_bytes); }
  // Empty when the frames fit (or there is nothing to check); else why not:
  // "20 frames/s × 2097152 bytes (PayloadSize) = 41.9 MB/s is more than the
  // camera's link carries: DeviceLinkThroughputLimit = 25.0 MB/s (at most 11.9 frames/s)".
  std::string problem() const;
};

// The figure a link feature reports, in bytes/s: GevLinkSpeed is in Mbit/s,
// the SFNC Device* features in bytes/s. 0 for a feature it does not know.
double genicam_link_bytes_per_s(const std::string& feature, double value);

}  // namespace bosfuse::acquisition
