#pragma once
// WatchedFolderSource turns image files appearing in a folder into frames,
// for a DSLR shooting tethered into that folder. Each new file becomes one
// frame, in name order, timed from its EXIF capture time plus the configured
// camera-clock offset (camera clock + offset = host UTC), else from the
// file's modification time. A file still being written is never read half-
// finished: it must keep the same size and time for `settle` and decode
// completely (a JPEG must end with its end-of-image marker) before it is
// taken; temporary names (hidden files, *.part, *.tmp, *~) are ignored until
// renamed. Files already in the folder when it is opened are left alone.

#include <filesystem>
#include <map>
#include <set>
#include <vector>

#include "acquisition/frame_source.h"

namespace bosfuse::acquisition {

struct WatchedFolderOptions {
  std::filesystem::path folder;
  std::chrono::milliseconds settle{500};
  double camera_clock_offset_s = 0;         // added to EXIF times to get host UTC
  std::chrono::seconds give_up_after{120};  // a file that never decodes is skipped (with a warning)
};

class WatchedFolderSource : public FrameSource {
 public:
  explicit WatchedFolderSource(WatchedFolderOptions options);

  std::string kind() const override { return "folder"; }
  std::string describe() const override;
  void open() override;
  void close() override {}
  std::optional<CapturedFrame> next(std::chrono::milliseconds wait) override;

  static bool is_image_name(const std::filesystem::path& path);

 private:
  struct Candidate {
    std::uintmax_t size = 0;
    std::filesystem::file_time_type modified;
    std::chrono::steady_clock::time_point unchanged_since;
    std::chrono::steady_clock::time_point first_seen;
  };

  std::optional<CapturedFrame> take_ready_file();
  std::optional<CapturedFrame> try_read(const std::filesystem::path& path);

  WatchedFolderOptions options_;
  std::set<std::filesystem::path> done_;  // taken, or present at open, or given up
  std::map<std::filesystem::path, Candidate> candidates_;
};

}  // namespace bosfuse::acquisition
