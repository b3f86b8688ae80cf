// `bosfuse mark` after the run (issue 31, item 2): a finished run refuses a
// marker "now" and shows --at; --at a UTC time or a time from the first
// sample moves t = 0 there for a run whose origin names the marker, and
// what is read afterwards (the export, a fit of it, `runs`) counts from it.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "app/test_streams.h"
#include "report/test_readers.h"
#include "sim/cooling_signal.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/synthetic_run.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using report::testreaders::sh_quoted;
using json = nlohmann::json;

using testing::kBosfuse;
constexpr int kValidationError = 105;  // CLI11's code for a value it refuses

class MarkCli : public ::testing::Test {
 protected:
  void SetUp() override {
    truth_.origin_event = "heater off";
    truth_.time_scale = 2;  // experiment seconds per recorded second
    testrun::create_run(run(), false, truth_);
  }
  fs::path run() const { return dir_ / "run"; }
  testing::StreamsResult bosfuse(const std::string& args) {
    return testing::run_with_streams(kBosfuse + " " + args, dir_.path(), 60);
  }
  std::size_t markers() const {
    std::size_t n = 0;
    for (const auto& e : storage::RunStore::open(run()).events()) n += e.kind == "marker";
    return n;
  }
  // The first t_s of the run's CSV export.
  double first_exported_t_s() {
    const auto exported = bosfuse("export " + sh_quoted(run()) + " --csv -o -");
    EXPECT_EQ(exported.exit_code, 0) << exported.err;
    const std::string row = exported.out.substr(exported.out.find('\n') + 1);
    const std::string t_s = row.substr(row.find(',') + 1);
    return std::stod(t_s.substr(0, t_s.find(',')));
  }

  testing::TempDir dir_;
  testrun::Truth truth_;
};

TEST_F(MarkCli, AFinishedRunRefusesAMarkerNowAndShowsAt) {
  const auto refused = bosfuse("mark " + sh_quoted(run()) + " 'heater off'");
  EXPECT_EQ(refused.exit_code, kValidationError) << refused.err;
  EXPECT_NE(refused.err.find("a marker made now would lie after everything it recorded"), std::string::npos)
      << refused.err;
  EXPECT_NE(refused.err.find("--at 2026-12-01T18:11:29.5Z (UTC) or --at +12.5s"), std::string::npos) << refused.err;
  EXPECT_EQ(markers(), 0u) << "a refused marker was written";
}

TEST_F(MarkCli, AtATimeFromTheFirstSampleMovesTheOriginAndAFitCountsFromIt) {
  EXPECT_DOUBLE_EQ(first_exported_t_s(), 0.0) << "without a marker t = 0 is the first sample";
  const auto marked = bosfuse("mark " + sh_quoted(run()) + " 'heater off' --at +50s");
  ASSERT_EQ(marked.exit_code, 0) << marked.err;
  EXPECT_NE(marked.err.find("this is the run's declared origin"), std::string::npos) << marked.err;
  // +50 s of experiment time is 25 s of a record made at 2×.
  const auto clock = storage::experiment_clock(storage::RunStore::open(run()));
  EXPECT_EQ(clock.origin_ns, truth_.start_ns + 25'000'000'000);
  EXPECT_NEAR(first_exported_t_s(), -50.0, 1e-6);

  const auto fit = bosfuse("export " + sh_quoted(run()) + " --csv -o - | " + kBosfuse +
                           " fit - --temperature-column 'tc0 [degC]' --json -");
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const json p = json::parse(fit.out).at("parameters");
  // The curve at t = 0 is the record's at 25 s; k is per experiment second.
  const double k = truth_.k_per_s[0] / truth_.time_scale;
  const double t0 = truth_.ambient_c + (truth_.t0_c[0] - truth_.ambient_c) * std::exp(-truth_.k_per_s[0] * 25);
  EXPECT_NEAR(p.at("k_per_s").at("value").get<double>(), k, 4 * p.at("k_per_s").at("std_error").get<double>());
  EXPECT_NEAR(p.at("T0_c").at("value").get<double>(), t0, 4 * p.at("T0_c").at("std_error").get<double>());

  const auto runs = bosfuse("runs " + sh_quoted(run()));
  ASSERT_EQ(runs.exit_code, 0) << runs.err;
  EXPECT_NE(runs.out.find("marker                  heater off  (t = 0, the run's origin)"), std::string::npos)
      << runs.out;
}

TEST_F(MarkCli, AtAUtcTimeMovesTheOriginThereAndALaterMarkerLeavesIt) {
  const std::string at = storage::format_iso8601_utc(truth_.start_ns + 10'000'000'000, 3);
  ASSERT_EQ(bosfuse("mark " + sh_quoted(run()) + " 'heater off' --at " + at).exit_code, 0);
  EXPECT_NEAR(first_exported_t_s(), -20.0, 1e-6) << "10 s of the record at 2×";
  const auto later = bosfuse("mark " + sh_quoted(run()) + " 'heater off' --at +60s");
  ASSERT_EQ(later.exit_code, 0) << later.err;
  EXPECT_NE(later.err.find("the run's origin stays at the earlier \"heater off\" marker (" + at + ")"),
            std::string::npos)
      << later.err;
  EXPECT_NEAR(first_exported_t_s(), -20.0, 1e-6);
  const auto runs = bosfuse("runs " + sh_quoted(run()));
  EXPECT_NE(runs.out.find("heater off  (t = 40.000 s)"), std::string::npos) << runs.out;
  EXPECT_EQ(markers(), 2u);
}

TEST_F(MarkCli, AnUnreadableTimeOrOneOutsideTheRecordIsSaid) {
  const auto unreadable = bosfuse("mark " + sh_quoted(run()) + " 'heater off' --at yesterday");
  EXPECT_EQ(unreadable.exit_code, kValidationError) << unreadable.err;
  EXPECT_NE(unreadable.err.find("'yesterday' is not a time of the run"), std::string::npos) << unreadable.err;
  EXPECT_EQ(markers(), 0u);
  const std::string before = storage::format_iso8601_utc(truth_.start_ns - 5'000'000'000, 1);
  const auto early = bosfuse("mark " + sh_quoted(run()) + " 'heater off' --at " + before);
  ASSERT_EQ(early.exit_code, 0) << early.err;
  EXPECT_NE(early.err.find("warning: the marker lies 5.000 s (host clock) before the run's first sample"),
            std::string::npos)
      << early.err;
}

// Issue 31, item 2: --estimate proposes the heater-off time from the knee
// of the simulator's curves (sim/cooling_signal.h, heated for 120 s, then
// cooling), recorded at 2×, and writes nothing. The stated tolerance: one
// sample interval (1 s of experiment time), and within 4σ of its own σ.
TEST(MarkEstimateCli, ProposesTheSimulatedHeaterOffTimeWithoutWriting) {
  testing::TempDir dir;
  const fs::path run = dir / "heated";
  constexpr double kHeaterOffS = 120;  // experiment seconds after the first sample
  constexpr double kTimeScale = 2;
  constexpr std::int64_t kStartNs = 1'795'000'000'000'000'000;
  {
    storage::RunInfo info{0, "heated", kStartNs, std::nullopt, "", storage::RunStatus::kRunning, kTimeScale,
                          "heater off"};
    auto store = storage::RunStore::create(run, info, storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "sim", "modbus-tcp", "adam-6018", "127.0.0.1:1502"});
    for (int c = 0; c < 2; ++c) {
      sim::CoolingSignal signal{22.0, 80.0 - 10 * c, 0.01 + 0.005 * c, 0.05, 7, kHeaterOffS};
      const auto channel = store.add_channel({0, device, "tc" + std::to_string(c), "thermocouple", "degC", "K", {}, {}});
      std::vector<storage::Sample> samples;
      for (int i = 0; i < 400; ++i) {  // one per experiment second
        storage::Sample s;
        s.channel_id = channel;
        s.t_ns = kStartNs + static_cast<std::int64_t>(i * 1e9 / kTimeScale);
        s.value = signal.sample_c(i, c, static_cast<std::uint64_t>(i));
        samples.push_back(s);
      }
      store.write_samples(samples);
    }
    store.finish(storage::RunStatus::kComplete, kStartNs + 200'000'000'000);
  }
  const auto proposed = testing::run_with_streams(kBosfuse + " mark " + sh_quoted(run) + " 'heater off' --estimate",
                                                  dir.path(), 60);
  ASSERT_EQ(proposed.exit_code, 0) << proposed.err;
  ASSERT_EQ(proposed.out.front(), '+') << proposed.out;
  const double at_s = std::stod(proposed.out.substr(1));
  EXPECT_EQ(proposed.out, proposed.out.substr(0, proposed.out.find('s')) + "s\n") << "only the --at value on stdout";
  EXPECT_NEAR(at_s, kHeaterOffS, 1.0) << proposed.err;
  EXPECT_NE(proposed.err.find("heater off proposed at +"), std::string::npos) << proposed.err;
  EXPECT_NE(proposed.err.find("nothing written; accept it with: bosfuse mark"), std::string::npos) << proposed.err;
  EXPECT_NE(proposed.err.find("tc1: knee at +"), std::string::npos) << proposed.err;
  const auto store = storage::RunStore::open(run);
  EXPECT_TRUE(store.events().empty()) << "--estimate wrote an event";

  // Accepted, the proposal is the origin.
  const auto accepted = testing::run_with_streams(
      kBosfuse + " mark " + sh_quoted(run) + " 'heater off' --at " + proposed.out.substr(0, proposed.out.size() - 1),
      dir.path(), 60);
  ASSERT_EQ(accepted.exit_code, 0) << accepted.err;
  EXPECT_NEAR(static_cast<double>(storage::experiment_clock(storage::RunStore::open(run)).origin_ns - kStartNs) *
                  1e-9 * kTimeScale,
              kHeaterOffS, 1.0);
}

TEST_F(MarkCli, EstimateSaysWhyACurveThatOnlyCoolsHasNoKnee) {
  const auto refused = bosfuse("mark " + sh_quoted(run()) + " 'heater off' --estimate");
  EXPECT_EQ(refused.exit_code, 1) << refused.err;
  EXPECT_NE(refused.err.find("tc0: no knee (the curve falls from its first sample: the heater was off before)"),
            std::string::npos)
      << refused.err;
  EXPECT_EQ(refused.out, "");
  EXPECT_EQ(markers(), 0u);
  const auto both = bosfuse("mark " + sh_quoted(run()) + " 'heater off' --estimate --at +3s");
  EXPECT_EQ(both.exit_code, 108) << both.err;  // CLI11's ExcludesError
}

}  // namespace
}  // namespace bosfuse
