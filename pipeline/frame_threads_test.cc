#include "pipeline/frame_threads.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <regex>
#include <stdexcept>
#include <thread>

namespace bosfuse::pipeline {
namespace {

Bytes frame_bytes(std::size_t i) { return Bytes{static_cast<std::uint8_t>(i)}; }

// Frame i's "work": its index as its result, later frames finishing first.
FrameWork work_of(std::size_t count, std::size_t failing = SIZE_MAX) {
  return [count, failing](std::size_t i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2 * (count - i)));
    if (i == failing) throw std::runtime_error("frame " + std::to_string(i) + " failed");
    return frame_bytes(i);
  };
}

TEST(FrameThreads, FramesAreTakenInOrderWhicheverThreadFinishesFirst) {
  const std::size_t count = 12;
  std::atomic<int> prepared{0};
  FrameThreads threads(3, [&](const Bytes& plan) {
    EXPECT_EQ(plan, Bytes({7}));
    ++prepared;
    return work_of(count);
  });
  std::vector<std::size_t> taken;
  const std::size_t n = threads.run(
      Bytes{7}, count, work_of(count),
      [&](std::size_t i, const Bytes& result) {
        EXPECT_EQ(result, frame_bytes(i));
        taken.push_back(i);
      },
      nullptr);
  EXPECT_EQ(n, count);
  ASSERT_EQ(taken.size(), count);
  for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(taken[i], i);
  EXPECT_EQ(prepared, 2) << "the first thread uses the caller's own work";
  EXPECT_TRUE(std::regex_match(threads.brief_report(),
                               std::regex("3 frames side by side: \\d+ frames, \\d+ frames, \\d+ frames\n")))
      << threads.brief_report();
}

TEST(FrameThreads, AFailedFrameStopsAtItsFrameAndIsRethrown) {
  const std::size_t count = 10;
  FrameThreads threads(2, [&](const Bytes&) { return work_of(count, 4); });
  std::vector<std::size_t> taken;
  try {
    threads.run(
        {}, count, work_of(count, 4), [&](std::size_t i, const Bytes&) { taken.push_back(i); }, nullptr);
    FAIL() << "the failure was not rethrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "frame 4 failed");
  }
  EXPECT_EQ(taken, (std::vector<std::size_t>{0, 1, 2, 3}));
}

TEST(FrameThreads, AStopTakesWhatWasHandedOutAndNoMore) {
  std::atomic<bool> stop{false};
  FrameThreads threads(2, [&](const Bytes&) { return work_of(100); });
  std::vector<std::size_t> taken;
  const std::size_t n = threads.run(
      {}, 100, work_of(100),
      [&](std::size_t i, const Bytes&) {
        taken.push_back(i);
        if (i == 2) stop = true;
      },
      &stop);
  EXPECT_EQ(n, taken.size());
  EXPECT_GE(n, 3u);
  EXPECT_LE(n, 6u) << "at most the frames in flight when it stopped";
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(taken[i], i);
}

TEST(FrameThreads, AThreadThatCannotPrepareFailsTheJobAndATakeErrorIsRethrown) {
  FrameThreads unprepared(2, [](const Bytes&) -> FrameWork { throw std::runtime_error("no context here"); });
  EXPECT_THROW(unprepared.run(
                   {}, 5, work_of(5), [](std::size_t, const Bytes&) {}, nullptr),
               std::runtime_error);
  FrameThreads threads(2, [](const Bytes&) { return work_of(5); });
  EXPECT_THROW(threads.run(
                   {}, 5, work_of(5),
                   [](std::size_t i, const Bytes&) {
                     if (i == 1) throw std::logic_error("store full");
                   },
                   nullptr),
               std::logic_error);
  EXPECT_THROW(FrameThreads(0, {}), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::pipeline
