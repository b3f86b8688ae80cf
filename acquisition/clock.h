#pragma once
// The one host clock every sample and frame is stamped with: nanoseconds
// since the Unix epoch (UTC). Scheduling uses std::chrono::steady_clock
// instead, so a clock step (NTP) never bunches or skips polls.

#include <chrono>
#include <cstdint>

namespace bosfuse::acquisition {

inline std::int64_t utc_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace bosfuse::acquisition
