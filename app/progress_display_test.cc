#include "app/progress_display.h"

#include <gtest/gtest.h>

#include <sstream>

namespace bosfuse::app {
namespace {

using namespace std::chrono_literals;

// A clock the test moves by hand.
struct FakeClock {
  std::chrono::steady_clock::time_point now{};
  ProgressDisplay::Clock function() {
    return [this] { return now; };
  }
};

TEST(ProgressDisplay, FormatsDurationsAsAClock) {
  EXPECT_EQ(format_clock_duration(0s), "0:00");
  EXPECT_EQ(format_clock_duration(7s), "0:07");
  EXPECT_EQ(format_clock_duration(1499ms), "0:01");
  EXPECT_EQ(format_clock_duration(1500ms), "0:02");
  EXPECT_EQ(format_clock_duration(725s), "12:05");
  EXPECT_EQ(format_clock_duration(3723s), "1:02:03");
  EXPECT_EQ(format_clock_duration(-5s), "0:00");
}

TEST(ProgressDisplay, NoEstimateUntilTwoStepsThenTheRateSinceTheFirst) {
  FakeClock clock;
  std::ostringstream out;
  ProgressDisplay progress(out, false, clock.function());
  EXPECT_FALSE(progress.eta());
  clock.now += 30s;  // set-up before the first step does not count against the rate
  progress.step(0, 10, "loading");
  EXPECT_FALSE(progress.eta());
  clock.now += 4s;
  progress.step(2, 10);
  ASSERT_TRUE(progress.eta());
  EXPECT_EQ(*progress.eta(), 16s) << "2 items in 4 s, 8 left";
  clock.now += 8s;
  progress.step(5, 10);
  EXPECT_EQ(*progress.eta(), 12s) << "5 items in 12 s, 5 left";
  clock.now += 1s;
  progress.step(10, 10);
  EXPECT_EQ(*progress.eta(), 0s);
}

TEST(ProgressDisplay, ANewTotalOrACountGoingBackStartsANewPhase) {
  FakeClock clock;
  std::ostringstream out;
  ProgressDisplay progress(out, false, clock.function());
  progress.step(0, 4);
  clock.now += 40s;
  progress.step(4, 4);
  progress.step(0, 100);
  EXPECT_FALSE(progress.eta()) << "the first phase's slow rate must not predict the second";
  clock.now += 1s;
  progress.step(10, 100);
  EXPECT_EQ(*progress.eta(), 9s);
  progress.step(3, 100);
  EXPECT_FALSE(progress.eta());
}

TEST(ProgressDisplay, PlainOutputIsOneLinePerStepWithoutControlCharacters) {
  FakeClock clock;
  std::ostringstream out;
  {
    ProgressDisplay progress(out, false, clock.function());
    clock.now += 2s;
    progress.step(1, 4, "frame 1");
    clock.now += 2s;
    progress.step(2, 4, "frame 2\r\n");
    progress.note("reference frame: 0\n");
    clock.now += 66s;
    progress.step(4, 4, "done");
  }
  EXPECT_EQ(out.str(),
            "1/4  25%  0:02 elapsed  ETA —  frame 1\n"
            "2/4  50%  0:04 elapsed  ETA 0:04  frame 2  \n"
            "reference frame: 0\n"
            "4/4 100%  1:10 elapsed  ETA 0:00  done\n");
  EXPECT_EQ(out.str().find('\x1b'), std::string::npos);
  EXPECT_EQ(out.str().find('\r'), std::string::npos);
}

// The demo records for 15 s and then processes for 1 s: its processing
// line must not say "0:16 elapsed" (issue 31).
TEST(ProgressDisplay, ANoteBetweenPhasesStartsTheNextPhasesElapsedTime) {
  FakeClock clock;
  std::ostringstream out;
  {
    ProgressDisplay progress(out, false, clock.function());
    clock.now += 15s;
    progress.note("processing ...");
    clock.now += 1s;
    progress.step(1, 2, "frame 1");
    progress.note("a message while frames run");
    clock.now += 1s;
    progress.step(2, 2, "frame 2");
  }
  EXPECT_EQ(out.str(),
            "processing ...\n"
            "1/2  50%  0:01 elapsed  ETA —  frame 1\n"
            "a message while frames run\n"
            "2/2 100%  0:02 elapsed  ETA 0:00  frame 2\n");
}

TEST(ProgressDisplay, OnATerminalOneLineIsRewrittenInPlace) {
  FakeClock clock;
  std::ostringstream out;
  ProgressDisplay progress(out, true, clock.function());
  progress.step(0, 3, "a");
  clock.now += 3s;
  progress.step(1, 3, "b");
  EXPECT_EQ(out.str(),
            "\r0/3   0%  0:00 elapsed  ETA —  a\x1b[K"
            "\r1/3  33%  0:03 elapsed  ETA 0:06  b\x1b[K");
  out.str("");
  // A note clears the line, prints above it and redraws it.
  progress.note("a message");
  EXPECT_EQ(out.str(), "\r\x1b[Ka message\n\r1/3  33%  0:03 elapsed  ETA 0:06  b\x1b[K");
  out.str("");
  progress.finish();
  EXPECT_EQ(out.str(), "\n") << "the last state stays on the screen";
  out.str("");
  progress.finish();
  EXPECT_EQ(out.str(), "") << "finishing twice ends the line once";
}

TEST(ProgressDisplay, ANoteBeforeAnyStepIsAPlainLine) {
  FakeClock clock;
  std::ostringstream out;
  ProgressDisplay progress(out, true, clock.function());
  progress.note("starting");
  progress.finish();
  EXPECT_EQ(out.str(), "starting\n");
}

TEST(ProgressDisplay, ALongLineIsCutToTheTerminalWidthWithoutSplittingACharacter) {
  FakeClock clock;
  std::ostringstream out;
  ProgressDisplay progress(out, true, clock.function());
  progress.step(2, 2, std::string(200, 'x'));
  const std::string drawn = out.str();
  ASSERT_TRUE(drawn.starts_with("\r2/2 100%") && drawn.ends_with("xx\x1b[K")) << drawn;
  EXPECT_EQ(drawn.size(), 1 + 79 + 3) << "80 columns (the default), one spare";
  out.str("");
  // "—" is three bytes but one column.
  progress.step(1, 3, std::string(200, 'y'));
  EXPECT_NE(out.str().find("ETA —"), std::string::npos);
  EXPECT_EQ(out.str().size(), 1 + 79 + 2 + 3);
}

TEST(ProgressDisplay, AnUnknownTotalShowsTheCountAndTheTimeOnly) {
  FakeClock clock;
  std::ostringstream out;
  ProgressDisplay progress(out, false, clock.function());
  clock.now += 5s;
  progress.step(7, 0, "frames");
  EXPECT_EQ(out.str(), "7  0:05 elapsed  frames\n");
}

}  // namespace
}  // namespace bosfuse::app
