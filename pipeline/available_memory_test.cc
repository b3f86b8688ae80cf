#include "pipeline/available_memory.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

// A fake /proc and /sys for available_memory().
class FakeSystem : public ::testing::Test {
 protected:
  void write(const std::string& relative, const std::string& text) {
    const auto file = dir_.path() / relative;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file) << text;
  }
  fusion::AvailableMemory read() {
    MemorySources sources;
    sources.proc = dir_.path() / "proc";
    sources.root = dir_.path();
    sources.read_rlimits = false;
    return available_memory(sources);
  }
  void SetUp() override {
    write("proc/meminfo", "MemTotal:       24684092 kB\nMemFree:  23291908 kB\nMemAvailable:   8000000 kB\n");
  }
  testing::TempDir dir_;
};

TEST_F(FakeSystem, MemAvailableAloneWhenNoCgroupLimits) {
  const auto m = read();
  EXPECT_EQ(m.mem_available_bytes, 8'192'000'000ull);
  EXPECT_FALSE(m.cgroup_bytes);
  EXPECT_EQ(m.bytes(), 8'192'000'000ull);
  EXPECT_EQ(m.limited_by(), "MemAvailable");
}

TEST_F(FakeSystem, CgroupV2TakesTheLeastHeadroomUpToTheRootCountingDroppableCache) {
  write("proc/self/mountinfo",
        "24 1 0:22 / /sys/fs/cgroup rw,nosuid - cgroup2 cgroup2 rw,nsdelegate\n"
        "25 1 8:1 / / rw - ext4 /dev/sda1 rw\n");
  write("proc/self/cgroup", "0::/user.slice/app.scope\n");
  write("sys/fs/cgroup/user.slice/app.scope/memory.max", "1000000000\n");
  write("sys/fs/cgroup/user.slice/app.scope/memory.current", "600000000\n");
  write("sys/fs/cgroup/user.slice/app.scope/memory.stat", "anon 400000000\nfile 200000000\ninactive_file 150000000\n");
  write("sys/fs/cgroup/user.slice/memory.max", "max\n");
  write("sys/fs/cgroup/user.slice/memory.current", "900000000\n");
  auto m = read();
  EXPECT_EQ(m.cgroup_bytes, 550'000'000ull) << "1000 − (600 − 150 inactive file) MB";
  EXPECT_EQ(m.limited_by(), "the cgroup limit");
  write("sys/fs/cgroup/user.slice/memory.max", "1200000000\n");
  m = read();
  EXPECT_EQ(m.cgroup_bytes, 300'000'000ull) << "the parent's limit binds";
}

TEST_F(FakeSystem, CgroupV1ReadsTheMemoryHierarchyAndTakesItsHugeLimitAsNone) {
  write("proc/self/mountinfo",
        "31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755\n"
        "35 31 0:32 / /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory\n"
        "36 31 0:33 / /sys/fs/cgroup/cpu,cpuacct rw,relatime - cgroup cgroup rw,cpu,cpuacct\n");
  write("proc/self/cgroup", "9:cpu,cpuacct:/jobs\n4:memory:/jobs/one\n0::/\n");
  write("sys/fs/cgroup/memory/jobs/one/memory.limit_in_bytes", "9223372036854771712\n");
  write("sys/fs/cgroup/memory/jobs/one/memory.usage_in_bytes", "863895552\n");
  EXPECT_FALSE(read().cgroup_bytes) << "v1's 'unlimited'";
  write("sys/fs/cgroup/memory/jobs/one/memory.limit_in_bytes", "2000000000\n");
  write("sys/fs/cgroup/memory/jobs/one/memory.stat", "cache 10\ninactive_file 5\ntotal_inactive_file 100000000\n");
  EXPECT_EQ(read().cgroup_bytes, 2'000'000'000ull - 863'895'552ull + 100'000'000ull);
}

TEST_F(FakeSystem, ACgroupMountedBelowItsRootIsFollowedFromThere) {
  // A container sees its own cgroup as the mount's root.
  write("proc/self/mountinfo", "40 31 0:38 /docker/abc /sys/fs/cgroup rw - cgroup2 cgroup2 rw\n");
  write("proc/self/cgroup", "0::/docker/abc\n");
  write("sys/fs/cgroup/memory.max", "500000000\n");
  write("sys/fs/cgroup/memory.current", "100000000\n");
  EXPECT_EQ(read().cgroup_bytes, 400'000'000ull);
}

TEST(AvailableMemory, ThisProcessKnowsItsAvailableMemory) {
  const auto m = available_memory();
  ASSERT_TRUE(m.mem_available_bytes) << "/proc/meminfo has MemAvailable since Linux 3.14";
  EXPECT_GT(*m.mem_available_bytes, 0u);
  ASSERT_TRUE(m.bytes());
  EXPECT_LE(*m.bytes(), *m.mem_available_bytes);
}

TEST(AvailableMemory, TheCheckCanBeSwitchedOffAndABadSwitchIsNamed) {
  install_memory_probe();  // as the program does at its start
  const cv::Mat image(48, 64, CV_8UC1, cv::Scalar(128));
  const fusion::XcorrOptions options;
  ::setenv("BOSFUSE_MEMORY_CHECK", "maybe", 1);
  EXPECT_THROW(
      {
        try {
          fusion::check_xcorr_memory(image, {}, options);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("BOSFUSE_MEMORY_CHECK must be on or off, not 'maybe'"),
                    std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  ::setenv("BOSFUSE_MEMORY_CHECK", "off", 1);
  EXPECT_NO_THROW(fusion::check_xcorr_memory(image, {}, options));
  ::unsetenv("BOSFUSE_MEMORY_CHECK");
  EXPECT_NO_THROW(fusion::check_xcorr_memory(image, {}, options)) << "a 64×48 pair fits anywhere";
}

}  // namespace
}  // namespace bosfuse::pipeline
