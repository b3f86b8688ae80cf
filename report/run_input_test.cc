#include "report/run_input.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <opencv2/imgcodecs.hpp>

#include "pipeline/field_csv.h"
#include "report/report.h"
#include "pipeline/process.h"
#include "tests/support/synthetic_run.h"
#include "storage/database.h"
#include "storage/processing_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

double max_unmasked(const MapField& map) {
  double high = 0;
  for (int r = 0; r < map.values.rows; ++r) {
    for (int c = 0; c < map.values.cols; ++c) {
      if (!map.mask.at<std::uint8_t>(r, c)) high = std::max(high, map.values.at<double>(r, c));
    }
  }
  return high;
}

std::string all_notes(const ReportInput& input) {
  std::string notes;
  for (const auto& n : input.notes) notes += n + "\n";
  return notes + input.displacement_maps_note;
}

pipeline::ProcessReport process(const std::filesystem::path& run, pipeline::SettingsOverrides overrides = {}) {
  pipeline::ProcessOptions options;
  options.overrides = std::move(overrides);
  return pipeline::process_run(run, options);
}

TEST(RunInput, ARunNotProcessedShowsItsSamplesWithoutFitsAndSaysToProcessIt) {
  testing::TempDir dir;
  const testrun::Truth truth;
  testrun::create_run(dir / "run", false, truth);
  const auto input = build_report_input(storage::RunStore::open(dir / "run"));
  EXPECT_EQ(input.run_name, "synthetic cooling");
  EXPECT_EQ(input.status, "complete");
  ASSERT_EQ(input.series.size(), 2u);
  for (int c = 0; c < 2; ++c) {
    const auto& s = input.series[c];
    EXPECT_EQ(s.name, "tc" + std::to_string(c));
    EXPECT_EQ(s.excluded_samples, static_cast<std::size_t>(truth.bad_samples));
    EXPECT_EQ(s.time_s.size() + s.excluded_samples, static_cast<std::size_t>(truth.samples));
    EXPECT_FALSE(s.fit) << "the report never fits on its own";
  }
  EXPECT_DOUBLE_EQ(input.series[0].time_s.front(), 0.0) << "experiment time from the run's first sample";
  EXPECT_NE(input.time_basis.find("experiment seconds since the first sample"), std::string::npos)
      << input.time_basis;
  EXPECT_NE(all_notes(input).find("not processed yet"), std::string::npos) << all_notes(input);
  EXPECT_NE(all_notes(input).find("bosfuse process"), std::string::npos);
  EXPECT_EQ(input.thermocouples_only, "the run has no frames") << "the report's BOS sections are left out";
  EXPECT_FALSE(input.quality);
}

TEST(RunInput, AProcessedRunIsReadFromWhatProcessStoredWithoutItsFrames) {
  testing::TempDir dir;
  const testrun::Truth truth;
  testrun::create_run(dir / "run", true, truth);
  ASSERT_TRUE(process(dir / "run").complete);
  std::filesystem::remove_all(dir / "run/frames");  // the report must not need them
  RunReportOptions options;
  options.map_times_s = {12, 50, 1000};  // 50 and 1000 both pick the frame at 60 s: one map
  options.px_per_mm = 30;
  const auto input = build_report_input(storage::RunStore::open(dir / "run"), options);
  ASSERT_EQ(input.series.size(), 4u) << "two thermocouples, two BOS probes";
  for (int c = 0; c < 2; ++c) {
    const auto& s = input.series[c];
    ASSERT_TRUE(s.fit && s.fit->ok()) << (s.fit ? s.fit->summary.message : "no stored fit");
    EXPECT_NEAR(s.fit->k_per_s.value, truth.k_per_s[c], 0.02 * truth.k_per_s[c]);
    EXPECT_DOUBLE_EQ(s.fit->origin_s, 0.0) << "stored fits have t = 0 at the run's origin";
    EXPECT_NEAR(s.fit->t0_c.value, truth.t0_c[c], 0.2);
  }
  EXPECT_TRUE(input.has_probes());
  ASSERT_EQ(input.displacement_maps.size(), 2u);
  ASSERT_EQ(input.temperature_maps.size(), 2u);
  for (int f = 0; f < 2; ++f) {
    const auto& map = input.displacement_maps[f];
    ASSERT_TRUE(map.time_s.has_value());
    EXPECT_NEAR(*map.time_s, truth.frame_times_s[f], 0.01);
    EXPECT_EQ(map.image_size_px, truth.image);
    EXPECT_DOUBLE_EQ(map.step_px, 8);
    // The window-averaged peak of |shift| is a little below the true peak.
    EXPECT_NEAR(max_unmasked(map), truth.frame_peak_px[f], 0.2 * truth.frame_peak_px[f]) << "frame " << f;
    EXPECT_NE(map.source.find("stored displacement field"), std::string::npos) << map.source;
  }
  ASSERT_TRUE(input.quality) << "stored by process";
  EXPECT_GT(input.quality->index.q_mod, 0.9) << "same pattern, same exposure";
  EXPECT_EQ(input.px_per_mm, 30.0);
  EXPECT_NE(all_notes(input).find("Processed on"), std::string::npos) << all_notes(input);
  EXPECT_NE(all_notes(input).find("full fields, cross-correlation, window 16 px, step 8 px"), std::string::npos);
}

// The uncertainty section from what `process` stored: every probe's
// samples carry σ, the budget is the processing's at the hottest sample;
// the same run with its σ gone (as processed before schema version 5)
// says so instead of showing numbers.
TEST(RunInput, TheUncertaintySectionIsWhatProcessStored) {
  testing::TempDir dir;
  testrun::create_run(dir / "run", true);
  ASSERT_TRUE(process(dir / "run").complete);
  const auto input = build_report_input(storage::RunStore::open(dir / "run"));
  const auto& u = input.uncertainty;
  ASSERT_EQ(u.probes.size(), 2u);
  for (const auto& p : u.probes) {
    EXPECT_EQ(p.samples, 2u) << p.probe;
    EXPECT_EQ(p.samples_with_sigma, 2u) << p.probe;
    EXPECT_GT(p.median_random_c, 0) << p.probe;
    EXPECT_TRUE(p.median_systematic_c) << p.probe;
  }
  ASSERT_TRUE(u.budget);
  ASSERT_EQ(u.budget->components.size(), 7u) << "the set-up's six and the window-average correction's";
  EXPECT_EQ(u.budget->components.back().quantity, "window-average correction (curvature)");
  EXPECT_NE(u.budget_basis.find("the hottest BOS probe sample"), std::string::npos) << u.budget_basis;
  EXPECT_NE(u.budget_basis.find("includes the window-average correction"), std::string::npos) << u.budget_basis;
  {
    // The table is the hottest sample's own budget: its combined σ is the
    // sample's stored systematic σ, the correction's σ included.
    const storage::ProcessingStore results(dir / "run");
    std::optional<storage::ProbeSampleRecord> hottest;
    for (const auto& probe : results.probes()) {
      for (const auto& s : results.probe_samples(probe.id)) {
        if (s.temperature_c && s.sigma_systematic_c && (!hottest || *s.temperature_c > *hottest->temperature_c))
          hottest = s;
      }
    }
    ASSERT_TRUE(hottest);
    EXPECT_NEAR(u.budget->combined_c, *hottest->sigma_systematic_c, 1e-9 * *hottest->sigma_systematic_c);
  }
  EXPECT_TRUE(u.notes.empty());
  const auto files = write_report(input, {}, dir / "out");
  std::ifstream page(files.html);
  const std::string html((std::istreambuf_iterator<char>(page)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("<h2 id=\"uncertainty\">Uncertainty of the BOS temperatures</h2>"), std::string::npos);
  EXPECT_NE(html.find("<h3>Type-B budget of a BOS temperature</h3>"), std::string::npos);
  EXPECT_NE(html.find("<h3>Random uncertainty of each probe</h3>"), std::string::npos);
  {
    storage::Database db((dir / "run" / storage::RunStore::kDatabaseFileName).string(),
                         storage::Database::Mode::kReadWrite);
    db.execute("UPDATE probe_samples SET sigma_u_px = NULL, sigma_v_px = NULL, sigma_shift_px = NULL, "
               "sigma_random_c = NULL, sigma_systematic_c = NULL");
  }
  const auto old = build_report_input(storage::RunStore::open(dir / "run")).uncertainty;
  EXPECT_FALSE(old.budget);
  ASSERT_EQ(old.notes.size(), 1u);
  EXPECT_NE(old.notes[0].find("carry no uncertainty"), std::string::npos);
}

// The synthetic run, processed with its holder under the mask.
void process_with_the_holder_masked(const std::filesystem::path& run, const testrun::Truth& truth) {
  testrun::create_run(run, true, truth);
  cv::imwrite((run / "holder.png").string(), testrun::holder_mask(truth));
  pipeline::SettingsOverrides overrides;
  overrides.mask = "holder.png";
  ASSERT_TRUE(process(run, overrides).complete);
}

TEST(RunInput, TheStoredMaskShowsAsMaskedCellsInTheMaps) {
  testing::TempDir dir;
  const testrun::Truth truth;
  ASSERT_NO_FATAL_FAILURE(process_with_the_holder_masked(dir / "run", truth));
  RunReportOptions options;
  options.map_times_s = {10};
  const auto input = build_report_input(storage::RunStore::open(dir / "run"), options);
  ASSERT_EQ(input.displacement_maps.size(), 1u);
  const auto& map = input.displacement_maps[0];
  int masked_inside = 0, masked_outside = 0;
  for (int r = 0; r < map.values.rows; ++r) {
    for (int c = 0; c < map.values.cols; ++c) {
      const cv::Point centre(static_cast<int>(map.x0_px + c * map.step_px),
                             static_cast<int>(map.y0_px + r * map.step_px));
      const bool masked = map.mask.at<std::uint8_t>(r, c) != 0;
      (truth.holder_px.contains(centre) ? masked_inside : masked_outside) += masked;
    }
  }
  EXPECT_GT(masked_inside, 10);
  EXPECT_EQ(masked_outside, 0) << "only the holder is masked on this textured pattern";
}

// Issue 29: the solve fills the masked heater harmonically (TemperatureField
// ::measured 0) and the report drew those values as if measured, with
// `masked` 0 in its CSV. They are NaN and flagged in the map and its CSV.
TEST(RunInput, AHeaterFilledInByTheSolveIsNotMeasuredInTheTemperatureMapOrItsCsv) {
  testing::TempDir dir;
  const testrun::Truth truth;
  ASSERT_NO_FATAL_FAILURE(process_with_the_holder_masked(dir / "run", truth));
  RunReportOptions options;
  options.map_times_s = {10};
  const auto store = storage::RunStore::open(dir / "run");
  const auto input = build_report_input(store, options);
  ASSERT_EQ(input.temperature_maps.size(), 1u);
  const MapField& map = input.temperature_maps[0];

  // What the solve stored: finite temperatures it filled in under the holder.
  const storage::ProcessingStore results(dir / "run");
  std::optional<pipeline::StoredFieldGrid> stored;
  for (const auto& f : results.fields()) {
    if (f.kind == "temperature" && map.source.find(f.path) != std::string::npos) {
      stored = pipeline::read_stored_field(dir / "run" / f.path, pipeline::kTemperatureColumns);
    }
  }
  ASSERT_TRUE(stored) << map.source;
  ASSERT_EQ(stored->rows(), map.values.rows);
  ASSERT_EQ(stored->cols(), map.values.cols);
  int filled_under_holder = 0, measured_shown = 0, not_measured = 0;
  for (int r = 0; r < map.values.rows; ++r) {
    for (int c = 0; c < map.values.cols; ++c) {
      const double t = stored->column("temperature_c").at<double>(r, c);
      const bool measured = stored->column("measured").at<double>(r, c) == 1 && std::isfinite(t);
      const cv::Point node(static_cast<int>(stored->x_px[c]), static_cast<int>(stored->y_px[r]));
      filled_under_holder += truth.holder_px.contains(node) && !measured && std::isfinite(t);
      if (measured) {
        EXPECT_EQ(map.mask.at<std::uint8_t>(r, c), 0) << r << "," << c;
        EXPECT_EQ(map.values.at<double>(r, c), t);
        ++measured_shown;
      } else {
        EXPECT_NE(map.mask.at<std::uint8_t>(r, c), 0) << "filled in, shown as measured at " << r << "," << c;
        EXPECT_TRUE(std::isnan(map.values.at<double>(r, c))) << r << "," << c;
        ++not_measured;
      }
    }
  }
  EXPECT_GT(filled_under_holder, 10) << "the solve fills the heater: the case this test is about";
  EXPECT_GT(measured_shown, 100);

  // The report's CSV of that map says the same: `nan` and masked 1 there, and nowhere else.
  const auto files = write_report(input, {}, dir / "report");
  EXPECT_TRUE(std::filesystem::exists(files.html));
  std::optional<std::filesystem::path> csv;
  for (const auto& e : std::filesystem::directory_iterator(dir / "report")) {
    const std::string name = e.path().filename().string();
    if (name.starts_with("map_temperature_") && name.ends_with(".csv")) csv = e.path();
  }
  ASSERT_TRUE(csv) << "no map_temperature_*.csv";
  std::ifstream in(*csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "x_px,y_px,x_mm,y_mm,value,masked");
  int rows = 0, flagged = 0, flagged_under_holder = 0;
  while (std::getline(in, line) && rows < 1'000'000) {
    ++rows;
    std::vector<std::string> cells;
    std::stringstream split(line);
    for (std::string cell; std::getline(split, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 6u) << line;
    const bool masked = cells[5] == "1";
    EXPECT_EQ(masked, cells[4] == "nan") << line;
    flagged += masked;
    const cv::Point node(static_cast<int>(std::stod(cells[0])), static_cast<int>(std::stod(cells[1])));
    flagged_under_holder += masked && truth.holder_px.contains(node);
  }
  EXPECT_EQ(rows, map.values.rows * map.values.cols);
  EXPECT_EQ(flagged, not_measured);
  EXPECT_GE(flagged_under_holder, filled_under_holder);
}

TEST(RunInput, AStoredFieldPathLeadingOutOfTheRunIsRefusedByName) {
  testing::TempDir dir;
  testrun::create_run(dir / "run", true);
  std::ofstream(dir / "outside.csv")
      << "x,y,temperature_c,measured,sigma_c\n8.0,8.0,30.5,1,0.01\n16.0,8.0,25.0,1,0.01\n";
  {
    const auto frames = storage::RunStore::open(dir / "run").frames();
    storage::ProcessingStore results(dir / "run", true);
    results.add_field({0, frames[2].id, "temperature", "../outside.csv", "{}"});
    results.add_field({0, frames[1].id, "temperature", "/etc/passwd", "{}"});
  }
  RunReportOptions options;
  options.map_times_s = {10, 60};
  const auto input = build_report_input(storage::RunStore::open(dir / "run"), options);
  EXPECT_TRUE(input.temperature_maps.empty()) << "a field file outside the run was read";
  const std::string notes = all_notes(input);
  EXPECT_NE(notes.find("stored path '../outside.csv' refused: it has a '..' component"), std::string::npos) << notes;
  EXPECT_NE(notes.find("stored path '/etc/passwd' refused: it is absolute"), std::string::npos) << notes;
}

TEST(RunInput, DisplacementMagnitudeMapMasksWhatWasNotMeasured) {
  fusion::DisplacementField field;
  field.rows = 2;
  field.cols = 3;
  for (int i = 0; i < 6; ++i) {
    fusion::DisplacementVector v;
    v.x_px = 8 + 8 * (i % 3);
    v.y_px = 8 + 8 * (i / 3);
    v.u_px = 0.3;
    v.v_px = 0.4;
    v.flag = i == 4 ? fusion::VectorFlag::kMasked
                    : (i == 5 ? fusion::VectorFlag::kOutlierReplaced : fusion::VectorFlag::kOk);
    field.vectors.push_back(v);
  }
  const auto map = displacement_magnitude_map(field, {32, 24});
  EXPECT_DOUBLE_EQ(map.values.at<double>(0, 0), 0.5);
  EXPECT_EQ(map.mask.at<std::uint8_t>(1, 1), 255);
  EXPECT_TRUE(std::isnan(map.values.at<double>(1, 1)));
  EXPECT_EQ(map.mask.at<std::uint8_t>(1, 2), 255) << "a replaced outlier holds its neighbours' median, not a measurement";
  EXPECT_TRUE(std::isnan(map.values.at<double>(1, 2)));
  EXPECT_EQ(map.mask.at<std::uint8_t>(0, 2), 0);
  EXPECT_DOUBLE_EQ(map.x0_px, 8);
  EXPECT_DOUBLE_EQ(map.step_px, 8);
  EXPECT_THROW(displacement_magnitude_map(fusion::DisplacementField{}, {}), std::invalid_argument);
}

// What `bosfuse process` stores, written here by hand so that every field is known.
TEST(RunInput, StoredProbesFitsAgreementsAndFieldsAreUsed) {
  testing::TempDir dir;
  const testrun::Truth truth;
  testrun::create_run(dir / "run", true, truth);
  const auto frames = storage::RunStore::open(dir / "run").frames();
  ASSERT_EQ(frames.size(), 3u);
  const auto channels = storage::RunStore::open(dir / "run").channels();
  ASSERT_EQ(channels.size(), 2u);
  {
    storage::ProcessingStore results(dir / "run", true);
    std::filesystem::create_directories(dir / "run/fields");
    const auto with_t = results.add_probe({0, channels[0].id, "tc0", 96, 64});
    const auto shift_only = results.add_probe({0, channels[1].id, "tc1", 176, 64});
    results.write_probe_samples(std::vector<storage::ProbeSampleRecord>{
        {with_t, frames[1].id, frames[1].t_ns, 0.3, 0.4, 0.5, 50.0, true},
        {with_t, frames[2].id, frames[2].t_ns, 0.3, 0.0, 0.3, 40.0, true},
        {shift_only, frames[1].id, frames[1].t_ns, 0.6, 0.8, 1.0, std::nullopt, true},
        {shift_only, frames[2].id, frames[2].t_ns, 0.0, 0.0, 0.0, std::nullopt, false}});
    // Fit origin at the 10 s frame: k = 0.02, T0 = 50 there, ambient 22.
    results.add_fit({0, storage::FitSubject::kProbe, with_t, frames[1].t_ns, true,
                     R"({"ok": true, "status": "ok", "parameters": {
                          "k_per_s": {"value": 0.02, "std_error": 0.001, "fixed": false,
                                      "interval": {"confidence": 0.95, "low": 0.018, "high": 0.022}},
                          "tau_s": {"value": 50, "std_error": 2.5, "fixed": false,
                                    "interval": {"confidence": 0.95, "low": 45, "high": 55}},
                          "T0_c": {"value": 50, "std_error": 0.1, "fixed": false,
                                   "interval": {"confidence": 0.95, "low": 49.8, "high": 50.2}},
                          "T_amb_c": {"value": 22, "std_error": 0, "fixed": true,
                                      "interval": {"confidence": 0.95, "low": 22, "high": 22}}},
                          "diagnostics": {"points_used": 2, "dof": 0}, "warnings": ["stored"]})"});
    results.add_agreement({0, channels[0].id, with_t,
                           R"({"verdict": "They agree.", "k": {"difference_per_s": -0.01, "std_error_per_s": 0.002,
                                "z": -5, "relative_difference": -0.5, "agree": false},
                               "series": {"common_points": 2, "rms_difference_c": 1.5, "bias_c": 1.0,
                                          "difference_std_c": 0.5, "loa_low_c": 0.02, "loa_high_c": 1.98}})"});
    std::ofstream(dir / "run/fields/t.csv") << "x,y,temperature_c,measured,sigma_c\n8.0,8.0,30.5,1,0.01\n"
                                            << "16.0,8.0,nan,0,nan\n8.0,16.0,25.0,1,0.01\n16.0,16.0,22.0,0,nan\n";
    std::ofstream(dir / "run/fields/d.csv") << "x,y,u,v,valid,peak_ratio\n8.0,8.0,0.30000,0.40000,1,3.0\n"
                                            << "16.0,8.0,9.0,9.0,0,1.0\n";
    results.add_field({0, frames[2].id, "temperature", "fields/t.csv", "{}"});
    results.add_field({0, frames[2].id, "displacement", "fields/d.csv", "{}"});
  }
  RunReportOptions options;
  options.map_times_s = {55};
  const auto input = build_report_input(storage::RunStore::open(dir / "run"), options);
  ASSERT_EQ(input.series.size(), 4u);
  EXPECT_TRUE(input.has_probes());
  const auto& probe = input.series[2];
  EXPECT_EQ(probe.kind, SeriesKind::kBosProbe);
  ASSERT_EQ(probe.time_s.size(), 2u);
  EXPECT_NEAR(probe.time_s[0], truth.frame_times_s[0] + 0.003, 1e-9) << "same origin as the thermocouples";
  EXPECT_DOUBLE_EQ(probe.temperature_c[1], 40.0);
  ASSERT_TRUE(probe.fit && probe.fit->ok());
  EXPECT_DOUBLE_EQ(probe.fit->k_per_s.value, 0.02);
  EXPECT_NEAR(probe.fit->origin_s, truth.frame_times_s[0] + 0.003, 1e-9);
  EXPECT_NEAR(probe.fit->temperature_at(probe.fit->origin_s), 50.0, 1e-9);
  EXPECT_EQ(probe.fit->summary.warnings, std::vector<std::string>{"stored"});
  const auto& shift = input.series[3];
  ASSERT_EQ(shift.time_s.size(), 1u) << "the invalid sample is left out";
  EXPECT_EQ(shift.excluded_samples, 1u);
  EXPECT_DOUBLE_EQ(shift.temperature_c[0], 1.0) << "no temperature stored: the shift";
  EXPECT_FALSE(shift.fit) << "no stored fit: the report never fits on its own";
  ASSERT_EQ(input.agreements.size(), 1u);
  EXPECT_EQ(input.agreements[0].thermocouple, "tc0");
  EXPECT_EQ(input.agreements[0].probe, probe.name);
  ASSERT_TRUE(input.agreements[0].agreement.k && input.agreements[0].agreement.series);
  EXPECT_DOUBLE_EQ(input.agreements[0].agreement.series->bias_c, 1.0);
  EXPECT_FALSE(input.agreements[0].agreement.k->agree);
  ASSERT_EQ(input.temperature_maps.size(), 1u);
  const auto& t = input.temperature_maps[0];
  EXPECT_EQ(t.unit, "°C");
  ASSERT_TRUE(t.time_s.has_value());
  EXPECT_NEAR(*t.time_s, truth.frame_times_s[1] + 0.003, 1e-9);
  ASSERT_EQ(t.values.size(), cv::Size(2, 2));
  EXPECT_DOUBLE_EQ(t.x0_px, 8.0);
  EXPECT_DOUBLE_EQ(t.step_px, 8.0);
  EXPECT_DOUBLE_EQ(t.values.at<double>(1, 0), 25.0);
  EXPECT_TRUE(t.mask.at<std::uint8_t>(0, 1)) << "no temperature: masked";
  EXPECT_TRUE(t.mask.at<std::uint8_t>(1, 1)) << "filled in by the solve (measured 0): not a measurement";
  EXPECT_TRUE(std::isnan(t.values.at<double>(1, 1)));
  EXPECT_FALSE(t.mask.at<std::uint8_t>(0, 0));
  ASSERT_EQ(input.displacement_maps.size(), 1u) << "the stored field, not a new evaluation";
  EXPECT_DOUBLE_EQ(input.displacement_maps[0].values.at<double>(0, 0), 0.5);
  EXPECT_TRUE(input.displacement_maps[0].mask.at<std::uint8_t>(0, 1));
  EXPECT_NE(input.displacement_maps[0].source.find("stored"), std::string::npos);

  // The whole report: no "not processed" note, probes, agreement and a temperature map in the JSON.
  write_report(input, {}, dir / "out");
  std::ifstream html_in(dir / "out/report.html");
  const std::string html((std::istreambuf_iterator<char>(html_in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(html.find("Not processed yet"), std::string::npos);
}

}  // namespace
}  // namespace bosfuse::report
