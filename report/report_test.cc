#include "report/report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "report/export.h"
#include "report/html.h"
#include "report/summary.h"
#include "report/test_data.h"
#include "tests/support/file_bytes.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Every src= and href= value in the page (a plain scan: std::regex overflows
// its stack on megabytes of base64).
std::vector<std::string> references(const std::string& html) {
  std::vector<std::string> out;
  std::string lower = html;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const std::string attr : {"src", "href"}) {
    for (auto p = lower.find(attr); p != std::string::npos; p = lower.find(attr, p + 1)) {
      if (p > 0 && std::isalnum(static_cast<unsigned char>(lower[p - 1]))) continue;
      auto q = p + attr.size();
      while (q < lower.size() && lower[q] == ' ') ++q;
      if (q >= lower.size() || lower[q] != '=') continue;
      ++q;
      while (q < lower.size() && lower[q] == ' ') ++q;
      const char quote = q < lower.size() && (lower[q] == '"' || lower[q] == '\'') ? lower[q] : 0;
      if (quote) ++q;
      const auto end = quote ? html.find(quote, q) : html.find_first_of(" >", q);
      out.push_back(html.substr(q, end == std::string::npos ? std::string::npos : end - q));
    }
  }
  return out;
}

void expect_self_contained(const std::string& html) {
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos) << "the report needs no script";
  EXPECT_EQ(html.find("<link"), std::string::npos) << "styles are inline";
  EXPECT_EQ(html.find("@import"), std::string::npos);
  EXPECT_EQ(html.find("url("), std::string::npos);
  for (const auto& ref : references(html)) {
    EXPECT_EQ(ref.rfind("data:image/png;base64,", 0), 0u) << "external reference: " << ref.substr(0, 80);
  }
}

TEST(Html, EscapesAndEncodes) {
  EXPECT_EQ(html_escape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
  const std::string text = "Man";
  EXPECT_EQ(base64_encode({reinterpret_cast<const std::uint8_t*>(text.data()), 3}), "TWFu");
  EXPECT_EQ(base64_encode({reinterpret_cast<const std::uint8_t*>(text.data()), 2}), "TWE=");
  EXPECT_EQ(base64_encode({reinterpret_cast<const std::uint8_t*>(text.data()), 1}), "TQ==");
  EXPECT_EQ(base64_encode({}), "");
  EXPECT_EQ(slug("tc 0/ä#"), "tc_0____");
}

class Report : public ::testing::Test {
 protected:
  ReportFiles write(ReportInput input) {
    fit_missing(input);
    input_ = input;
    return write_report(input_, {}, dir_ / "out");
  }
  testing::TempDir dir_;
  ReportInput input_;
};

TEST_F(Report, WritesOneSelfContainedPageWithEveryFigureEmbedded) {
  const auto files = write(testdata::sample_input(true));
  EXPECT_EQ(files.html, dir_ / "out" / "report.html");
  const std::string html = testing::file_bytes(files.html);
  expect_self_contained(html);
  // overview + two curves + one map
  ASSERT_EQ(files.figures.size(), 4u);
  std::size_t images = 0;
  for (const auto& ref : references(html)) images += ref.rfind("data:image/png;base64,", 0) == 0;
  EXPECT_EQ(images, files.figures.size());
  for (const auto& f : files.figures) {
    EXPECT_TRUE(fs::exists(f.png)) << f.png;
    EXPECT_TRUE(fs::exists(f.svg)) << f.svg;
    EXPECT_NE(html.find(f.png.filename().string()), std::string::npos) << "the page lists " << f.png.filename();
  }
  // The embedded data is the PNG file itself.
  const auto first = html.find("data:image/png;base64,") + std::strlen("data:image/png;base64,");
  const std::string png = testing::file_bytes(files.figures[0].png);
  const std::string encoded = base64_encode({reinterpret_cast<const std::uint8_t*>(png.data()), png.size()});
  EXPECT_EQ(html.compare(first, encoded.size(), encoded), 0);
  EXPECT_NE(html.find("unit &lt;run&gt; &amp; co"), std::string::npos) << "the run name is escaped";
  EXPECT_NE(html.find("Displacement maps"), std::string::npos);
  EXPECT_NE(html.find("Q_mod"), std::string::npos);
}

TEST_F(Report, RunWithoutFramesHasNoMapsButSaysWhy) {
  const auto files = write(testdata::sample_input(false));
  const std::string html = testing::file_bytes(files.html);
  expect_self_contained(html);
  for (const auto& f : files.figures) EXPECT_EQ(f.png.filename().string().rfind("map_", 0), std::string::npos);
  EXPECT_NE(html.find("No displacement maps: the run has no frames."), std::string::npos);
  EXPECT_NE(html.find("Not processed yet"), std::string::npos);
  EXPECT_NE(html.find("bosfuse process"), std::string::npos);
  EXPECT_NE(html.find("No image quality index"), std::string::npos);
  const auto json = nlohmann::json::parse(testing::file_bytes(files.json));
  EXPECT_TRUE(json["maps"].empty());
  EXPECT_EQ(json["image_quality"], "not computed: the run has no frames to compare") << "a reason, not null";
}

TEST_F(Report, CsvAndJsonHoldEveryChannelsDataAndTheFitsWithIntervals) {
  const auto files = write(testdata::sample_input(true));
  const auto series = lines_of(testing::file_bytes(dir_ / "out" / "series.csv"));
  ASSERT_FALSE(series.empty());
  EXPECT_EQ(series[0], "series,kind,t_s,temperature_c,fit_c,residual_c,fit_half_width_c");
  std::map<std::string, std::size_t> rows;
  for (std::size_t i = 1; i < series.size(); ++i) ++rows[series[i].substr(0, series[i].find(','))];
  EXPECT_EQ(rows["tc0"], input_.series[0].time_s.size());
  EXPECT_EQ(rows["tc1"], input_.series[1].time_s.size());
  // The second row is the first sample of tc0, exactly.
  std::stringstream row(series[1]);
  std::string name, kind, t, temp;
  std::getline(row, name, ',');
  std::getline(row, kind, ',');
  std::getline(row, t, ',');
  std::getline(row, temp, ',');
  EXPECT_EQ(kind, "thermocouple");
  EXPECT_DOUBLE_EQ(std::stod(temp), input_.series[0].temperature_c[0]);

  const auto fits = lines_of(testing::file_bytes(dir_ / "out" / "fits.csv"));
  ASSERT_EQ(fits.size(), 3u);
  EXPECT_NE(fits[0].find("k_per_s,k_low,k_high"), std::string::npos);
  EXPECT_EQ(fits[1].rfind("tc0,thermocouple,true,ok,0.95,200,", 0), 0u) << fits[1];

  const auto json = nlohmann::json::parse(testing::file_bytes(files.json));
  ASSERT_EQ(json["series"].size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& s = json["series"][i];
    EXPECT_EQ(s["name"], input_.series[i].name);
    EXPECT_EQ(s["time_s"].size(), input_.series[i].time_s.size());
    EXPECT_EQ(s["temperature_c"].size(), input_.series[i].temperature_c.size());
    const auto& k = s["fit"]["parameters"]["k_per_s"];
    EXPECT_DOUBLE_EQ(k["value"].get<double>(), input_.series[i].fit->k_per_s.value);
    EXPECT_LT(k["interval"]["low"].get<double>(), k["value"].get<double>());
    EXPECT_GT(k["interval"]["high"].get<double>(), k["value"].get<double>());
    EXPECT_EQ(k["interval"]["confidence"].get<double>(), 0.95);
    for (const char* p : {"tau_s", "T0_c", "T_amb_c"}) {
      EXPECT_TRUE(s["fit"]["parameters"][p]["interval"].contains("low")) << p;
    }
  }
  EXPECT_NEAR(json["series"][0]["fit"]["parameters"]["k_per_s"]["value"].get<double>(), 0.01, 0.0005);
  ASSERT_EQ(json["maps"].size(), 1u);
  EXPECT_EQ(json["maps"][0]["px_per_mm"].get<double>(), 30.0);
  EXPECT_GT(json["maps"][0]["masked_cells"].get<int>(), 0);
  EXPECT_EQ(json["figures"].size(), files.figures.size());

  // The map's CSV: one row per cell, masked cells flagged, their value `nan` (not an empty cell).
  const fs::path map_csv = dir_ / "out" / "map_displacement_t10s.csv";
  const auto map_rows = lines_of(testing::file_bytes(map_csv));
  ASSERT_EQ(map_rows.size(), 1u + 24 * 32);
  EXPECT_EQ(map_rows[0], "x_px,y_px,x_mm,y_mm,value,masked");
  EXPECT_EQ(std::count_if(map_rows.begin(), map_rows.end(), [](const auto& l) { return l.ends_with(",nan,1"); }),
            json["maps"][0]["masked_cells"].get<long>());
}

// A channel's name went into the CSV as-is, so a spreadsheet ran it.
TEST(ReportCsv, AFormulaLikeNameIsInertAndNumbersStayNumbers) {
  testing::TempDir dir;
  ReportInput input;
  CurveSeries s;
  s.name = "=cmd|' /C calc'!A0";
  s.kind = SeriesKind::kThermocouple;
  s.time_s = {0, 1.5};
  s.temperature_c = {-3.5, -4};
  input.series.push_back(s);
  write_series_csv(input, dir / "series.csv");
  write_fits_csv(input, dir / "fits.csv");
  const auto series = lines_of(testing::file_bytes(dir / "series.csv"));
  ASSERT_EQ(series.size(), 3u);
  EXPECT_EQ(series[1], "\"'=cmd|' /C calc'!A0\",thermocouple,0,-3.5,,,");
  EXPECT_EQ(series[2], "\"'=cmd|' /C calc'!A0\",thermocouple,1.5,-4,,,");
  const auto fits = lines_of(testing::file_bytes(dir / "fits.csv"));
  ASSERT_EQ(fits.size(), 2u);
  EXPECT_EQ(fits[1].rfind("\"'=cmd|' /C calc'!A0\",thermocouple,false,", 0), 0u) << fits[1];
}

// A series far from the run's origin (a later session of an appended run)
// has T0 at its first sample, not an extrapolation e^(k·Δt) times its
// amplitude: the summary says so and fits.csv gives the time T0 is at.
TEST(ReportFits, AT0AtTheFirstSampleIsNotedAndItsTimeIsInFitsCsv) {
  testing::TempDir dir;
  ReportInput input;
  CurveSeries late = testdata::cooling_series("late", 0.01, 80, 22, 200, 2.0, 0.1, 3);
  for (double& t : late.time_s) t += 7200.0;  // two hours, 72 τ, into the run
  input.series.push_back(late);
  input.series.push_back(testdata::cooling_series("early", 0.01, 80, 22, 200, 2.0, 0.1, 4));
  fit_missing(input, {});
  ASSERT_TRUE(input.series[0].fit && input.series[0].fit->ok());
  ASSERT_FALSE(input.series[0].fit->t0_at_origin());
  EXPECT_NEAR(input.series[0].fit->t0_c.value, 80.0, 0.5);
  const auto summary = summarize(input);
  const auto& notes = summary.series[0].notes;
  EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& n) {
    return n.rfind("T0 is at t = 7200 s, the series' first sample", 0) == 0;
  })) << ::testing::PrintToString(notes);
  for (const auto& n : summary.series[1].notes) EXPECT_EQ(n.find("T0 is at"), std::string::npos) << n;

  write_fits_csv(input, dir / "fits.csv");
  const auto rows = lines_of(testing::file_bytes(dir / "fits.csv"));
  ASSERT_EQ(rows.size(), 3u);
  const auto cells = [](const std::string& row) {
    std::vector<std::string> out;
    std::stringstream in(row);
    for (std::string cell; std::getline(in, cell, ',');) out.push_back(cell);
    return out;
  };
  const auto header = cells(rows[0]);
  const auto column = std::find(header.begin(), header.end(), "T0_t_s") - header.begin();
  ASSERT_LT(static_cast<std::size_t>(column), header.size());
  EXPECT_EQ(header[column - 1], "T0_high");
  EXPECT_EQ(std::stod(cells(rows[1])[column]), 7200.0);
  EXPECT_EQ(std::stod(cells(rows[2])[column]), 0.0);
}

TEST_F(Report, ProbesAgreementAndTemperatureMapsAppearWhenProvided) {
  ReportInput input = testdata::sample_input(true);
  CurveSeries probe = testdata::cooling_series("tc0 probe", 0.0102, 80, 22, 40, 10.0, 0.4, 9);
  probe.kind = SeriesKind::kBosProbe;
  input.series.push_back(probe);
  MapField temperature = testdata::bump_map();
  temperature.quantity = "temperature";
  temperature.unit = "°C";
  temperature.values = temperature.values * 100 + 22;
  input.temperature_maps.push_back(temperature);
  fit_missing(input);
  const auto a = fitting::clean_series(input.series[0].time_s, input.series[0].temperature_c, 0.0);
  const auto b = fitting::clean_series(input.series[2].time_s, input.series[2].temperature_c, 0.0);
  input.agreements.push_back(
      {"tc0", "tc0 probe", fitting::compare_fits(*input.series[0].fit, *input.series[2].fit, a, b)});
  const auto files = write_report(input, {}, dir_ / "out");
  const std::string html = testing::file_bytes(files.html);
  expect_self_contained(html);
  EXPECT_EQ(html.find("Not processed yet"), std::string::npos) << "everything was processed";
  EXPECT_NE(html.find("class=\"summary agreement\""), std::string::npos);
  EXPECT_NE(html.find(html_escape(input.agreements[0].agreement.verdict)), std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "map_temperature_t10s.png"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "curve_probe_tc0_probe.svg"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "agreement_tc0_tc0_probe.png")) << "Bland–Altman plot";
  EXPECT_TRUE(fs::exists(dir_ / "out" / "agreement_tc0_tc0_probe.svg"));
  const auto json = nlohmann::json::parse(testing::file_bytes(files.json));
  ASSERT_EQ(json["agreements"].size(), 1u);
  EXPECT_TRUE(json["agreements"][0]["k"].contains("z"));
  EXPECT_EQ(json["series"][2]["kind"], "BOS probe");
}

// The page without its embedded images (base64 is not text).
std::string page_text(const fs::path& html_file) {
  std::string text = testing::file_bytes(html_file);
  for (auto at = text.find("base64,"); at != std::string::npos; at = text.find("base64,", at + 7)) {
    text.erase(at + 7, text.find('"', at) - at - 7);
  }
  return text;
}

// Words nan, inf, infinity or null standing where a number would: between
// the characters that delimit a number in a table cell, a list or a CSV
// field. A reason such as "rejected as NaN/inf" is prose, not a number.
std::vector<std::string> missing_numbers_shown(const std::string& text) {
  const auto is_letter = [](char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; };
  const std::string before = ">[(,=: \n\t\"+-", after = "<])},; \n\t\"%";
  std::vector<std::string> found;
  for (std::size_t i = 0; i < text.size();) {
    if (!is_letter(text[i])) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < text.size() && is_letter(text[end])) ++end;
    std::string word = text.substr(i, end - i);
    std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return std::tolower(c); });
    const bool opens = i == 0 || before.find(text[i - 1]) != std::string::npos;
    const bool closes = end == text.size() || after.find(text[end]) != std::string::npos;
    if ((word == "nan" || word == "inf" || word == "infinity" || word == "null") && opens && closes) {
      found.push_back(text.substr(i >= 40 ? i - 40 : 0, 80));
    }
    i = end;
  }
  return found;
}

std::vector<std::string> json_gaps(const nlohmann::json& j, const std::string& path = "") {
  std::vector<std::string> gaps;
  if (j.is_null() || (j.is_number_float() && !std::isfinite(j.get<double>()))) gaps.push_back(path);
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      for (auto& g : json_gaps(value, path + "/" + key)) gaps.push_back(g);
    }
  }
  if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      for (auto& g : json_gaps(j[i], path + "/" + std::to_string(i))) gaps.push_back(g);
    }
  }
  return gaps;
}

// What the summary cannot compute: a failed fit (tc2, three points), a BOS
// probe in px (no temperature to compare with tc0), a pair without series
// statistics (tc1 against its probe) and one without k (tc2), plus a NaN
// sample.
ReportInput input_with_gaps() {
  ReportInput input = testdata::sample_input(false);
  input.time_basis = "experiment seconds since heater off (2026-11-30T02:00:00.000Z); recorded at 16×";
  input.series[1].temperature_c[5] = NAN;
  CurveSeries failed;
  failed.name = "tc2";
  failed.time_s = {0, 1, 2};
  failed.temperature_c = {50, 45, 41};
  input.series.push_back(failed);
  CurveSeries px = testdata::cooling_series("tc0 probe", 0.0102, 0.8, 0.02, 40, 10.0, 0.005, 9);
  px.kind = SeriesKind::kBosProbe;
  px.unit = "px";
  input.series.push_back(px);
  CurveSeries probe = testdata::cooling_series("tc1 probe", 0.012, 70, 22, 40, 10.0, 0.3, 10);
  probe.kind = SeriesKind::kBosProbe;
  input.series.push_back(probe);
  fit_missing(input);
  const auto pair = [&](std::size_t a, std::size_t b) {
    const auto& sa = input.series[a];
    const auto& sb = input.series[b];
    return AgreementEntry{
        sa.name, sb.name,
        fitting::compare_fits(*sa.fit, *sb.fit, fitting::clean_series(sa.time_s, sa.temperature_c, 0.0),
                              fitting::clean_series(sb.time_s, sb.temperature_c, 0.0))};
  };
  input.agreements.push_back(pair(0, 3));
  input.agreements.push_back(pair(1, 4));
  input.agreements.back().agreement.series.reset();
  input.agreements.push_back(pair(2, 4));
  return input;
}

TEST_F(Report, NoNumberIsNanInfOrNullAndEveryGapSaysWhy) {
  const ReportInput input = input_with_gaps();
  ASSERT_FALSE(input.series[2].fit->ok());
  ASSERT_TRUE(input.series[3].fit->ok()) << input.series[3].fit->brief_report();
  ASSERT_TRUE(input.agreements[0].agreement.series) << "compare_fits compares px with °C: the report must not";
  const auto files = write_report(input, {}, dir_ / "out");

  const std::string html = page_text(files.html);
  EXPECT_TRUE(missing_numbers_shown(html).empty()) << ::testing::PrintToString(missing_numbers_shown(html));
  for (const char* reason :
       {"Δk only: tc0 probe is in px, not °C — no temperature difference", "the fit of tc2 failed (too few points)",
        "no temperature difference: the two series share too few common times", "no Δk: the fit of tc2 failed",
        "T0, T_amb and the residual RMS are in px, not °C"}) {
    EXPECT_NE(html.find(html_escape(reason)), std::string::npos) << reason;
  }
  EXPECT_NE(html.find("<td>—<sup>1</sup></td>"), std::string::npos) << "a gap is a dash with its footnote";
  EXPECT_NE(html.find("<ol class=\"footnotes\">"), std::string::npos);

  const std::string json_text = testing::file_bytes(files.json);
  const auto json = nlohmann::json::parse(json_text);
  EXPECT_TRUE(json_gaps(json).empty()) << ::testing::PrintToString(json_gaps(json));
  EXPECT_TRUE(missing_numbers_shown(json_text).empty()) << ::testing::PrintToString(missing_numbers_shown(json_text));
  const auto& summary = json["summary"];
  EXPECT_FALSE(summary["series"][2]["k"].contains("value"));
  EXPECT_NE(summary["series"][2]["k"]["not_computed"].get<std::string>().find("failed"), std::string::npos);
  EXPECT_EQ(summary["series"][3]["T0"]["unit"], "px");
  EXPECT_TRUE(summary["pairs"][0]["delta_k"].contains("value")) << "k compares whatever the unit";
  EXPECT_NE(summary["pairs"][0]["bias"]["not_computed"].get<std::string>().find("px, not °C"), std::string::npos);
  EXPECT_TRUE(json["agreements"][0]["series"].is_string()) << "no °C − px statistics in report.json";
  const std::string verdict = summary["pairs"][0]["verdict"];
  EXPECT_EQ(verdict.find("°C RMS"), std::string::npos) << verdict;
  EXPECT_NE(verdict.find("k agree"), std::string::npos) << verdict;
  EXPECT_NE(verdict.find("The temperatures are not compared: tc0 probe is in px, not °C."), std::string::npos);
  EXPECT_EQ(json["agreements"][0]["verdict"], verdict);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "agreement_tc0_tc0_probe.png")) << "no Bland–Altman plot of °C against px";
  EXPECT_NE(html.find("No Bland–Altman plot of tc0 against tc0 probe: tc0 probe is in px, not °C."), std::string::npos);
  EXPECT_TRUE(json["agreements"][1]["series"].is_string());
  EXPECT_TRUE(json["agreements"][1]["k"].is_object());
  EXPECT_TRUE(json["agreements"][2]["k"].is_string());
  EXPECT_EQ(json["series"][1]["non_finite_samples_left_out"], 1);
  EXPECT_FALSE(json["series"][2]["fit"]["ok"].get<bool>());
  EXPECT_FALSE(json["series"][2]["fit"]["parameters"].contains("k_per_s")) << "absent, not null";

  for (const char* csv : {"summary.csv", "series.csv", "fits.csv"}) {
    const std::string text = testing::file_bytes(dir_ / "out" / csv);
    EXPECT_TRUE(missing_numbers_shown(text).empty())
        << csv << ": " << ::testing::PrintToString(missing_numbers_shown(text));
  }
  const auto rows = lines_of(testing::file_bytes(dir_ / "out" / "summary.csv"));
  EXPECT_NE(std::find_if(rows.begin(), rows.end(),
                         [](const std::string& r) {
                           return r.rfind("tc2,thermocouple,,k,,,,,1/s,the fit of tc2 failed (too few points)", 0) == 0;
                         }),
            rows.end())
      << "an empty value with its reason";
}

TEST_F(Report, ThePairTableShowsTheVerdictItsZItsMarginAndBlandAltmansN) {
  ReportInput input = testdata::sample_input(true);
  CurveSeries probe = testdata::cooling_series("tc0 probe", 0.0102, 80, 22, 40, 10.0, 0.4, 9);
  probe.kind = SeriesKind::kBosProbe;
  input.series.push_back(probe);
  fit_missing(input);
  const auto a = fitting::clean_series(input.series[0].time_s, input.series[0].temperature_c, 0.0);
  const auto b = fitting::clean_series(input.series[2].time_s, input.series[2].temperature_c, 0.0);
  const auto agreement = fitting::compare_fits(*input.series[0].fit, *input.series[2].fit, a, b);
  ASSERT_TRUE(agreement.curve && agreement.series);
  input.agreements.push_back({"tc0", "tc0 probe", agreement});
  const ReportSummary summary = summarize(input);
  ASSERT_EQ(summary.pairs.size(), 1u);
  const PairSummary& p = summary.pairs[0];
  const fitting::ParameterAgreement* deciding = agreement.curve->deciding();
  ASSERT_NE(deciding, nullptr);
  EXPECT_EQ(p.equivalence, fitting::to_string(agreement.curve->verdict));
  ASSERT_TRUE(p.deciding_z.value && p.margin.value && p.pairs);
  EXPECT_DOUBLE_EQ(*p.deciding_z.value, deciding->z);
  EXPECT_DOUBLE_EQ(*p.margin.value, deciding->margin);
  EXPECT_EQ(*p.pairs, agreement.series->common_points);
  const std::string html = summary_html(summary);
  EXPECT_NE(html.find("<strong>" + p.equivalence + "</strong>"), std::string::npos) << html;
  EXPECT_NE(html.find("z = " + display_number(deciding->z, "{:.2f}")), std::string::npos) << html;
  EXPECT_NE(html.find("margin ±" + display_number(deciding->margin, "{:.2g}")), std::string::npos) << html;
  EXPECT_NE(html.find("<td>" + std::to_string(*p.pairs) + "</td>"), std::string::npos) << html;
}

TEST_F(Report, APixelProbesVerdictIsOnKAloneAndAnOldAgreementSaysItHasNone) {
  ReportInput input = input_with_gaps();
  const ReportSummary summary = summarize(input);
  const PairSummary& px = summary.pairs[0];
  ASSERT_TRUE(input.agreements[0].agreement.curve);
  EXPECT_EQ(px.equivalence, fitting::to_string(input.agreements[0].agreement.curve->parameters[0].verdict));
  EXPECT_EQ(px.deciding, "k");
  EXPECT_NE(px.verdict.find(" on k alone: k "), std::string::npos) << px.verdict;
  input.agreements[0].agreement.curve.reset();  // as stored before the equivalence test
  const PairSummary old = summarize(input).pairs[0];
  EXPECT_TRUE(old.equivalence.empty());
  EXPECT_NE(old.deciding_z.reason.find("stored before the equivalence test"), std::string::npos);
}

TEST_F(Report, TheSummaryComesFirstInTheRunsTimeBasis) {
  ReportInput input = input_with_gaps();
  const auto files = write_report(input, {}, dir_ / "out");
  const std::string html = page_text(files.html);
  const auto summary_at = html.find("<h2 id=\"summary\">");
  ASSERT_NE(summary_at, std::string::npos);
  EXPECT_LT(summary_at, html.find("<figure")) << "the summary comes before the figures";
  EXPECT_LT(summary_at, html.find("class=\"summary agreement\""));
  EXPECT_NE(
      html.find("<caption>Newton fits T(t) = T_amb + (T0 − T_amb)·exp(−k·t), t in " + html_escape(input.time_basis)),
      std::string::npos);
  for (const auto& f : files.figures) {
    if (f.png.filename().string().rfind("curve", 0) == 0) {
      EXPECT_NE(f.caption.find(input.time_basis), std::string::npos) << f.caption;
    }
  }

  const auto json = nlohmann::json::parse(testing::file_bytes(files.json));
  EXPECT_EQ(json["time_basis"], input.time_basis);
  EXPECT_EQ(json["summary"]["time_basis"], input.time_basis);
  const auto& k = json["summary"]["series"][0]["k"];
  EXPECT_DOUBLE_EQ(k["value"].get<double>(), input.series[0].fit->k_per_s.value);
  EXPECT_DOUBLE_EQ(k["low"].get<double>(), input.series[0].fit->k_per_s.low);
  EXPECT_EQ(json["summary"]["pairs"].size(), 3u);
  EXPECT_EQ(json["summary"]["pairs"][1]["k_agree"], input.agreements[1].agreement.k->agree);

  const auto rows = lines_of(testing::file_bytes(dir_ / "out" / "summary.csv"));
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows[0], "series,kind,compared_with,quantity,value,std_error,low,high,unit,note");
  EXPECT_EQ(rows[1], "tc0,thermocouple,,points,200,,,,,");
  // series.csv: the band's half-width beside every fitted value, positive and small.
  const auto series = lines_of(testing::file_bytes(dir_ / "out" / "series.csv"));
  const std::string last = series[1].substr(series[1].rfind(',') + 1);
  ASSERT_FALSE(last.empty());
  EXPECT_GT(std::stod(last), 0.0);
  EXPECT_LT(std::stod(last), 0.5);
  EXPECT_DOUBLE_EQ(std::stod(last), input.series[0].fit->temperature_half_width_at(input.series[0].time_s[0]));
}

TEST_F(Report, AReportThatFailsHalfWayLeavesTheEarlierOneWhole) {
  const auto first = write(testdata::sample_input(true));
  std::map<fs::path, std::string> before;
  for (const auto& entry : fs::directory_iterator(dir_ / "out"))
    before[entry.path()] = testing::file_bytes(entry.path());
  ASSERT_GT(before.size(), 8u);
  ReportInput input = testdata::sample_input(true);
  fit_missing(input);
  input.run_name = "second";
  ReportOptions options;
  options.map_size = {50, 50};  // refused by the map, after the curves are drawn
  EXPECT_THROW(write_report(input, options, dir_ / "out"), std::invalid_argument);
  std::map<fs::path, std::string> after;
  for (const auto& entry : fs::directory_iterator(dir_ / "out"))
    after[entry.path()] = testing::file_bytes(entry.path());
  EXPECT_EQ(after, before) << "every file of the first report byte for byte, no staging folder left";
}

TEST_F(Report, UnwritableFolderIsAnError) {
  const fs::path file = dir_ / "a_file";
  std::ofstream(file) << "x";
  ReportInput input = testdata::sample_input(false);
  fit_missing(input);
  EXPECT_THROW(write_report(input, {}, file / "sub"), std::runtime_error);
}

}  // namespace
}  // namespace bosfuse::report
