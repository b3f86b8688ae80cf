#include "acquisition/cameras/watched_folder_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "acquisition/cameras/exif_time.h"
#include "acquisition/cameras/image_file.h"

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

std::int64_t file_time_ns(fs::file_time_type t) {
  const auto system = std::chrono::file_clock::to_sys(t);
  return std::chrono::duration_cast<std::chrono::nanoseconds>(system.time_since_epoch()).count();
}

// OpenCV's PNG decoder prints libpng's complaint (naming no file) each time
// it meets a PNG that ends early: a PNG still being written is left alone
// until it ends with its IEND chunk, the end every PNG has.
bool ends_before_iend(const std::vector<std::uint8_t>& bytes) {
  static constexpr std::uint8_t kIend[] = {'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  MemoryBytes source(bytes);
  return image_format(source) == ImageFormat::kPng &&
         (bytes.size() < sizeof kIend || !std::equal(std::begin(kIend), std::end(kIend), bytes.end() - sizeof kIend));
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

void WatchedFolderSource::connect() {
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
    auto [it, added] = candidates_.try_emplace(path, Candidate{size, modified, now, now, {}});
    Candidate& c = it->second;
    if (!added && (c.size != size || c.modified != modified)) c = {size, modified, now, c.first_seen, {}};
    if (size == 0 || now - c.unchanged_since < options_.settle) continue;
    if (c.failure.empty()) {
      if (auto frame = try_read(path, c)) {
        forget(path);
        return frame;
      }
    }
    if (now - c.first_seen > options_.give_up_after) {
      const std::string failure = c.failure;
      forget(path);
      throw FrameLost(fmt::format("{} never became a complete image ({}); the frame is skipped",
                                  path.filename().string(), failure));
    }
  }
  return std::nullopt;
}

void WatchedFolderSource::forget(const fs::path& path) {
  done_.insert(path);
  candidates_.erase(path);
}

std::optional<CapturedFrame> WatchedFolderSource::try_read(const fs::path& path, Candidate& candidate) {
  std::vector<std::uint8_t> bytes;
  CapturedFrame frame;
  try {
    bytes = read_image_bytes(path);
    std::error_code error;
    if (bytes.empty()) {
      candidate.failure = "not a PNG, JPEG, TIFF, BMP or PNM image";
      return std::nullopt;
    }
    if (bytes.size() != fs::file_size(path, error) || error) {
      candidate.failure = "it changed while it was read";
      return std::nullopt;
    }
    if (ends_before_iend(bytes)) {
      candidate.failure = "the PNG does not end with its IEND chunk";
      return std::nullopt;
    }
    frame.image = decode_image(bytes, path.string());
  } catch (const ImageTooLarge& e) {
    forget(path);  // never a frame, however long it settles
    throw FrameLost(std::string(e.what()) + "; the frame is skipped");
  } catch (const ImageUnreadable& e) {  // perhaps still being written: tried again once it changes
    candidate.failure = e.what();
    return std::nullopt;
  }
  frame.origin = path.filename().string();
  if (const auto exif = exif_capture_time(bytes)) {
    frame.device_t_ns = exif->t_ns;
    frame.t_ns = exif->t_ns + std::llround(options_.camera_clock_offset_s * 1e9);
  } else {
    std::error_code error;
    frame.t_ns = file_time_ns(fs::last_write_time(path, error));
  }
  return frame;
}

}  // namespace bosfuse::acquisition
