#include "storage/disk_space.h"

#include <sys/statvfs.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "storage/database.h"

namespace bosfuse::storage {

namespace fs = std::filesystem;

std::uint64_t free_bytes(const fs::path& path) {
  fs::path probe = fs::absolute(path);
  std::error_code ec;
  while (!fs::exists(probe, ec) && probe.has_parent_path() && probe != probe.parent_path()) probe = probe.parent_path();
  struct statvfs info {};
  if (::statvfs(probe.c_str(), &info) != 0) {
    throw StorageError("cannot tell the free space of '" + probe.string() + "': " + std::strerror(errno));
  }
  return static_cast<std::uint64_t>(info.f_bavail) * info.f_frsize;
}

std::string bytes_text(std::uint64_t bytes) {
  char text[32];
  const double b = static_cast<double>(bytes);
  constexpr double kKB = 1024, kMB = kKB * 1024, kGB = kMB * 1024;
  if (b >= kGB) {
    std::snprintf(text, sizeof text, "%.1f GB", b / kGB);
  } else if (b >= kMB) {
    std::snprintf(text, sizeof text, "%.0f MB", b / kMB);
  } else {
    std::snprintf(text, sizeof text, "%.0f KB", b / kKB);
  }
  return text;
}

std::string DiskFillWatchOptions::Validate() const {
  if (warn_within.count() < 0) return "warn_within must not be negative";
  if (window.count() <= 0) return "window must be positive";
  return {};
}

DiskFillWatch::DiskFillWatch(DiskFillWatchOptions options) : options_(options) {}

std::optional<DiskFillWatch::Change> DiskFillWatch::add(std::chrono::steady_clock::time_point now,
                                                        std::uint64_t free) {
  readings_.push_back({now, free});
  // The oldest reading kept is the last one at least a window old, so the
  // rate always spans a full window once there is one.
  while (readings_.size() > 2 && now - readings_[1].t >= options_.window) readings_.pop_front();
  if (!short_ && runs_short(1)) {
    short_ = true;
    return Change{true, describe()};
  }
  if (short_ && !runs_short(2)) {
    short_ = false;
    return Change{false, "the disk of the run has room again: " + bytes_text(free) + " free" +
                             (filling_bytes_per_s() > 0 ? ", full in about " + time_left_text() : "")};
  }
  return std::nullopt;
}

double DiskFillWatch::filling_bytes_per_s() const {
  if (readings_.size() < 2) return 0;
  const Reading& first = readings_.front();
  const Reading& last = readings_.back();
  const double seconds = std::chrono::duration<double>(last.t - first.t).count();
  if (seconds <= 0 || last.free >= first.free) return 0;
  return static_cast<double>(first.free - last.free) / seconds;
}

std::optional<std::chrono::seconds> DiskFillWatch::time_to_full() const {
  const double rate = filling_bytes_per_s();
  if (rate <= 0) return std::nullopt;
  return std::chrono::seconds(static_cast<std::int64_t>(std::floor(static_cast<double>(readings_.back().free) / rate)));
}

bool DiskFillWatch::runs_short(double margin) const {
  if (readings_.empty()) return false;
  if (static_cast<double>(readings_.back().free) < margin * static_cast<double>(options_.min_free_bytes)) return true;
  const auto left = time_to_full();
  return left && static_cast<double>(left->count()) < margin * static_cast<double>(options_.warn_within.count());
}

std::string DiskFillWatch::describe() const {
  if (readings_.back().free == 0) return "the disk of the run is full";
  std::string text = "the disk of the run has " + bytes_text(readings_.back().free) + " free";
  if (const double rate = filling_bytes_per_s(); rate > 0) {
    text += " and is filling at " + bytes_text(static_cast<std::uint64_t>(rate)) + "/s: full in about " +
            time_left_text();
  }
  if (readings_.back().free < options_.min_free_bytes) {
    text += " (less than the " + bytes_text(options_.min_free_bytes) + " of [run] min_free_mb)";
  }
  return text;
}

std::string DiskFillWatch::time_left_text() const {
  const auto left = time_to_full();
  if (!left) return "never at this rate";
  char text[32];
  const double s = static_cast<double>(left->count());
  if (s < 120) {
    std::snprintf(text, sizeof text, "%.0f s", s);
  } else if (s < 7200) {
    std::snprintf(text, sizeof text, "%.0f min", s / 60);
  } else {
    std::snprintf(text, sizeof text, "%.1f h", s / 3600);
  }
  return text;
}

}  // namespace bosfuse::storage
