#pragma once
// An image sequence without a run: the frames a user names with a glob
// pattern or a folder (`bosfuse evaluate --sequence 'frames/*.tif'`), in
// natural order, each with the time it was taken. PIV users batch-process a
// folder of images this way; a run's frames come from its store instead.
//
// Listing, timing and evaluating (sequence_evaluation.h) are separate steps
// so that a parallel driver can list once, hand frame indices to workers
// and write the results in order.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace bosfuse::pipeline {

// Natural order: runs of digits compare by their value, so frame_2 comes
// before frame_10; everything else compares byte by byte. Names equal but
// for leading zeros (frame_02, frame_2) are ordered by their bytes, so the
// order is total and the same on every machine.
bool natural_less(std::string_view a, std::string_view b);

struct ImageSequence {
  std::vector<std::string> frames;    // paths as the pattern or folder gave them, in natural order
  std::vector<std::string> left_out;  // matches that are not frames (the reference, the mask)
};

// `pattern_or_folder`: a folder (its image files: .png, .tif, .jpg ...; not
// its subfolders) or a glob(3) pattern, expanded here so it works quoted
// (a shell's expansion would hit its argument limit on a large folder).
// Folders a pattern matches are skipped. Files equivalent to one of
// `not_frames` (the reference, the mask) are left out and listed as such.
// Throws std::runtime_error when nothing is left.
ImageSequence list_image_sequence(const std::string& pattern_or_folder, const std::vector<std::string>& not_frames);

// Where a frame's time came from.
enum class TimeSource {
  kExif,              // EXIF DateTimeOriginal (+ SubSecTimeOriginal), a camera's clock read as UTC
  kExifWithOffset,    // the same, with OffsetTimeOriginal applied: UTC
  kFileModification,  // the file's modification time (UTC)
  kNone,              // neither: the file is gone
};
std::string to_string(TimeSource source);  // "exif", "exif_offset", "mtime", "none"

struct FrameTime {
  std::optional<std::int64_t> t_ns;  // since the Unix epoch
  TimeSource source = TimeSource::kNone;
};

// The capture time in `bytes` (the file's content) when its EXIF data has
// one, else `path`'s modification time.
FrameTime frame_time(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace bosfuse::pipeline
