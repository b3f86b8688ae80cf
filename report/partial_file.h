#pragma once
// A file written under a temporary name beside its destination and renamed
// into place by commit(); removed when the owner goes without a commit. An
// export that fails half-way (a broken input, a full disk, an exception)
// thereby leaves the destination as it was, never a half-written file.

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace bosfuse::report {

class PartialFile {
 public:
  explicit PartialFile(const std::filesystem::path& destination)
      : destination_(destination),
        temporary_(destination.parent_path() /
                   fmt::format(".{}.partial-{}", destination.filename().string(), static_cast<long>(getpid()))) {}
  ~PartialFile() {
    std::error_code ignored;
    if (!committed_) std::filesystem::remove(temporary_, ignored);
  }
  PartialFile(const PartialFile&) = delete;
  PartialFile& operator=(const PartialFile&) = delete;

  const std::filesystem::path& path() const { return temporary_; }
  void commit() {
    std::error_code error;
    std::filesystem::rename(temporary_, destination_, error);
    if (error) {
      throw std::runtime_error(fmt::format("cannot write '{}': {}", destination_.string(), error.message()));
    }
    committed_ = true;
  }

 private:
  std::filesystem::path destination_;
  std::filesystem::path temporary_;
  bool committed_ = false;
};

}  // namespace bosfuse::report
