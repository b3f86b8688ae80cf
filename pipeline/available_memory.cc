#include "pipeline/available_memory.h"

#include <sys/resource.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace bosfuse::pipeline {
namespace {

using ByteCount = std::uint64_t;

bool check_enabled() {
  const char* value = std::getenv("BOSFUSE_MEMORY_CHECK");
  if (!value || !*value) return true;
  const std::string text = value;
  if (text == "on" || text == "1") return true;
  if (text == "off" || text == "0") return false;
  throw std::invalid_argument("BOSFUSE_MEMORY_CHECK must be on or off, not '" + text + "'");
}

std::optional<ByteCount> read_number(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string text;
  if (!(in >> text)) return std::nullopt;
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;  // "max"
  try {
    return std::stoull(text);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// The value of `key` in a "key value" or "key: value kB" file (meminfo,
// status, memory.stat), in bytes when the line says kB.
std::optional<ByteCount> read_keyed(const std::filesystem::path& file, const std::string& key) {
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string name, unit;
    ByteCount value = 0;
    if (!(fields >> name >> value)) continue;
    if (!name.empty() && name.back() == ':') name.pop_back();
    if (name != key) continue;
    fields >> unit;
    return unit == "kB" ? value * 1024 : value;
  }
  return std::nullopt;
}

struct CgroupMount {
  std::filesystem::path mount_point;
  std::string root;  // the cgroup the mount shows at its mount point
};

// The memory cgroup mounts: cgroup2, and v1's with the memory controller.
std::vector<std::pair<CgroupMount, bool>> memory_cgroup_mounts(const std::filesystem::path& mountinfo) {
  std::vector<std::pair<CgroupMount, bool>> mounts;  // bool: v2
  std::ifstream in(mountinfo);
  for (std::string line; std::getline(in, line);) {
    const auto dash = line.find(" - ");
    if (dash == std::string::npos) continue;
    std::istringstream before(line.substr(0, dash)), after(line.substr(dash + 3));
    std::string id, parent, device, root, mount_point, fstype, source, super_options;
    if (!(before >> id >> parent >> device >> root >> mount_point)) continue;
    if (!(after >> fstype >> source >> super_options)) continue;
    const bool v2 = fstype == "cgroup2";
    const bool v1_memory = fstype == "cgroup" && ("," + super_options + ",").find(",memory,") != std::string::npos;
    if (v2 || v1_memory) mounts.push_back({{mount_point, root}, v2});
  }
  return mounts;
}

// This process's cgroup path in the v2 hierarchy (line "0::path") or the
// v1 memory hierarchy (a line whose controllers include memory).
std::optional<std::string> cgroup_path(const std::filesystem::path& cgroup_file, bool v2) {
  std::ifstream in(cgroup_file);
  for (std::string line; std::getline(in, line);) {
    const auto first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const bool match = v2 ? line.substr(0, first) == "0" && controllers.empty()
                          : ("," + controllers + ",").find(",memory,") != std::string::npos;
    if (match) return line.substr(second + 1);
  }
  return std::nullopt;
}

// Limit minus usage at each level from the process's cgroup up to the
// mount's root, the least of them; page cache the cgroup could drop
// (inactive file pages) counts as free, as the kernel would reclaim it
// before failing an allocation.
std::optional<ByteCount> cgroup_headroom(const CgroupMount& mount, bool v2, const std::string& path,
                                     const std::filesystem::path& root) {
  std::string relative = path;
  const bool below_root =
      relative.starts_with(mount.root) && (relative.size() == mount.root.size() || relative[mount.root.size()] == '/');
  if (mount.root != "/" && below_root) relative = relative.substr(mount.root.size());
  const std::filesystem::path top = root / std::filesystem::path(mount.mount_point).relative_path();
  std::filesystem::path dir = top;
  for (const auto& part : std::filesystem::path(relative).relative_path()) {
    // A cgroup outside this namespace's view ("/../..") has no files here to read.
    if (part == "..") return std::nullopt;
    if (!part.empty()) dir /= part;
  }
  const char* limit_file = v2 ? "memory.max" : "memory.limit_in_bytes";
  const char* usage_file = v2 ? "memory.current" : "memory.usage_in_bytes";
  std::optional<ByteCount> least;
  for (int level = 0; level < 64; ++level) {  // a path has fewer levels than that
    const auto limit = read_number(dir / limit_file);
    const auto usage = read_number(dir / usage_file);
    // v1 writes "no limit" as the largest page-aligned long.
    if (limit && usage && *limit < (ByteCount{1} << 60)) {
      const ByteCount reclaimable =
          read_keyed(dir / "memory.stat", v2 ? "inactive_file" : "total_inactive_file").value_or(0);
      const ByteCount used = *usage > reclaimable ? *usage - reclaimable : 0;
      const ByteCount headroom = *limit > used ? *limit - used : 0;
      least = least ? std::min(*least, headroom) : headroom;
    }
    if (dir == top || dir.parent_path() == dir) break;
    dir = dir.parent_path();
  }
  return least;
}

std::optional<ByteCount> rlimit_headroom(int resource, const std::filesystem::path& status, const std::string& key) {
  rlimit limit{};
  if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  const ByteCount used = read_keyed(status, key).value_or(0);
  return limit.rlim_cur > used ? ByteCount(limit.rlim_cur) - used : 0;
}

}  // namespace

fusion::AvailableMemory available_memory(const MemorySources& sources) {
  fusion::AvailableMemory m;
  m.mem_available_bytes = read_keyed(sources.proc / "meminfo", "MemAvailable");
  for (const auto& [mount, v2] : memory_cgroup_mounts(sources.proc / "self" / "mountinfo")) {
    const auto path = cgroup_path(sources.proc / "self" / "cgroup", v2);
    const auto headroom = path ? cgroup_headroom(mount, v2, *path, sources.root) : std::nullopt;
    if (headroom) m.cgroup_bytes = std::min(m.cgroup_bytes.value_or(*headroom), *headroom);
  }
  if (sources.read_rlimits) {
    const auto status = sources.proc / "self" / "status";
    m.address_space_bytes = rlimit_headroom(RLIMIT_AS, status, "VmSize");
    m.data_bytes = rlimit_headroom(RLIMIT_DATA, status, "VmData");
  }
  return m;
}

std::optional<fusion::AvailableMemory> checked_available_memory() {
  if (!check_enabled()) return std::nullopt;
  return available_memory();
}

void install_memory_probe() { fusion::install_available_memory_probe(checked_available_memory); }

}  // namespace bosfuse::pipeline
