#pragma once
// A small disk made for a test: a tmpfs of the given size ("1m") mounted on
// a fresh folder, so a test can fill a disk on demand; unmounted (lazily,
// so files still open do not keep it) when the test ends. Mounting needs
// root, as the tests have in CI; elsewhere the test fails saying so.

#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace bosfuse::testing {

class TmpfsMount {
 public:
  TmpfsMount(std::filesystem::path where, const std::string& size) : path_(std::move(where)) {
    std::filesystem::create_directories(path_);
    const std::string options = "size=" + size + ",mode=0755";
    if (::mount("tmpfs", path_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) != 0) {
      throw std::runtime_error("cannot mount a " + size + " tmpfs on " + path_.string() + ": " + std::strerror(errno) +
                               (::geteuid() == 0 ? "" : " (these tests need root, as they have in CI)"));
    }
  }
  ~TmpfsMount() { ::umount2(path_.c_str(), MNT_DETACH); }
  TmpfsMount(const TmpfsMount&) = delete;
  TmpfsMount& operator=(const TmpfsMount&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace bosfuse::testing
