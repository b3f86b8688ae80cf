#include "pipeline/frame_order.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace bosfuse::pipeline {
namespace {

Bytes bytes_of(std::size_t index) { return Bytes{static_cast<std::uint8_t>(index)}; }

std::vector<std::size_t> pop_all(FrameOrder& order) {
  std::vector<std::size_t> popped;
  while (const auto result = order.pop_next()) {
    EXPECT_EQ(result->second, bytes_of(result->first));
    popped.push_back(result->first);
  }
  return popped;
}

TEST(FrameOrder, ResultsFinishedOutOfOrderComeOutInOrder) {
  FrameOrder order(4, nullptr);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(order.next(), i);
  EXPECT_FALSE(order.next());
  order.done(2, bytes_of(2));
  order.done(1, bytes_of(1));
  EXPECT_TRUE(pop_all(order).empty());  // frame 0 is not finished
  order.done(0, bytes_of(0));
  EXPECT_EQ(pop_all(order), (std::vector<std::size_t>{0, 1, 2}));
  order.done(3, bytes_of(3));
  EXPECT_EQ(pop_all(order), (std::vector<std::size_t>{3}));
  EXPECT_EQ(order.taken(), 4u);
  EXPECT_NO_THROW(order.rethrow_failure());
}

TEST(FrameOrder, NothingFromTheFirstFailedFrameOnIsTakenAndItsErrorIsReported) {
  FrameOrder order(6, nullptr);
  for (int i = 0; i < 5; ++i) order.next();
  order.failed(3, std::make_exception_ptr(std::runtime_error("frame 3")));
  order.failed(4, std::make_exception_ptr(std::runtime_error("frame 4")));
  order.failed(1, std::make_exception_ptr(std::runtime_error("frame 1")));
  EXPECT_FALSE(order.handing_out());
  EXPECT_FALSE(order.next());
  for (const std::size_t i : {0, 2, 4}) order.done(i, bytes_of(i));
  EXPECT_EQ(pop_all(order), (std::vector<std::size_t>{0}));
  try {
    order.rethrow_failure();
    FAIL() << "no failure";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "frame 1");
  }
}

TEST(FrameOrder, AStopEndsTheHandingOutButNotTheTaking) {
  std::atomic<bool> stop{false};
  FrameOrder order(10, &stop);
  EXPECT_EQ(order.next(), 0u);
  stop = true;
  EXPECT_FALSE(order.next());
  order.done(0, bytes_of(0));
  EXPECT_EQ(pop_all(order), (std::vector<std::size_t>{0}));
  EXPECT_NO_THROW(order.rethrow_failure());
}

}  // namespace
}  // namespace bosfuse::pipeline
