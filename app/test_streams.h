#pragma once
// For the command-line tests: a command run with its standard output and
// standard error captured apart, so a test can check the convention that
// data goes to one and messages to the other (tests/support/subprocess.h's
// run_command merges them). The command is given to /bin/sh as one
// argument, so it may hold pipes and quotes as typed in a shell.

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace bosfuse::testing {

struct StreamsResult {
  int exit_code = -1;
  std::string out;  // standard output
  std::string err;  // standard error
  // The most memory (resident) the command, or any process it ran, held.
  std::int64_t peak_memory_bytes = 0;
};

// Runs `command` under coreutils' timeout, its streams into files in `scratch`.
inline StreamsResult run_with_streams(const std::string& command, const std::filesystem::path& scratch,
                                      int timeout_s = 60) {
  const std::string out_path = (scratch / "command.stdout").string();
  const std::string err_path = (scratch / "command.stderr").string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> argv{"timeout", std::to_string(timeout_s), "/bin/sh", "-c", command};
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "timeout", &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw std::runtime_error("cannot run: " + command);
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);  // usage includes the descendants timeout waited for
  const auto read = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read(out_path), read(err_path),
          static_cast<std::int64_t>(usage.ru_maxrss) * 1024};
}

}  // namespace bosfuse::testing
