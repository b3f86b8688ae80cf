#include "pipeline/image_sequence.h"

#include <glob.h>

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "acquisition/cameras/exif_time.h"
#include "acquisition/cameras/watched_folder_source.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// The digit run starting at `begin`, without its leading zeros (but at least one digit).
std::string_view digit_run(std::string_view text, std::size_t begin, std::size_t& end) {
  end = begin;
  while (end < text.size() && is_digit(text[end])) ++end;
  std::size_t first = begin;
  while (first + 1 < end && text[first] == '0') ++first;
  return text.substr(first, end - first);
}

std::vector<std::string> expand_glob(const std::string& pattern) {
  glob_t matches{};
  const int status = glob(pattern.c_str(), GLOB_MARK, nullptr, &matches);
  const std::unique_ptr<glob_t, void (*)(glob_t*)> release(&matches, globfree);
  if (status == GLOB_NOMATCH) throw std::runtime_error("--sequence '" + pattern + "': no file matches");
  if (status != 0) throw std::runtime_error("--sequence '" + pattern + "': cannot read the folders it names");
  std::vector<std::string> files;
  for (std::size_t i = 0; i < matches.gl_pathc; ++i) {
    const std::string path = matches.gl_pathv[i];
    if (!path.ends_with('/')) files.push_back(path);  // GLOB_MARK: folders end with '/'
  }
  return files;
}

std::vector<std::string> list_folder(const fs::path& folder) {
  std::vector<std::string> files;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (entry.is_regular_file(error) && acquisition::WatchedFolderSource::is_image_name(entry.path())) {
      files.push_back(entry.path().string());
    }
  }
  if (error) throw std::runtime_error("--sequence " + folder.string() + ": cannot list the folder: " + error.message());
  return files;
}

}  // namespace

bool natural_less(std::string_view a, std::string_view b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      std::size_t a_end = 0, b_end = 0;
      const std::string_view x = digit_run(a, i, a_end), y = digit_run(b, j, b_end);
      // Without leading zeros, the shorter number is the smaller; equal lengths compare as text.
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = a_end;
      j = b_end;
      continue;
    }
    if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
    ++i;
    ++j;
  }
  if (i == a.size() && j == b.size()) return a < b;  // equal but for leading zeros
  return i == a.size();                              // a prefix comes first
}

ImageSequence list_image_sequence(const std::string& pattern_or_folder, const std::vector<std::string>& not_frames) {
  if (pattern_or_folder.empty()) throw std::runtime_error("--sequence: give a glob pattern or a folder");
  std::error_code error;
  const bool folder = fs::is_directory(pattern_or_folder, error);
  std::vector<std::string> files = folder ? list_folder(pattern_or_folder) : expand_glob(pattern_or_folder);
  std::sort(files.begin(), files.end(), natural_less);
  ImageSequence sequence;
  for (auto& file : files) {
    const bool excluded = std::any_of(not_frames.begin(), not_frames.end(), [&](const std::string& other) {
      std::error_code ignored;
      return !other.empty() && fs::equivalent(file, other, ignored);
    });
    (excluded ? sequence.left_out : sequence.frames).push_back(std::move(file));
  }
  if (sequence.frames.empty()) {
    throw std::runtime_error("--sequence " + pattern_or_folder + ": no image " +
                             (folder ? std::string("in the folder") : std::string("matches")) +
                             (sequence.left_out.empty() ? "" : " besides the reference and the mask"));
  }
  return sequence;
}

std::string to_string(TimeSource source) {
  switch (source) {
    case TimeSource::kExif:
      return "exif";
    case TimeSource::kExifWithOffset:
      return "exif_offset";
    case TimeSource::kFileModification:
      return "mtime";
    case TimeSource::kNone:
      break;
  }
  return "none";
}

FrameTime frame_time(const fs::path& path, std::span<const std::uint8_t> bytes) {
  if (const auto exif = acquisition::exif_capture_time(bytes)) {
    return {exif->t_ns, exif->had_zone_offset ? TimeSource::kExifWithOffset : TimeSource::kExif};
  }
  std::error_code error;
  const auto modified = fs::last_write_time(path, error);
  if (error) return {};
  const auto system = std::chrono::file_clock::to_sys(modified);
  return {std::chrono::duration_cast<std::chrono::nanoseconds>(system.time_since_epoch()).count(),
          TimeSource::kFileModification};
}

}  // namespace bosfuse::pipeline
