#include "pipeline/process.h"
#include "pipeline/process_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>

#include "fusion/temperature_budget.h"
#include "pipeline/run_selection.h"
#include "sim/synthetic_pair.h"
#include "storage/experiment_clock.h"
#include "storage/processing_store.h"
#include "storage/run_lock.h"
#include "storage/run_store.h"
#include "tests/support/synthetic_run.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using sorted_json = nlohmann::json;

ProcessReport process(const fs::path& run, SettingsOverrides overrides = {}, bool resume = false,
                      const std::atomic<bool>* stop = nullptr,
                      std::function<void(const ProcessProgress&)> progress = {}, bool pipelined = true) {
  ProcessOptions options;
  options.overrides = std::move(overrides);
  options.resume = resume;
  options.stop = stop;
  options.progress = std::move(progress);
  options.prefetch_frames = pipelined ? 1 : 0;
  options.finish_aside = pipelined;
  options.frames_at_once = 1;  // the pipelined loop; frames side by side have their own test
  return process_run(run, options);
}

// Pipelined: the next frame decoded and the last one finished while one is
// evaluated; else each step in turn.
ProcessReport process_pipelined(const fs::path& run, bool pipelined, SettingsOverrides overrides = {}) {
  return process(run, std::move(overrides), false, nullptr, {}, pipelined);
}

// More measurement frames of the bump, each its own peak, stored out of time
// order among the run's two (ids and time order differ).
void add_frames(const fs::path& run, const testrun::Truth& truth) {
  auto store = storage::RunStore::open(run, true);
  sim::PairOptions pair;
  pair.pattern.width_px = truth.image.width;
  pair.pattern.height_px = truth.image.height;
  pair.pattern.dot_diameter_px = 3;
  pair.pattern.seed = 5;  // the run's background
  const double times_s[] = {90, 30, 120, 45};
  for (int f = 0; f < 4; ++f) {
    pair.field = sim::DisplacementModel::bump_gradient(truth.bump_centre.x, truth.bump_centre.y, truth.bump_radius_px,
                                                       0.2 + 0.2 * f);
    pair.noise_seed = 200 + f;
    const std::string name = "frames/extra" + std::to_string(f) + ".png";
    ASSERT_TRUE(cv::imwrite((run / name).string(), sim::render_pair(pair).measurement));
    store.add_frame({0, std::nullopt, truth.start_ns + static_cast<std::int64_t>(times_s[f] * 1e9), std::nullopt, name,
                     truth.image.width, truth.image.height, 8, false});
  }
}

// The frames a processing left staged, when one was left unfinished.
std::vector<std::int64_t> staged_frames(const fs::path& run) {
  const storage::ProcessingStore results(run);
  const auto unfinished = results.unfinished_processing();
  return unfinished ? results.staged_frame_ids(unfinished->id) : std::vector<std::int64_t>{};
}

sorted_json current_settings(const fs::path& run) {
  const auto p = storage::ProcessingStore(run).current_processing();
  return p ? sorted_json::parse(p->settings_json) : sorted_json();
}

// Everything a processing stored, in a comparable form (field files by content).
struct Results {
  std::vector<std::pair<std::string, std::vector<storage::ProbeSampleRecord>>> probes;
  std::vector<std::string> fits, agreements;
  std::vector<std::string> field_files;

  explicit Results(const fs::path& run) {
    const storage::ProcessingStore results(run);
    for (const auto& p : results.probes()) probes.emplace_back(p.name, results.probe_samples(p.id));
    for (const auto& f : results.fits()) fits.push_back(f.json);
    for (const auto& a : results.agreements()) agreements.push_back(a.json);
    for (const auto& f : results.fields()) {
      std::ifstream in(run / f.path);
      field_files.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  }
};

void expect_equal(const Results& a, const Results& b) {
  ASSERT_EQ(a.probes.size(), b.probes.size());
  for (std::size_t p = 0; p < a.probes.size(); ++p) {
    EXPECT_EQ(a.probes[p].first, b.probes[p].first);
    ASSERT_EQ(a.probes[p].second.size(), b.probes[p].second.size());
    for (std::size_t i = 0; i < a.probes[p].second.size(); ++i) {
      const auto &x = a.probes[p].second[i], &y = b.probes[p].second[i];
      EXPECT_EQ(x.frame_id, y.frame_id);
      EXPECT_EQ(x.t_ns, y.t_ns);
      EXPECT_EQ(x.u_px, y.u_px);
      EXPECT_EQ(x.v_px, y.v_px);
      EXPECT_EQ(x.shift_px, y.shift_px);
      EXPECT_EQ(x.temperature_c, y.temperature_c);
      EXPECT_EQ(x.valid, y.valid);
      EXPECT_EQ(x.sigma_u_px, y.sigma_u_px);
      EXPECT_EQ(x.sigma_v_px, y.sigma_v_px);
      EXPECT_EQ(x.sigma_shift_px, y.sigma_shift_px);
      EXPECT_EQ(x.sigma_random_c, y.sigma_random_c);
      EXPECT_EQ(x.sigma_systematic_c, y.sigma_systematic_c);
    }
  }
  EXPECT_EQ(a.fits, b.fits);
  EXPECT_EQ(a.agreements, b.agreements);
  EXPECT_EQ(a.field_files, b.field_files);
}

class Process : public ::testing::Test {
 protected:
  void SetUp() override { testrun::create_run(run(), true, truth_); }
  fs::path run() const { return dir_ / "run"; }

  testing::TempDir dir_;
  testrun::Truth truth_;
};

TEST_F(Process, StoresItsSettingsReusesThemWithoutOptionsAndOptionsOverrideThem) {
  cv::imwrite((run() / "holder.png").string(), testrun::holder_mask(truth_));
  SettingsOverrides first;
  first.mask = "holder.png";
  first.passes = 2;
  ASSERT_TRUE(process(run(), first).complete);
  const sorted_json stored = current_settings(run());
  EXPECT_EQ(stored.at("mask"), "holder.png");
  EXPECT_EQ(stored.at("passes"), 2);
  EXPECT_EQ(stored.at("window_px"), 16) << "the default";
  EXPECT_EQ(stored.at("mode"), "full");
  const Results before(run());

  const auto again = process(run());
  ASSERT_TRUE(again.complete);
  EXPECT_EQ(current_settings(run()), stored) << "no options: the stored settings";
  const Results repeated(run());
  EXPECT_EQ(repeated.fits, before.fits) << "the same settings give the same results";
  EXPECT_EQ(repeated.field_files, before.field_files);

  SettingsOverrides step;
  step.step_px = 16;
  ASSERT_TRUE(process(run(), step).complete);
  const sorted_json changed = current_settings(run());
  EXPECT_EQ(changed.at("step_px"), 16);
  EXPECT_EQ(changed.at("mask"), "holder.png") << "what the options did not name is kept";
  EXPECT_EQ(changed.at("passes"), 2);
  EXPECT_EQ(fs::directory_iterator(run() / "fields")->path().filename(),
            "p" + std::to_string(storage::ProcessingStore(run()).current_processing()->id))
      << "only the current processing's field files are kept";
}

// Every valid sample of a processed run carries its σ: the shift's (px)
// and, under the physical model, the random and systematic σ of its
// temperature; the systematic one is the Type-B budget of that temperature
// with the window term, so at least the budget without it, and a sample
// without a measurement carries none.
TEST_F(Process, StoredSamplesCarryTheirUncertainty) {
  ASSERT_TRUE(process(run()).complete);
  const storage::ProcessingStore results(run());
  auto settings = settings_from_json(sorted_json::parse(results.current_processing()->settings_json));
  const auto store = storage::RunStore::open(run());
  resolve_ambient(settings.geometry, store, positioned_channels(store.channels()), storage::experiment_clock(store),
                  split_frames(store.frames()).reference);
  const fusion::BosGeometry geometry(settings.geometry.geometry);
  std::size_t with_temperature = 0;
  for (const auto& probe : results.probes()) {
    for (const auto& s : results.probe_samples(probe.id)) {
      if (!s.valid) {
        EXPECT_FALSE(s.sigma_shift_px || s.sigma_random_c || s.sigma_systematic_c);
        continue;
      }
      ASSERT_TRUE(s.sigma_u_px && s.sigma_v_px && s.sigma_shift_px) << probe.name << " frame " << s.frame_id;
      EXPECT_GT(*s.sigma_shift_px, 0);
      EXPECT_LT(*s.sigma_shift_px, 0.2) << "a bounded σ for a textured synthetic frame";
      EXPECT_LE(*s.sigma_shift_px, std::max(*s.sigma_u_px, *s.sigma_v_px) + 1e-12);
      if (!s.temperature_c) continue;
      ++with_temperature;
      ASSERT_TRUE(s.sigma_random_c && s.sigma_systematic_c);
      EXPECT_TRUE(std::isfinite(*s.sigma_random_c) && *s.sigma_random_c > 0);
      const auto budget = fusion::temperature_budget(geometry, settings.geometry.uncertainty, *s.temperature_c);
      EXPECT_GE(*s.sigma_systematic_c, budget.combined_c - 1e-12) << "the budget, and the window term besides";
      std::printf("%s t=%lld: T %.3f degC, sigma random %.4f, systematic %.4f (budget without window %.4f)\n",
                  probe.name.c_str(), static_cast<long long>(s.t_ns), *s.temperature_c, *s.sigma_random_c,
                  *s.sigma_systematic_c, budget.combined_c);
    }
  }
  EXPECT_GT(with_temperature, 0u) << "the physical model gave temperatures";
}

TEST_F(Process, AdaptiveRefinementIsASettingAndEachFieldStoresTheFractionRefined) {
  ASSERT_TRUE(process(run()).complete);
  EXPECT_EQ(current_settings(run()).at("adaptive_refinement"), false) << "the default";
  for (const auto& f : storage::ProcessingStore(run()).fields()) {
    if (f.kind == "displacement") {
      EXPECT_EQ(sorted_json::parse(f.json).at("refined_fraction"), 1.0);
    }
  }
  SettingsOverrides adaptive;
  adaptive.adaptive_refinement = true;
  adaptive.adaptive_threshold = 6;
  ASSERT_TRUE(process(run(), adaptive).complete);
  EXPECT_EQ(current_settings(run()).at("adaptive_refinement"), true);
  EXPECT_EQ(current_settings(run()).at("adaptive_threshold"), 6);
  std::size_t displacement_fields = 0;
  for (const auto& f : storage::ProcessingStore(run()).fields()) {
    if (f.kind != "displacement") continue;
    const double fraction = sorted_json::parse(f.json).at("refined_fraction").get<double>();
    EXPECT_GE(fraction, 0.0);
    EXPECT_LE(fraction, 1.0);
    ++displacement_fields;
  }
  EXPECT_GT(displacement_fields, 0u);
  ASSERT_TRUE(process(run()).complete);
  EXPECT_EQ(current_settings(run()).at("adaptive_refinement"), true) << "kept without options";
  // Settings stored before the option existed read as off.
  sorted_json old = current_settings(run());
  old.erase("adaptive_refinement");
  old.erase("adaptive_threshold");
  EXPECT_FALSE(settings_from_json(old).evaluator.xcorr.adaptive_refinement);
  SettingsOverrides bad;
  bad.adaptive_threshold = 0;
  EXPECT_THROW(process(run(), bad), std::runtime_error);
}

// The run's measurement frames shifted (5.3, -3.7) px from its reference:
// |d| = 6.5 px, past the ±4 px the search starts from.
void shift_frames_far(const fs::path& run, const testrun::Truth& truth) {
  sim::PairOptions pair;
  pair.pattern.width_px = truth.image.width;
  pair.pattern.height_px = truth.image.height;
  pair.pattern.dot_diameter_px = 3;
  pair.pattern.seed = 5;  // the run's background
  pair.field = sim::DisplacementModel::uniform(5.3, -3.7);
  for (int f = 0; f < 2; ++f) {
    pair.noise_seed = 300 + f;
    const std::string name = "frames/frame" + std::to_string(f) + ".png";
    ASSERT_TRUE(cv::imwrite((run / name).string(), sim::render_pair(pair).measurement));
  }
}

// Each displacement field's record of its first pass's search.
std::vector<sorted_json> field_searches(const fs::path& run) {
  std::vector<sorted_json> out;
  for (const auto& f : storage::ProcessingStore(run).fields()) {
    if (f.kind == "displacement") out.push_back(sorted_json::parse(f.json).at("search"));
  }
  return out;
}

TEST_F(Process, TheSearchBoundFoundFromTheSceneIsStoredAndTheNextProcessingUsesItWithoutSampling) {
  shift_frames_far(run(), truth_);
  ProcessOptions options;
  options.frames_at_once = 2;  // side by side: the other thread's evaluator gets the bound with the plan
  ASSERT_TRUE(process_run(run(), options).complete);
  const sorted_json found = current_settings(run()).at("found_search");
  EXPECT_TRUE(found.at("widened").get<bool>()) << found;
  const double bound_px = found.at("max_shift_px").get<double>();
  EXPECT_GT(bound_px, 6) << found;
  for (const auto& search : field_searches(run())) {
    EXPECT_EQ(search.at("max_shift_px").get<double>(), bound_px) << "every frame searched as far: " << search;
  }

  // The next processing reads the stored bound back and uses it as found: a
  // stored bound of 9.5 px, which no sample of this scene gives, is what
  // every frame then searches.
  sorted_json stored = current_settings(run());
  stored["found_search"]["max_shift_px"] = 9.5;
  storage::ProcessingStore(run(), true).add_inherited_settings(stored.dump(), truth_.start_ns);
  options.frames_at_once = 1;
  ASSERT_TRUE(process_run(run(), options).complete);
  EXPECT_EQ(current_settings(run()).at("found_search").at("max_shift_px"), 9.5);
  for (const auto& search : field_searches(run())) {
    EXPECT_EQ(search.at("max_shift_px"), 9.5) << search;
    EXPECT_TRUE(search.at("stored").get<bool>()) << "the scene was not sampled again: " << search;
  }

  // Options that change what the search sees sample the scene again.
  options.overrides.step_px = 8;
  ASSERT_TRUE(process_run(run(), options).complete);
  EXPECT_EQ(current_settings(run()).at("found_search").at("max_shift_px"), bound_px);
  for (const auto& search : field_searches(run())) EXPECT_FALSE(search.at("stored").get<bool>()) << search;

  // An explicit bound is not a found one: nothing is stored.
  options.overrides.max_shift_px = 8;
  ASSERT_TRUE(process_run(run(), options).complete);
  EXPECT_FALSE(current_settings(run()).contains("found_search"));
}

TEST_F(Process, AResumedProcessingSearchesAsFarAsItsFirstFramesDid) {
  shift_frames_far(run(), truth_);
  std::atomic<bool> stop{false};
  ASSERT_FALSE(process(run(), {}, false, &stop, [&](const ProcessProgress& p) { stop = stop || p.done >= 1; }).complete);
  const storage::ProcessingStore results(run());
  const sorted_json interrupted = sorted_json::parse(results.unfinished_processing()->settings_json);
  ASSERT_TRUE(interrupted.contains("found_search")) << "stored before the first frame: " << interrupted;
  const double bound_px = interrupted.at("found_search").at("max_shift_px").get<double>();
  ASSERT_TRUE(process(run(), {}, true).complete);
  const auto searches = field_searches(run());
  ASSERT_EQ(searches.size(), 2u);
  EXPECT_EQ(searches.back().at("max_shift_px").get<double>(), bound_px);
  EXPECT_TRUE(searches.back().at("stored").get<bool>()) << "the resumed frame did not sample: " << searches.back();
}

TEST_F(Process, AMaskOutsideTheRunIsCopiedIntoItAndARelativeOneMustBeInIt) {
  cv::imwrite((dir_ / "holder.png").string(), testrun::holder_mask(truth_));
  SettingsOverrides outside;
  outside.mask = (dir_ / "holder.png").string();
  ASSERT_TRUE(process(run(), outside).complete);
  EXPECT_EQ(current_settings(run()).at("mask"), "masks/holder.png");
  EXPECT_TRUE(fs::is_regular_file(run() / "masks/holder.png")) << "the run keeps its own copy";
  SettingsOverrides escaping;
  escaping.mask = "../holder.png";
  EXPECT_THROW(process(run(), escaping), std::exception);
  SettingsOverrides none;
  none.mask = "";
  ASSERT_TRUE(process(run(), none).complete);
  EXPECT_FALSE(current_settings(run()).contains("mask"));
}

TEST_F(Process, AStoppedProcessingLeavesTheCurrentResultsAndResumeEqualsAnUninterruptedOne) {
  ASSERT_TRUE(process(run()).complete);
  const Results first(run());
  fs::copy(run(), dir_ / "copy", fs::copy_options::recursive);

  SettingsOverrides other;
  other.passes = 2;
  std::atomic<bool> stop{false};
  const auto stopped =
      process(run(), other, false, &stop, [&](const ProcessProgress& p) { stop = stop || p.done >= 1; });
  EXPECT_FALSE(stopped.complete);
  EXPECT_NE(stopped.text.find("--resume"), std::string::npos) << stopped.text;
  expect_equal(Results(run()), first);  // the earlier results, untouched and readable
  EXPECT_EQ(current_settings(run()).at("passes"), 3);

  const auto resumed = process(run(), {}, true);
  ASSERT_TRUE(resumed.complete);
  EXPECT_EQ(resumed.frames_resumed, 1u);
  EXPECT_EQ(current_settings(run()).at("passes"), 2) << "resumed with the interrupted processing's settings";
  ASSERT_TRUE(process(dir_ / "copy", other).complete);
  expect_equal(Results(run()), Results(dir_ / "copy"));
}

TEST_F(Process, ResumeNeedsAnInterruptedProcessingAndTakesNoOptions) {
  try {
    process(run(), {}, true);
    FAIL() << "resumed nothing";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("nothing to resume"), std::string::npos) << e.what();
  }
  std::atomic<bool> stop{true};
  EXPECT_FALSE(process(run(), {}, false, &stop).complete);
  SettingsOverrides other;
  other.passes = 2;
  EXPECT_THROW(process(run(), other, true), std::runtime_error);
  const auto fresh = process(run());  // not --resume: the interrupted one is discarded
  ASSERT_TRUE(fresh.complete);
  EXPECT_NE(fresh.text.find("was discarded"), std::string::npos) << fresh.text;
}

TEST_F(Process, ASecondProcessingOfTheRunIsRefusedWhileOneRuns) {
  const auto held = storage::RunLock::try_acquire(run(), "process.lock");  // as a running `process` holds it
  ASSERT_TRUE(held);
  try {
    process(run());
    FAIL() << "two processings of one run at once";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another bosfuse is processing"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(storage::ProcessingStore(run()).unfinished_processing()) << "the refused one left nothing behind";
}

TEST_F(Process, ThePipelinedProcessingStoresWhatOneInTurnStores) {
  add_frames(run(), truth_);
  for (const bool probes_only : {false, true}) {
    SCOPED_TRACE(probes_only ? "probe mode" : "full fields");
    SettingsOverrides mode;
    mode.probes_only = probes_only;
    const auto in_turn = process_pipelined(run(), false, mode);
    ASSERT_TRUE(in_turn.complete);
    EXPECT_EQ(in_turn.frames, 6u);
    const Results sequential(run());
    EXPECT_EQ(sequential.probes.at(0).second.size(), 6u);
    EXPECT_EQ(sequential.field_files.size(), probes_only ? 0u : 12u);
    const auto pipelined = process_pipelined(run(), true, mode);
    ASSERT_TRUE(pipelined.complete);
    expect_equal(Results(run()), sequential);
    EXPECT_GT(pipelined.times.decode_s, 0) << "the decoding is accounted for";
    EXPECT_GT(pipelined.times.evaluation_s, 0);
    if (!probes_only) {
      EXPECT_GT(pipelined.times.csv_s, 0) << "the field files, written aside, are accounted for";
    }
  }
}

// A distributor in one process, for the logic of ProcessOptions::distributor
// (the MPI one, cluster/frame_farm.h, is tested under mpirun in app/): odd
// frames are evaluated by "another rank" — a context made from the plan's
// bytes alone, as a rank on another node makes it — even frames locally,
// all of them last to first; results are taken in frame order, up to the
// first that failed.
class ReversedDistributor : public FrameDistributor {
 public:
  std::size_t run(const Bytes& plan, std::size_t count, const FrameWork& local, const TakeFrame& take,
                  const std::atomic<bool>*) override {
    const FrameWork remote = planned_frame_work(plan);
    std::map<std::size_t, Bytes> done;
    std::optional<std::pair<std::size_t, std::string>> failure;
    for (std::size_t i = count; i-- > 0;) {
      try {
        done[i] = (i % 2 ? remote : local)(i);
      } catch (const std::exception& e) {
        failure.emplace(i, e.what());
      }
    }
    std::size_t taken = 0;
    for (; taken < count && (!failure || taken < failure->first); ++taken) take(taken, done.at(taken));
    if (failure) throw std::runtime_error(failure->second);
    return taken;
  }
  std::string brief_report() const override { return "reversed\n"; }
};

TEST_F(Process, ADistributedProcessingStoresWhatOneProcessStores) {
  add_frames(run(), truth_);
  for (const bool probes_only : {false, true}) {
    SCOPED_TRACE(probes_only ? "probe mode" : "full fields");
    ProcessOptions options;
    options.overrides.probes_only = probes_only;
    ASSERT_TRUE(process_run(run(), options).complete);
    const Results alone(run());
    ReversedDistributor distributor;
    options.distributor = &distributor;
    std::string notes;
    options.progress = [&](const ProcessProgress& p) {
      if (!p.frame) notes += p.line;
    };
    const auto distributed = process_run(run(), options);
    ASSERT_TRUE(distributed.complete);
    EXPECT_EQ(distributed.frames, 6u);
    // The distributor's report is a note (standard error), not the results' text.
    EXPECT_NE(notes.find("reversed"), std::string::npos) << notes;
    EXPECT_EQ(distributed.text.find("reversed"), std::string::npos) << distributed.text;
    expect_equal(Results(run()), alone);
    EXPECT_GT(distributed.times.evaluation_s, 0) << "every rank's times reach the report";
  }
}

TEST_F(Process, FramesSideBySideStoreWhatOneAtATimeStores) {
  add_frames(run(), truth_);
  for (const bool probes_only : {false, true}) {
    SCOPED_TRACE(probes_only ? "probe mode" : "full fields");
    ProcessOptions options;
    options.overrides.probes_only = probes_only;
    options.frames_at_once = 1;
    ASSERT_TRUE(process_run(run(), options).complete);
    const Results one_at_a_time(run());
    options.frames_at_once = 3;
    std::string notes;
    options.progress = [&](const ProcessProgress& p) {
      if (!p.frame) notes += p.line;
    };
    const auto side_by_side = process_run(run(), options);
    ASSERT_TRUE(side_by_side.complete);
    // How the frames were shared is a note (standard error), not the results' text (standard output).
    EXPECT_NE(notes.find("3 frames side by side"), std::string::npos) << notes;
    EXPECT_EQ(side_by_side.text.find("side by side"), std::string::npos) << side_by_side.text;
    expect_equal(Results(run()), one_at_a_time);
    // The threads share one temperature solver: every frame's field, one analysis of the Poisson system.
    EXPECT_EQ(side_by_side.temperature_fields, probes_only ? 0 : int(side_by_side.frames));
    EXPECT_EQ(side_by_side.temperature_analyses, probes_only ? 0 : 1);
  }
}

TEST_F(Process, ADistributedFrameThatFailsStopsTheProcessingAtItsFrameAndResumeCompletesIt) {
  add_frames(run(), truth_);
  ASSERT_TRUE(process(run()).complete);
  const Results alone(run());
  auto frames = storage::RunStore::open(run()).frames();
  std::erase_if(frames, [](const auto& f) { return f.is_reference; });
  std::sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });
  const fs::path fourth = run() / frames.at(3).path;  // the fourth of six in time order
  fs::rename(fourth, fourth.string() + ".away");
  ProcessOptions options;
  options.overrides.window_px = 16;  // a new processing, with the same numbers
  ReversedDistributor distributor;
  options.distributor = &distributor;
  try {
    process_run(run(), options);
    FAIL() << "a missing frame was processed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("frame " + std::to_string(frames.at(3).id)), std::string::npos) << e.what();
  }
  EXPECT_EQ(staged_frames(run()).size(), 3u) << "the three frames before it in time, not the two after";
  expect_equal(Results(run()), alone);  // the current results are untouched
  fs::rename(fourth.string() + ".away", fourth);
  options.resume = true;
  options.overrides = {};
  const auto resumed = process_run(run(), options);
  ASSERT_TRUE(resumed.complete);
  EXPECT_EQ(resumed.frames_resumed, 3u);
  expect_equal(Results(run()), alone);
}

TEST_F(Process, AnUnreadableFrameFailsAtItsOwnFrameWithTheSameMessagePipelinedOrNot) {
  const auto frames = storage::RunStore::open(run()).frames();
  const storage::FrameRecord& second = frames.back();  // the later of the two measurements
  ASSERT_FALSE(second.is_reference);
  std::ofstream(run() / second.path, std::ios::trunc) << "not a PNG";
  std::string messages[2];
  for (const bool pipelined : {false, true}) {
    try {
      process_pipelined(run(), pipelined);
      FAIL() << "an unreadable frame was processed";
    } catch (const std::runtime_error& e) {
      messages[pipelined] = e.what();
    }
    EXPECT_EQ(staged_frames(run()), std::vector<std::int64_t>{frames[1].id})
        << "the frame before the unreadable one was done, " << (pipelined ? "pipelined" : "in turn");
  }
  EXPECT_NE(messages[0].find("frame " + std::to_string(second.id) + " "), std::string::npos) << messages[0];
  EXPECT_NE(messages[0].find("unreadable image"), std::string::npos) << messages[0];
  EXPECT_EQ(messages[1], messages[0]);
  ProcessOptions negative;
  negative.prefetch_frames = -1;
  EXPECT_THROW(process_run(run(), negative), std::invalid_argument);
}

TEST(ProcessTime, FitsAreInExperimentSecondsFromTheDeclaredOriginAndScale) {
  testing::TempDir dir;
  testrun::Truth truth;
  truth.time_scale = 10;  // recorded ten times faster than it happened
  truth.origin_event = "heater off";
  testrun::create_run(dir / "run", true, truth);
  const std::int64_t heater_off_ns = truth.start_ns + 20'000'000'000;
  {
    auto store = storage::RunStore::open(dir / "run", true);
    const storage::Event marker{0, std::nullopt, heater_off_ns, "marker", "heater off"};
    store.write_events({&marker, 1});
  }
  ASSERT_TRUE(process(dir / "run").complete);
  const storage::ProcessingStore results(dir / "run");
  const auto channels = storage::RunStore::open(dir / "run").channels();
  int checked = 0;
  for (const auto& fit : results.fits()) {
    if (fit.subject != storage::FitSubject::kChannel) continue;
    const int c = fit.subject_id == channels[0].id ? 0 : 1;
    const sorted_json j = sorted_json::parse(fit.json);
    EXPECT_EQ(fit.origin_t_ns, heater_off_ns);
    EXPECT_NEAR(j.at("parameters").at("k_per_s").at("value").get<double>(), truth.k_per_s[c] / 10,
                0.02 * truth.k_per_s[c] / 10);
    // T0 is the temperature at the origin, 20 recorded seconds into the run.
    const double t0 = truth.ambient_c + (truth.t0_c[c] - truth.ambient_c) * std::exp(-truth.k_per_s[c] * 20);
    EXPECT_NEAR(j.at("parameters").at("T0_c").at("value").get<double>(), t0, 0.2);
    EXPECT_NE(j.at("time_basis").get<std::string>().find("since heater off"), std::string::npos);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

TEST(InheritSettings, ARunGetsAnotherRunsSettingsAndTheMaskTheyName) {
  testing::TempDir dir;
  testrun::Truth truth;
  testrun::create_run(dir / "a", true, truth);
  testrun::create_run(dir / "b", true, truth);
  EXPECT_FALSE(inherit_settings(dir / "a", dir / "b")) << "nothing stored yet";
  cv::imwrite((dir / "a/holder.png").string(), testrun::holder_mask(truth));
  SettingsOverrides o;
  o.mask = "holder.png";
  o.window_px = 32;
  o.step_px = 16;
  ASSERT_TRUE(process(dir / "a", o).complete);
  ASSERT_TRUE(inherit_settings(dir / "a", dir / "b"));
  EXPECT_TRUE(fs::is_regular_file(dir / "b/holder.png"));
  const auto settings = resolve_settings(dir / "b", {});
  EXPECT_EQ(settings.evaluator.xcorr.window_px, 32);
  EXPECT_EQ(settings.mask, "holder.png");
  EXPECT_NE(settings.source.find("inherited"), std::string::npos) << settings.source;
  ASSERT_TRUE(current_settings(dir / "a").contains("found_search"));
  EXPECT_FALSE(settings.evaluator.xcorr.known_search) << "another scene's search bound is not inherited";
}

}  // namespace
}  // namespace bosfuse::pipeline
