#pragma once
// Runs another program for a test: either to completion with its output
// captured (run_command), or in the background until the test ends
// (BackgroundProcess, killed and reaped in its destructor). Both are
// bounded in time so a hung peer cannot hang the suite.

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace bosfuse::testing {

#ifdef BOSFUSE_BINARY_DIR
// The bosfuse executable of this build, for tests that run it.
inline const std::string kBosfuse = std::string(BOSFUSE_BINARY_DIR) + "/bosfuse";
#endif

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// `command` is run by /bin/sh under coreutils' timeout.
inline CommandResult run_command(const std::string& command, int timeout_s = 30) {
  const std::string wrapped = "timeout " + std::to_string(timeout_s) + " " + command + " 2>&1";
  CommandResult result;
  FILE* pipe = popen(wrapped.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot run: " + command);
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

class BackgroundProcess {
 public:
  explicit BackgroundProcess(std::vector<std::string> argv) {
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    if (posix_spawnp(&pid_, args[0], nullptr, nullptr, args.data(), environ) != 0) {
      throw std::runtime_error("cannot start " + argv[0]);
    }
  }
  ~BackgroundProcess() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    for (int i = 0; i < 100; ++i) {  // up to 1 s, then force
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  void send_signal(int signal) { kill(pid_, signal); }
  pid_t pid() const { return pid_; }

  // The exit code once the process ends within `limit`; -1 if it is still
  // running then or was killed by a signal.
  int wait_exit(std::chrono::milliseconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }

 private:
  pid_t pid_ = -1;
};

// Polls `done` every 10 ms for at most `limit`; true if it became true.
template <typename Predicate>
bool wait_for(Predicate done, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

}  // namespace bosfuse::testing
