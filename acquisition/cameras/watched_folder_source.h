#pragma once
// WatchedFolderSource turns image files appearing in a folder into frames,
// for a DSLR shooting tethered into that folder. Each new file becomes one
// frame, in name order, timed from its EXIF capture time plus the configured
// camera-clock offset (camera clock + offset = host UTC), else from the
// file's modification time. A file still being written is never read half-
// finished: it must keep the same size and time for `settle` and decode
// completely (acquisition/cameras/image_file.h: a truncated JPEG, PNG or TIFF is
// refused by its own library) before it is taken; one that does not is
// tried again each time it changes, and after `give_up_after` it is a lost
// frame (FrameLost, with the reason). A file too large for the image limits
// is a lost frame at once. Temporary names (hidden files, *.part, *.tmp, *~)
// are ignored until renamed. Files already in the folder when it is opened
// are left alone.

#include <filesystem>
#include <map>
#include <set>
#include <vector>

#include "acquisition/cameras/frame_source.h"

namespace bosfuse::acquisition {

struct WatchedFolderOptions {
  std::filesystem::path folder;
  std::chrono::milliseconds settle{500};
  double camera_clock_offset_s = 0;         // added to EXIF times to get host UTC
  std::chrono::milliseconds give_up_after{120'000};  // a file that never decodes is then a lost frame
};

class WatchedFolderSource : public FrameSource {
 public:
  explicit WatchedFolderSource(WatchedFolderOptions options);

  std::string kind() const override { return "folder"; }
  std::string describe() const override;
  void connect() override;
  void disconnect() override {}
  std::optional<CapturedFrame> next(std::chrono::milliseconds wait) override;

  static bool is_image_name(const std::filesystem::path& path);

 private:
  struct Candidate {
    std::uintmax_t size = 0;
    std::filesystem::file_time_type modified;
    std::chrono::steady_clock::time_point unchanged_since;
    std::chrono::steady_clock::time_point first_seen;
    std::string failure;  // why it did not decode at this size and time; empty: not tried since it changed
  };

  std::optional<CapturedFrame> take_ready_file();
  // The frame, or nullopt with `candidate.failure` said; throws FrameLost
  // for a file that never can be one.
  std::optional<CapturedFrame> try_read(const std::filesystem::path& path, Candidate& candidate);
  void forget(const std::filesystem::path& path);  // taken or given up: never looked at again

  WatchedFolderOptions options_;
  std::set<std::filesystem::path> done_;  // taken, or present at open, or given up
  std::map<std::filesystem::path, Candidate> candidates_;
};

}  // namespace bosfuse::acquisition
