#include "storage/partial_file.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <stdexcept>
#include <system_error>

#include "storage/output_path.h"

namespace bosfuse::storage {
namespace fs = std::filesystem;
namespace {

// PID and a counter: two processes, or two outputs of one, never share a temporary.
std::string unique_suffix() {
  static std::atomic<unsigned> counter{0};
  return fmt::format("partial-{}-{}", static_cast<long>(getpid()), counter++);
}

fs::path written_through_symlink(const fs::path& destination) {
  std::error_code error;
  if (!fs::is_symlink(destination, error)) return destination;
  const fs::path target = fs::weakly_canonical(destination, error);
  return error ? destination : target;
}

}  // namespace

PartialFile::PartialFile(const fs::path& destination) : destination_(written_through_symlink(destination)) {
  check_output_path(destination);
  std::error_code error;
  if (const auto status = fs::status(destination_, error); fs::exists(status) && !fs::is_regular_file(status)) {
    // A device or a pipe (/dev/null, /dev/stdout) is written as it is: renaming onto it would replace it.
    temporary_ = destination_;
    committed_ = true;
    return;
  }
  const fs::path name = destination_.filename();
  temporary_ = destination_.parent_path() /
               fmt::format(".{}.{}{}", name.stem().string(), unique_suffix(), name.extension().string());
  // Something left under that name (a planted symlink) is not written through.
  std::error_code ignored;
  fs::remove(temporary_, ignored);
}

PartialFile::~PartialFile() {
  std::error_code ignored;
  if (!committed_) fs::remove(temporary_, ignored);
}

void PartialFile::commit() {
  if (temporary_ == destination_) return;
  std::error_code error;
  fs::rename(temporary_, destination_, error);
  if (error) throw std::runtime_error(fmt::format("cannot write '{}': {}", destination_.string(), error.message()));
  committed_ = true;
}

PartialFileStream::PartialFileStream(const fs::path& destination) : file_(destination) {
  out_.open(file_.path(), std::ios::binary);
  if (!out_) throw std::runtime_error(fmt::format("cannot write '{}'", destination.string()));
}

void PartialFileStream::close() {
  out_.flush();
  out_.close();
  if (!out_) throw std::runtime_error(fmt::format("could not write '{}'", file_.destination().string()));
  file_.commit();
}

PartialFolder::PartialFolder(const fs::path& destination) : destination_(destination) {
  check_output_path(destination);
  std::error_code error;
  created_destination_ = fs::create_directories(destination_, error);
  if (error || !fs::is_directory(destination_)) {
    throw std::runtime_error(fmt::format("cannot create the folder '{}': {}", destination_.string(),
                                         error ? error.message() : "it is not a folder"));
  }
  staging_ = destination_ / ("." + unique_suffix());
  fs::create_directory(staging_, error);
  if (error) {
    throw std::runtime_error(
        fmt::format("cannot write into the folder '{}': {}", destination_.string(), error.message()));
  }
}

PartialFolder::~PartialFolder() {
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
  if (!committed_ && created_destination_) fs::remove(destination_, ignored);  // only if still empty
}

std::vector<fs::path> PartialFolder::commit() {
  std::vector<fs::path> moved;
  for (const auto& entry : fs::directory_iterator(staging_)) {
    const fs::path target = destination_ / entry.path().filename();
    check_output_path(target);
    std::error_code error;
    fs::rename(entry.path(), target, error);
    if (error) throw std::runtime_error(fmt::format("cannot write '{}': {}", target.string(), error.message()));
    moved.push_back(target);
  }
  committed_ = true;
  return moved;
}

}  // namespace bosfuse::storage
