#include "acquisition/watched_folder_source.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <thread>

#include "acquisition/exif_time.h"
#include "acquisition/image_file.h"

namespace bosfuse::acquisition {
namespace fs = std::filesystem;
namespace {

using Steady = std::chrono::steady_clock;
constexpr auto kRescanInterval = std::chrono::milliseconds(50);

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool ends_with(const std::vector<std::uint8_t>& bytes, std::span<const std::uint8_t> tail) {
  return bytes.size() >= tail.size() && std::equal(tail.begin(), tail.end(), bytes.end() - tail.size());
}

// A format's own end marker, where it has one: decoders are lenient with a
// truncated JPEG (they fill the rest grey), so a file missing its end is
// still being written.
bool has_end_marker(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  const std::string ext = lower_extension(path);
  static constexpr std::array<std::uint8_t, 2> kJpegEnd = {0xFF, 0xD9};
  static constexpr std::array<std::uint8_t, 8> kPngEnd = {'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  if (ext == ".jpg" || ext == ".jpeg") return ends_with(bytes, kJpegEnd);
  if (ext == ".png") return ends_with(bytes, kPngEnd);
  return true;
}

std::int64_t file_time_ns(fs::file_time_type t) {
  const auto system = std::chrono::file_clock::to_sys(t);
  return std::chrono::duration_cast<std::chrono::nanoseconds>(system.time_since_epoch()).count();
}

bool is_temporary_name(const fs::path& path) {
  const std::string name = path.filename().string();
  const std::string ext = lower_extension(path);
  return name.empty() || name[0] == '.' || name.back() == '~' || ext == ".part" || ext == ".tmp" ||
         ext == ".crdownload";
}

}  // namespace

bool WatchedFolderSource::is_image_name(const fs::path& path) {
  static const std::set<std::string> kImageExtensions = {".jpg", ".jpeg", ".png", ".tif", ".tiff",
                                                         ".bmp", ".pgm",  ".ppm", ".pnm"};
  return !is_temporary_name(path) && kImageExtensions.count(lower_extension(path)) > 0;
}

WatchedFolderSource::WatchedFolderSource(WatchedFolderOptions options) : options_(std::move(options)) {}

std::string WatchedFolderSource::describe() const { return "folder " + options_.folder.string(); }

void WatchedFolderSource::open() {
  std::error_code error;
  if (!fs::is_directory(options_.folder, error)) throw DeviceError(describe() + " does not exist");
  for (const auto& entry : fs::directory_iterator(options_.folder, error)) done_.insert(entry.path());
  if (error) throw DeviceError("cannot list " + describe() + ": " + error.message());
}

std::optional<CapturedFrame> WatchedFolderSource::next(std::chrono::milliseconds wait) {
  const auto deadline = Steady::now() + wait;
  for (;;) {
    if (auto frame = take_ready_file()) return frame;
    const auto now = Steady::now();
    if (now >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::min<Steady::duration>(kRescanInterval, deadline - now));
  }
}

std::optional<CapturedFrame> WatchedFolderSource::take_ready_file() {
  std::error_code error;
  std::vector<fs::path> names;
  for (const auto& entry : fs::directory_iterator(options_.folder, error)) {
    if (entry.is_regular_file(error) && is_image_name(entry.path()) && !done_.count(entry.path())) {
      names.push_back(entry.path());
    }
  }
  if (error) throw DeviceError("cannot list " + describe() + ": " + error.message());
  std::sort(names.begin(), names.end());
  const auto now = Steady::now();
  for (const fs::path& path : names) {
    const auto size = fs::file_size(path, error);
    const auto modified = fs::last_write_time(path, error);
    if (error) continue;  // renamed or removed meanwhile
    auto [it, added] = candidates_.try_emplace(path, Candidate{size, modified, now, now});
    Candidate& c = it->second;
    if (!added && (c.size != size || c.modified != modified)) c = {size, modified, now, c.first_seen};
    if (size == 0 || now - c.unchanged_since < options_.settle) continue;
    if (auto frame = try_read(path)) {
      done_.insert(path);
      candidates_.erase(path);
      return frame;
    }
    if (now - c.first_seen > options_.give_up_after) {
      spdlog::warn("{}: {} never became a complete image; skipped", describe(), path.filename().string());
      done_.insert(path);
      candidates_.erase(path);
    }
  }
  return std::nullopt;
}

std::optional<CapturedFrame> WatchedFolderSource::try_read(const fs::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  std::error_code error;
  if (bytes.size() != fs::file_size(path, error) || error || !has_end_marker(path, bytes)) return std::nullopt;
  CapturedFrame frame;
  try {
    frame.image = decode_image(bytes, path.filename().string());
  } catch (const ImageTooLarge& e) {
    spdlog::warn("{}: {}; skipped", describe(), e.what());
    done_.insert(path);  // never a frame, however long it settles
    return std::nullopt;
  }
  if (frame.image.empty()) return std::nullopt;
  frame.origin = path.filename().string();
  if (const auto exif = exif_capture_time(bytes)) {
    frame.device_t_ns = exif->t_ns;
    frame.t_ns = exif->t_ns + std::llround(options_.camera_clock_offset_s * 1e9);
  } else {
    frame.t_ns = file_time_ns(fs::last_write_time(path, error));
  }
  return frame;
}

}  // namespace bosfuse::acquisition
