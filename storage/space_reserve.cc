#include "storage/space_reserve.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>
#include <utility>
#include <vector>

#include "storage/database.h"

namespace bosfuse::storage {
namespace {

// posix_fallocate, or zeros written where the file system cannot allocate
// without writing; 0 or the errno.
int allocate(int fd, std::size_t bytes) {
  const int rc = ::posix_fallocate(fd, 0, static_cast<off_t>(bytes));
  if (rc != EOPNOTSUPP && rc != EINVAL) return rc;
  const std::vector<char> zeros(64 * 1024, 0);
  for (std::size_t written = 0; written < bytes;) {
    const ssize_t n = ::write(fd, zeros.data(), std::min(zeros.size(), bytes - written));
    if (n < 0) return errno;
    written += static_cast<std::size_t>(n);
  }
  return ::fsync(fd) == 0 ? 0 : errno;
}

}  // namespace

SpaceReserve::SpaceReserve(const std::filesystem::path& run_dir, std::size_t bytes)
    : path_(run_dir / kFileName), bytes_(bytes) {
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw StorageError("cannot create '" + path_.string() + "': " + std::strerror(errno));
  const int rc = allocate(fd, bytes);
  ::close(fd);
  if (rc != 0) {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
    throw StorageError("cannot reserve " + std::to_string(bytes / 1024) + " KB in '" + path_.string() +
                       "': " + std::strerror(rc));
  }
}

SpaceReserve::SpaceReserve(SpaceReserve&& other) noexcept
    : path_(std::exchange(other.path_, {})), bytes_(other.bytes_) {}

SpaceReserve::~SpaceReserve() { release(); }

bool SpaceReserve::release() noexcept {
  if (path_.empty()) return false;
  std::error_code ec;
  const bool removed = std::filesystem::remove(path_, ec);
  path_.clear();
  return removed;
}

}  // namespace bosfuse::storage
