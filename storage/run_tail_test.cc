#include "storage/run_tail.h"

#include <gtest/gtest.h>

#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

TEST(RunTail, ReadsRowsAfterTheCursorInCommitOrder) {
  testing::TempDir dir;
  auto writer = RunStore::create(dir / "run", {.name = "t", .started_ns = 1000}, RunStore::CreateMode::kNew);
  const auto device = writer.add_device({.name = "d", .kind = "modbus-tcp"});
  const auto channel = writer.add_channel({.device_id = device, .name = "tc0", .kind = "thermocouple", .unit = "degC"});
  // The second batch is older in time but newer in commit: the tail follows commits.
  const std::vector<Sample> first{{channel, 5000, {}, 1.0, {}, {}}, {channel, 6000, {}, 2.0, {}, {}}};
  const std::vector<Sample> second{{channel, 4000, {}, 3.0, {}, {}}};
  writer.write_samples(first);
  writer.write_samples(second);

  RunTail tail(dir / "run");
  const TailCursor head = tail.head();
  EXPECT_EQ(head.sample_rowid, 3);
  const auto all = tail.samples_after(0, 10);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[2].sample.value, 3.0);
  const auto rest = tail.samples_after(all[0].rowid, 1);
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0].sample.value, 2.0);
  EXPECT_TRUE(tail.samples_after(head.sample_rowid, 10).empty());
  EXPECT_EQ(tail.run_status(), "running");
}

}  // namespace
}  // namespace bosfuse::storage
