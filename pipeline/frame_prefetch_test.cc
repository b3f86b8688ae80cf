#include "pipeline/frame_prefetch.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace bosfuse::pipeline {
namespace {

using namespace std::chrono_literals;
using storage::FrameRecord;

std::vector<FrameRecord> frames(int count) {
  std::vector<FrameRecord> out;
  for (int i = 0; i < count; ++i) {
    FrameRecord f;
    f.id = 10 + i;
    f.path = "frames/" + std::to_string(f.id) + ".png";
    out.push_back(f);
  }
  return out;
}

// A 1×1 image holding the frame's id, so a test sees which frame it got.
cv::Mat image_of(const FrameRecord& frame) { return cv::Mat(1, 1, CV_32S, cv::Scalar(static_cast<int>(frame.id))); }

// Counts the loads of each frame, from whichever thread they run on.
struct CountingLoad {
  std::mutex mutex;
  std::map<std::int64_t, int> loads;

  FramePrefetch::Load load() {
    return [this](const FrameRecord& frame) {
      const std::lock_guard lock(mutex);
      ++loads[frame.id];
      return image_of(frame);
    };
  }
  int total() {
    const std::lock_guard lock(mutex);
    int n = 0;
    for (const auto& [id, count] : loads) n += count;
    return n;
  }
};

class LookAhead : public ::testing::TestWithParam<int> {};

TEST_P(LookAhead, HandsOutEveryFrameInOrderEachLoadedOnce) {
  CountingLoad counting;
  const auto all = frames(6);
  FramePrefetch prefetch(all, counting.load(), GetParam());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(prefetch.remaining(), all.size() - i);
    const auto next = prefetch.next();
    ASSERT_TRUE(next);
    EXPECT_EQ(next->frame.id, all[i].id);
    EXPECT_EQ(next->frame.path, all[i].path);
    EXPECT_EQ(next->image.at<int>(0, 0), all[i].id) << "the image is its own frame's";
    EXPECT_GE(next->decode_seconds, 0);
    EXPECT_GE(next->wait_seconds, 0);
  }
  EXPECT_EQ(prefetch.remaining(), 0u);
  EXPECT_FALSE(prefetch.next());
  EXPECT_FALSE(prefetch.next()) << "the end stays the end";
  for (const auto& f : all) EXPECT_EQ(counting.loads[f.id], 1) << "frame " << f.id;
  EXPECT_EQ(counting.total(), 6);
}

TEST_P(LookAhead, ALoadErrorComesFromTheNextOfItsOwnFrameAndTheOthersStillCome) {
  const auto all = frames(4);
  FramePrefetch prefetch(
      all,
      [](const FrameRecord& frame) -> cv::Mat {
        if (frame.id == 12) throw std::runtime_error("frame 12: unreadable image");
        return image_of(frame);
      },
      GetParam());
  EXPECT_EQ(prefetch.next()->frame.id, 10);
  EXPECT_EQ(prefetch.next()->frame.id, 11) << "the frame before the bad one comes as usual";
  try {
    prefetch.next();
    FAIL() << "the unreadable frame came";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "frame 12: unreadable image") << "the load's own exception";
  }
  EXPECT_EQ(prefetch.next()->frame.id, 13);
  EXPECT_FALSE(prefetch.next());
}

INSTANTIATE_TEST_SUITE_P(FramePrefetch, LookAhead, ::testing::Values(0, 1, 2));

// Lets a test hold one frame's load until it releases it, and see it start.
struct HeldLoad {
  std::int64_t held_id = 0;
  std::promise<void> started, release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<bool> finished{false};
  CountingLoad counting;

  FramePrefetch::Load load() {
    return [this, count = counting.load()](const FrameRecord& frame) {
      cv::Mat image = count(frame);
      if (frame.id != held_id) return image;
      started.set_value();
      released.wait_for(30s);  // bounded: a broken test fails instead of hanging
      // A prefetch that did not wait for this load would be gone by now.
      std::this_thread::sleep_for(100ms);
      finished = true;
      return image;
    };
  }
};

TEST(FramePrefetch, LoadsTheNextFrameWhileTheCallerHoldsOneAndNoFurther) {
  HeldLoad held;
  held.held_id = 11;
  const auto all = frames(5);
  FramePrefetch prefetch(all, held.load(), 1);
  const auto first = prefetch.next();
  ASSERT_EQ(first->frame.id, 10);
  // The caller has not asked for frame 11, yet its load runs.
  ASSERT_EQ(held.started.get_future().wait_for(30s), std::future_status::ready) << "frame 11 was not read ahead";
  EXPECT_EQ(held.counting.total(), 2) << "a look-ahead of one: frames 10 and 11, not 12";
  held.release.set_value();
  EXPECT_EQ(prefetch.next()->frame.id, 11);
  EXPECT_TRUE(held.finished);
}

TEST(FramePrefetch, DestroyedWhileALoadRunsItWaitsForItAndStartsNoOther) {
  HeldLoad held;
  held.held_id = 11;
  {
    FramePrefetch prefetch(frames(5), held.load(), 1);
    ASSERT_EQ(prefetch.next()->frame.id, 10);  // the caller stops after one frame
    ASSERT_EQ(held.started.get_future().wait_for(30s), std::future_status::ready);
    held.release.set_value();
  }
  EXPECT_TRUE(held.finished) << "the destructor returned while a load still ran";
  EXPECT_EQ(held.counting.total(), 2) << "frames after the one in flight were loaded";
}

TEST(FramePrefetch, WithoutLookAheadNothingLoadsBeforeItIsAskedFor) {
  CountingLoad counting;
  FramePrefetch prefetch(frames(3), counting.load(), 0);
  EXPECT_EQ(counting.total(), 0);
  prefetch.next();
  EXPECT_EQ(counting.total(), 1);
}

TEST(FramePrefetch, RefusesANegativeLookAheadAndNoLoad) {
  CountingLoad counting;
  EXPECT_THROW(FramePrefetch(frames(2), counting.load(), -1), std::invalid_argument);
  EXPECT_THROW(FramePrefetch(frames(2), FramePrefetch::Load{}, 1), std::invalid_argument);
  FramePrefetch none(std::vector<FrameRecord>{}, counting.load(), 1);
  EXPECT_FALSE(none.next());
  EXPECT_EQ(counting.total(), 0);
}

}  // namespace
}  // namespace bosfuse::pipeline
