// The main job end to end, small and short: `bosfuse demo` simulates the
// experiment, records it through the real paths (at 10x), processes it and
// writes the report; the cooling rates it recovers from thermocouples and
// from BOS must match the scene's true one in experiment time. Then the run
// is read back the way a user would: `process` with no options, `report`,
// `export` + `fit`, and a `replay --speed 2` processed and reported the
// same way, and every one of them must state the same k.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "app/test_streams.h"

#include <signal.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>

#include "fitting/fit_json.h"
#include "fusion/temperature_budget.h"
#include "pipeline/geometry_config.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/browser.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::app {
namespace {

namespace fs = std::filesystem;

// Every quantity of the demo's report can be computed, so none may show as
// nan, inf or null (a reader once missed the stored limits of agreement).
void expect_every_number_present(const std::string& page, const fs::path& json_file) {
  std::string text = page;
  for (auto at = text.find("base64,"); at != std::string::npos; at = text.find("base64,", at + 7)) {
    text.erase(at + 7, text.find('"', at) - at - 7);  // images are not text
  }
  for (const char* bad : {">nan", "nan<", "[nan", "nan]", " nan ", ">inf", "inf<", "null"}) {
    EXPECT_EQ(text.find(bad), std::string::npos)
        << "report.html shows '" << bad
        << "' near: " << text.substr(text.find(bad) > 80 ? text.find(bad) - 80 : 0, 160);
  }
  nlohmann::json report;
  std::ifstream(json_file) >> report;
  std::vector<std::string> nulls;
  const std::function<void(const nlohmann::json&, const std::string&)> walk = [&](const nlohmann::json& j,
                                                                                  const std::string& path) {
    if (j.is_null()) nulls.push_back(path);
    if (j.is_number_float() && !std::isfinite(j.get<double>())) nulls.push_back(path);
    if (j.is_object()) {
      for (const auto& [key, value] : j.items()) walk(value, path + "/" + key);
    }
    if (j.is_array()) {
      for (std::size_t i = 0; i < j.size(); ++i) walk(j[i], path + "/" + std::to_string(i));
    }
  };
  walk(report, "");
  EXPECT_TRUE(nulls.empty()) << "report.json has no number at " << ::testing::PrintToString(nulls);
}

using testing::kBosfuse;

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

testing::CommandResult bosfuse(const std::string& args, int timeout_s = 120) {
  return testing::run_command(kBosfuse + " " + args, timeout_s);
}

// What a run stores, by series name: k and its interval; per pair the RMS
// temperature difference.
struct StoredRates {
  std::map<std::string, fitting::Estimate> k;
  std::map<std::string, double> rms_difference_c;
};

StoredRates stored_rates(const fs::path& run) {
  const storage::RunStore store = storage::RunStore::open(run);
  const storage::ProcessingStore results(run);
  std::map<std::int64_t, std::string> channel_names, probe_names;
  for (const auto& c : store.channels()) channel_names[c.id] = c.name;
  for (const auto& p : results.probes()) probe_names[p.id] = p.name + " (BOS)";
  StoredRates out;
  for (const auto& fit : results.fits()) {
    EXPECT_TRUE(fit.ok) << fit.json;
    const auto f = fitting::fit_from_json(nlohmann::json::parse(fit.json));
    out.k[fit.subject == storage::FitSubject::kChannel ? channel_names[fit.subject_id] : probe_names[fit.subject_id]] =
        f.k_per_s;
  }
  for (const auto& a : results.agreements()) {
    const auto agreement = fitting::agreement_from_json(nlohmann::json::parse(a.json));
    EXPECT_TRUE(agreement.series) << a.json;
    EXPECT_TRUE(agreement.curve) << a.json;
    if (agreement.series) out.rms_difference_c[channel_names[a.channel_id]] = agreement.series->rms_difference_c;
  }
  return out;
}

// The demo's experiment file states each thermocouple's simulated lag
// (0.5 s), and every stored agreement removed it.
void expect_stated_lag_removed(const fs::path& run) {
  const storage::ProcessingStore results(run);
  ASSERT_FALSE(results.agreements().empty());
  for (const auto& a : results.agreements()) {
    const auto agreement = fitting::agreement_from_json(nlohmann::json::parse(a.json));
    EXPECT_EQ(agreement.lag.source, "given") << a.json;
    EXPECT_EQ(agreement.lag.time_constant_s, 0.5) << a.json;
  }
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// report.json's summary and the page state the k of every stored fit.
void expect_report_states(const fs::path& report_dir, const StoredRates& stored) {
  const auto json = nlohmann::json::parse(read_text(report_dir / "report.json"));
  const std::string page = read_text(report_dir / "report.html");
  std::size_t found = 0;
  for (const auto& row : json.at("summary").at("series")) {
    const std::string name = row.at("name");
    ASSERT_TRUE(stored.k.count(name)) << name;
    const double k = row.at("k").at("value").get<double>();
    EXPECT_EQ(k, stored.k.at(name).value) << name << ": report.json states another k than the stored fit";
    EXPECT_NE(page.find(fmt::format("{:.4g}", k)), std::string::npos) << name << ": k not on the page";
    ++found;
  }
  EXPECT_EQ(found, stored.k.size());
  EXPECT_NE(json.at("time_basis").get<std::string>().find("experiment seconds since heater off"), std::string::npos);
}

// The simulated devices run on one clock from the heater-off marker: each
// frame is stamped at the experiment time of the scene it shows (its
// device time), to within a frame's own capture (the stamp is taken right
// after the scene time). Each device's own start put the frames 0.45 to 5
// experiment seconds late, which read as a T0 difference (issue 29).
void expect_frames_stamped_at_their_scene_time(const fs::path& run) {
  const auto store = storage::RunStore::open(run);
  const auto info = store.run();
  std::size_t checked = 0;
  for (const auto& frame : store.frames()) {
    if (frame.is_reference || !frame.device_t_ns) continue;
    const double stamped_s = static_cast<double>(frame.t_ns - info.started_ns) * 1e-9 * info.time_scale;
    const double shown_s = static_cast<double>(*frame.device_t_ns) * 1e-9;
    EXPECT_NEAR(stamped_s, shown_s, 0.05) << "frame " << frame.id;
    ++checked;
  }
  EXPECT_GT(checked, 10u);
}

// The demo's experiment file states a well-equipped lab's Type-B
// uncertainties, each smaller than the defaults' quick set-up.
void expect_a_labs_uncertainty_stated(const fs::path& run) {
  const auto config = pipeline::parse_geometry_config(storage::RunStore::open(run).run().config_toml, "run config");
  ASSERT_TRUE(config.has_value());
  const fusion::TypeBUncertainties defaults;
  const auto& u = config->uncertainty;
  EXPECT_LT(u.depth_relative, defaults.depth_relative);
  EXPECT_LT(u.z_d_relative, defaults.z_d_relative);
  EXPECT_LT(u.magnification_relative, defaults.magnification_relative);
  EXPECT_LT(u.ambient_pressure_pa, defaults.ambient_pressure_pa);
  EXPECT_LT(u.ambient_temperature_c, defaults.ambient_temperature_c);
  EXPECT_LT(u.gladstone_dale_relative, defaults.gladstone_dale_relative);
}

TEST(DemoCli, EveryCommandStatesTheSameCoolingRateInExperimentTime) {
  testing::TempDir dir;
  // One background and noise draw, so that the test checks a reproducible
  // scene: from pattern to pattern the probes' k spreads by a few percent
  // (docs/RELIABILITY.md), which a new draw per run would turn into a test
  // that fails now and then rather than one that finds a change.
  const auto demo = bosfuse("demo --out " + quoted(dir / "demo") + " --experiment-time 150s --speed 10 --seed 1");
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  ASSERT_EQ(std::distance(fs::directory_iterator(dir / "demo"), fs::directory_iterator()), 1);
  const fs::path run = fs::directory_iterator(dir / "demo")->path();
  EXPECT_NE(demo.output.find((run / "report/report.html").string()), std::string::npos) << demo.output;

  // 1. The demo itself: every fit within 5% of the true rate, in experiment time.
  nlohmann::json truth;
  std::ifstream(run / "demo-truth.json") >> truth;
  const double true_k = truth["plume_k_per_s"];
  const StoredRates by_demo = stored_rates(run);
  ASSERT_EQ(by_demo.k.size(), 4u) << "two thermocouples, two BOS probes";
  ASSERT_EQ(by_demo.rms_difference_c.size(), 2u);
  for (const auto& [name, k] : by_demo.k) EXPECT_NEAR(k.value, true_k, 0.05 * true_k) << name;
  for (const auto& [name, rms] : by_demo.rms_difference_c) EXPECT_LT(rms, 0.5) << name;
  expect_report_states(run / "report", by_demo);
  expect_stated_lag_removed(run);
  expect_frames_stamped_at_their_scene_time(run);
  expect_a_labs_uncertainty_stated(run);
  expect_every_number_present(read_text(run / "report/report.html"), run / "report/report.json");

  // 2. `process` with no options repeats the demo (its stored settings), `report` states it.
  const auto again = bosfuse("process " + quoted(run));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("settings from the run's stored settings"), std::string::npos) << again.output;
  const StoredRates reprocessed = stored_rates(run);
  for (const auto& [name, k] : by_demo.k) EXPECT_EQ(reprocessed.k.at(name).value, k.value) << name;
  EXPECT_EQ(reprocessed.rms_difference_c, by_demo.rms_difference_c);
  ASSERT_EQ(bosfuse("report " + quoted(run) + " -o " + quoted(dir / "report")).exit_code, 0);
  expect_report_states(dir / "report", reprocessed);

  // 3. export + fit on the thermocouple's column: the stored fit's k.
  const auto csv = dir / "samples.csv";
  ASSERT_EQ(bosfuse("export " + quoted(run) + " --csv -o " + quoted(csv)).exit_code, 0);
  const auto fitted =
      bosfuse("fit " + quoted(csv) + " --temperature-column 'tc-35mm [degC]' --json " + quoted(dir / "fit.json"));
  ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
  const auto exported_fit = fitting::fit_from_json(nlohmann::json::parse(read_text(dir / "fit.json")));
  const auto& stored_tc = by_demo.k.at("tc-35mm");
  // The export prints each reading at its channel's resolution (the
  // module's 0.021 °C step: two decimals, q = 0.01 °C). Rounding adds
  // independent noise of SD q/√12 to every reading, which moves k by about
  // std_error × (q/√12)/s, s the residual SD; three of those bound it.
  const double rounding_sd_c = 0.01 / std::sqrt(12.0);
  const double k_shift_sd = stored_tc.std_error * rounding_sd_c / exported_fit.summary.residual_std_c;
  EXPECT_NEAR(exported_fit.k_per_s.value, stored_tc.value, 3.0 * k_shift_sd)
      << "export + fit and the stored fit disagree on one series (residual SD "
      << exported_fit.summary.residual_std_c << " °C)";

  // 4. A replay at 2x (so 20x in all) processed with no options: the same
  //    experiment.
  const fs::path replay = dir / "replay";
  const auto replayed = bosfuse("replay " + quoted(run) + " -o " + quoted(replay) + " --speed 2");
  ASSERT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_DOUBLE_EQ(storage::RunStore::open(replay).run().time_scale, 20.0);
  const auto processed = bosfuse("process " + quoted(replay));
  ASSERT_EQ(processed.exit_code, 0) << processed.output;
  EXPECT_NE(processed.output.find("inherited from the recorded run"), std::string::npos) << processed.output;
  const StoredRates by_replay = stored_rates(replay);
  // Every sample and frame of the replay is stamped with its recorded time
  // (sim/replay.h), so the thermocouples, the BOS probes and their pairs are
  // the demo's: the same k, and the same RMS difference, to the float32
  // rounding of the replayed values. Stamped by the host clock, the
  // thermocouples' k had come out up to 3.2% high and the RMS 0.11 °C off.
  for (const auto& [name, k] : by_demo.k) {
    ASSERT_TRUE(by_replay.k.count(name)) << name;
    EXPECT_NEAR(by_replay.k.at(name).value, k.value, 2e-3 * k.value) << name;
  }
  for (const auto& [name, rms] : by_demo.rms_difference_c) {
    EXPECT_NEAR(by_replay.rms_difference_c.at(name), rms, 0.01) << name;
  }
  ASSERT_EQ(bosfuse("report " + quoted(replay) + " -o " + quoted(dir / "replay-report")).exit_code, 0);
  expect_report_states(dir / "replay-report", by_replay);

  // 5. And a real browser draws every figure of the demo's report.
  const std::string page = read_text(run / "report/report.html");
  std::size_t figures = 0;
  for (auto at = page.find("src=\"data:image/png;base64,"); at != std::string::npos;
       at = page.find("src=\"data:image/png;base64,", at + 1)) {
    ++figures;
  }
  EXPECT_GE(figures, 4u);
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  const auto images = testing::render_check(page, run / "report/render-check.html", dir.path());
  EXPECT_EQ(images.size(), figures);
  for (const auto& image : images) {
    EXPECT_TRUE(image.complete);
    EXPECT_NE(image.size, "0x0");
    EXPECT_GT(image.spread, 100);
  }
  EXPECT_EQ(storage::RunStore::open(run).run().status, storage::RunStatus::kComplete);
}

// A demo too short for a BOS fit says so before it records, and its table
// keeps the probes' labels with a dash and the reason, never "nan".
TEST(DemoCli, ADemoTooShortForBosFitsWarnsAndItsTableSaysWhy) {
  testing::TempDir dir;
  const auto demo = bosfuse("demo --out " + quoted(dir / "demo") + " --experiment-time 30s --speed 16 --seed 2");
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_NE(demo.output.find("gives 3 frame(s) after the reference, and a BOS fit needs at least 4"),
            std::string::npos)
      << demo.output;
  EXPECT_NE(demo.output.find("--experiment-time 40s or more"), std::string::npos) << demo.output;
  for (const char* probe : {"BOS tc-35mm", "BOS tc-45mm"}) {
    const auto line = demo.output.find(std::string("  ") + probe);
    ASSERT_NE(line, std::string::npos) << "the table lost the label " << probe << ": " << demo.output;
    const std::string text = demo.output.substr(line, demo.output.find('\n', line) - line);
    EXPECT_NE(text.find("k = — (no fit: "), std::string::npos) << text;
  }
  EXPECT_FALSE(std::regex_search(demo.output, std::regex("\\bnan\\b"))) << demo.output;
}

// Standard output is the demo's result only (issue 31): the table of rates
// beside the truth and where the run and its report are; the recording's
// summary and the progress are on stderr.
TEST(DemoCli, StandardOutputHoldsTheResultTableOnly) {
  testing::TempDir dir;
  const auto demo = testing::run_with_streams(
      kBosfuse + " demo --out " + quoted(dir / "demo") + " --experiment-time 30s --speed 16 --seed 2", dir.path(), 300);
  ASSERT_EQ(demo.exit_code, 0) << demo.err;
  EXPECT_TRUE(demo.out.starts_with("cooling rate of the plume at the thermocouples, true: k = ")) << demo.out;
  EXPECT_NE(demo.out.find("\nreport:  "), std::string::npos) << demo.out;
  for (const std::string& line : {std::string("samples"), std::string("run store")}) {
    EXPECT_EQ(demo.out.find(line), std::string::npos) << line << " on stdout: " << demo.out;
  }
  EXPECT_EQ(demo.out.find("warning"), std::string::npos) << demo.out;
  EXPECT_NE(demo.err.find("a BOS fit needs at least 4"), std::string::npos) << demo.err;
}

TEST(DemoCli, CtrlCStopsTheDemoPromptlyWithTheRunRecordedSoFar) {
  testing::TempDir dir;
  testing::BackgroundProcess demo(
      {kBosfuse, "demo", "--out", (dir / "demo").string(), "--experiment-time", "10m", "--speed", "10"});
  const auto has_samples = [&] {
    if (!fs::is_directory(dir / "demo") || fs::directory_iterator(dir / "demo") == fs::directory_iterator()) {
      return false;
    }
    const fs::path run = fs::directory_iterator(dir / "demo")->path();
    try {
      return storage::RunStore::holds_run(run) && storage::RunStore::open(run).first_sample_ns().has_value();
    } catch (const std::exception&) {
      return false;  // being created
    }
  };
  ASSERT_TRUE(testing::wait_for(has_samples, std::chrono::seconds(30)));
  const auto interrupted = std::chrono::steady_clock::now();
  demo.send_signal(SIGINT);
  EXPECT_EQ(demo.wait_exit(std::chrono::seconds(10)), 5) << "kExitStopped";
  EXPECT_LT(std::chrono::steady_clock::now() - interrupted, std::chrono::seconds(3)) << "not prompt";
  const fs::path run = fs::directory_iterator(dir / "demo")->path();
  const auto store = storage::RunStore::open(run);
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete) << "the logger closed the run cleanly";
  EXPECT_TRUE(store.first_sample_ns().has_value());
}

}  // namespace
}  // namespace bosfuse::app
