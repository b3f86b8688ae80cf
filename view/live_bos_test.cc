// The live BOS evaluation as the viewer runs it: over a run whose frames
// arrive while it watches, newest first, skipped frames counted, results
// streamed.

#include "view/live_bos.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "tests/support/synthetic_run.h"
#include "tests/support/temp_dir.h"
#include "view/live_stream.h"
#include "view/page.h"
#include "view/test_sse.h"

namespace bosfuse::view {
namespace {

using namespace std::chrono_literals;

#if defined(__SANITIZE_THREAD__)
// OpenCV's parallel loops run on TBB, which is not instrumented: TSan cannot
// see their hand-offs and reports them as races. What this test checks under
// TSan is LiveBos's own threading, so OpenCV runs its loops serially here.
const bool kOpenCvSerial = [] {
  cv::setNumThreads(0);
  return true;
}();
#endif

// Polls `done` every 20 ms for at most 20 s.
template <typename Done>
bool wait_until(Done done) {
  for (int i = 0; i < 1000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return false;
}

// Appends a copy of the run's first measurement frame, `seconds` later.
void add_frame_copy(const std::filesystem::path& run, int index, double seconds) {
  auto store = storage::RunStore::open(run, true);
  storage::FrameRecord frame;
  for (const auto& f : store.frames()) {
    if (!f.is_reference) frame = f;
  }
  const std::string name = "frames/copy" + std::to_string(index) + ".png";
  std::filesystem::copy_file(run / frame.path, run / name);
  frame.id = 0;
  frame.path = name;
  frame.t_ns += static_cast<std::int64_t>(seconds * 1e9);
  store.add_frame(frame);
}

TEST(LiveBos, EvaluatesTheNewestFrameAndCountsTheOnesItSkipped) {
  bosfuse::testing::TempDir dir;
  const auto run = dir.path() / "run";
  testrun::create_run(run, true);  // a reference and two frames, already there
  RunWatch watch(run, 20ms);
  LiveBos bos(watch);
  ASSERT_TRUE(wait_until([&] { return bos.state().evaluated == 1; })) << bos.state().state;
  auto results = bos.results_from(0);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].frame.frame.path, "frames/frame1.png");  // the newest of the two
  EXPECT_EQ(results[0].skipped, 1);
  ASSERT_EQ(results[0].frame.probes.size(), 2u);
  for (const auto& p : results[0].frame.probes) {
    EXPECT_TRUE(p.valid) << p.name;
    EXPECT_TRUE(p.temperature_c.has_value()) << p.name;
  }
  EXPECT_EQ(bos.state().state, "live");
  const std::string png = bos.latest_frame_png();
  const cv::Mat view = cv::imdecode(std::vector<unsigned char>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(view.cols, 256);  // narrower than the limit: kept at its size

  add_frame_copy(run, 1, 5);
  ASSERT_TRUE(wait_until([&] { return bos.state().evaluated == 2; }));
  results = bos.results_from(1);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].frame.frame.path, "frames/copy1.png");
  EXPECT_EQ(results[0].skipped, 1);  // nothing new was skipped
}

TEST(LiveBos, ARunWithoutFramesSaysWhatItWaitsFor) {
  bosfuse::testing::TempDir dir;
  const auto run = dir.path() / "run";
  testrun::create_run(run, false);
  RunWatch watch(run, 20ms);
  LiveBos bos(watch);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(bos.state().state, "waiting for frames");
  EXPECT_EQ(bos.state().evaluated, 0);
  EXPECT_TRUE(bos.latest_frame_png().empty());
}

TEST(LiveBos, TheStreamSendsEveryResultWithTheStateAfterIt) {
  bosfuse::testing::TempDir dir;
  const auto run = dir.path() / "run";
  testrun::create_run(run, true);
  RunWatch watch(run, 20ms);
  LiveBos bos(watch);
  ASSERT_TRUE(wait_until([&] { return bos.state().evaluated == 1; }));
  LiveStream stream(run, {}, &bos);
  const auto messages = testing::parse_sse(stream.next(watch.snapshot()));
  std::vector<std::string> types;
  for (const auto& m : messages) types.push_back(m.type);
  const auto bos_at = std::find(types.begin(), types.end(), "bos");
  ASSERT_NE(bos_at, types.end());
  EXPECT_EQ(types.back(), "bos-state");
  const auto data = nlohmann::json::parse(messages[bos_at - types.begin()].data);
  EXPECT_EQ(data.at("probes").size(), 2u);
  EXPECT_TRUE(data.at("probes")[0].contains("t_c"));
  // Each probe's σ, as `process` stores them: the random and systematic σ
  // of its temperature and the σ of its shift, those of the evaluated frame.
  const auto evaluated = bos.results_from(0).at(0).frame.probes;
  for (std::size_t p = 0; p < evaluated.size(); ++p) {
    const auto& message = data.at("probes")[p];
    ASSERT_TRUE(evaluated[p].sigma_random_c && evaluated[p].sigma_systematic_c && evaluated[p].sigma_shift_px);
    EXPECT_DOUBLE_EQ(message.at("sigma_random_c").get<double>(), *evaluated[p].sigma_random_c);
    EXPECT_DOUBLE_EQ(message.at("sigma_systematic_c").get<double>(), *evaluated[p].sigma_systematic_c);
    EXPECT_DOUBLE_EQ(message.at("sigma_shift_px").get<double>(), *evaluated[p].sigma_shift_px);
    EXPECT_GT(*evaluated[p].sigma_random_c, 0);
  }
  // The page shows them as "± x °C" beside the BOS temperature.
  const std::string_view page = live_page_html();
  EXPECT_NE(page.find("' ± ' + sig(p.sigma_random_c) + ' °C (random)'"), std::string_view::npos);
  EXPECT_NE(page.find("' ± ' + sig(p.sigma_systematic_c) + ' °C (systematic)'"), std::string_view::npos);
  EXPECT_GT(data.at("quality").at("q_mod").get<double>(), 0.5);
  // Synthetic frames are at 10 and 60 s; the newest is the one evaluated.
  EXPECT_NEAR(data.at("t_s").get<double>(), 60.003, 1e-6);
  EXPECT_EQ(nlohmann::json::parse(messages.back().data).at("skipped"), 1);
  // Nothing new: nothing sent again.
  EXPECT_EQ(stream.next(watch.snapshot()), "");
}

}  // namespace
}  // namespace bosfuse::view
