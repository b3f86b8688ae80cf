#pragma once
// What this machine offers the process in memory, read from the system, and
// the probe fusion's memory check asks (fusion/memory_budget.h), which the
// program installs once at its start (app/main.cc): fusion/ reads no system
// file and no environment itself.
//
// What is available is the least of MemAvailable (/proc/meminfo), the memory
// cgroup's limit minus its usage (cgroup v2 memory.max − memory.current, v1
// memory.limit_in_bytes − memory.usage_in_bytes, page cache it could drop
// counted as free, each level up to the root), and the address-space and
// data limits (ulimit -v, -d) minus what the process has mapped; it is only
// read. BOSFUSE_MEMORY_CHECK=off skips the check (swap is not counted as
// available, for example).

#include <filesystem>
#include <optional>

#include "fusion/memory_budget.h"

namespace bosfuse::pipeline {

// Where available_memory() reads; tests point it at a fake tree.
struct MemorySources {
  std::filesystem::path proc = "/proc";  // meminfo, self/status, self/cgroup, self/mountinfo
  std::filesystem::path root = "/";      // prefix of the cgroup mount points mountinfo names
  bool read_rlimits = true;              // getrlimit(RLIMIT_AS, RLIMIT_DATA)
};

fusion::AvailableMemory available_memory(const MemorySources& sources = {});

// available_memory(), or nullopt when BOSFUSE_MEMORY_CHECK is "off" (or
// "0"); throws std::invalid_argument naming the variable when it is neither
// on nor off. Read at every call, as the check is.
std::optional<fusion::AvailableMemory> checked_available_memory();

// Makes fusion's memory check ask checked_available_memory().
void install_memory_probe();

}  // namespace bosfuse::pipeline
