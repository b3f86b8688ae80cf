// `bosfuse report` end to end: a small synthetic run on disk (two
// thermocouples on known Newton curves, a reference and two measurement
// frames with a known displacement), the report made by the executable, its
// files checked, and the page opened in a real headless browser (Debian's
// chromium) to check that every figure renders.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "report/html.h"
#include "tests/support/file_bytes.h"
#include "tests/support/synthetic_run.h"
#include "tests/support/browser.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using testing::shell_quote;

using testing::kBosfuse;

class ReportCli : public ::testing::Test {
 protected:
  testing::CommandResult chromium(const std::string& args) { return testing::chromium(dir_.path(), args); }
  std::vector<testing::RenderedImage> render_check(const std::string& html, const fs::path& copy) {
    return testing::render_check(html, copy, dir_.path());
  }

  testing::TempDir dir_;
};

// The render check itself tells a figure from a broken or a blank one.
TEST_F(ReportCli, BrowserCheckTellsRenderedFromBrokenAndBlankImages) {
  if (!testing::have_chromium()) GTEST_FAIL() << "chromium is not installed (scripts/debian-packages.txt lists it)";
  cv::Mat drawn(60, 80, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::circle(drawn, {40, 30}, 20, cv::Scalar(200, 30, 30), cv::FILLED);
  const cv::Mat blank(60, 80, CV_8UC3, cv::Scalar(255, 255, 255));
  auto uri = [](const cv::Mat& image) {
    std::vector<std::uint8_t> png;
    cv::imencode(".png", image, png);
    return "data:image/png;base64," + report::base64_encode(png);
  };
  const std::string good = uri(drawn);
  const std::string html = "<!DOCTYPE html><html><body><img src=\"" + good + "\"><img src=\"" +
                           "data:image/png;base64,QUJDRA==" + "\"><img src=\"" + uri(blank) + "\"></body></html>";
  const auto images = render_check(html, dir_ / "control.html");
  ASSERT_EQ(images.size(), 3u);
  EXPECT_EQ(images[0].size, "80x60");
  EXPECT_GT(images[0].spread, 100);
  EXPECT_EQ(images[1].size, "0x0") << "bytes that are not a PNG cannot decode";
  EXPECT_EQ(images[2].size, "80x60");
  EXPECT_EQ(images[2].spread, 0) << "a blank image has no spread";
}

TEST_F(ReportCli, MakesAReportThatABrowserRendersCompletely) {
  const testrun::Truth truth;
  testrun::create_run(dir_ / "run", true, truth);
  const fs::path out = dir_ / "out";
  ASSERT_TRUE(cv::imwrite((dir_ / "holder-mask.png").string(), testrun::holder_mask(truth)));
  const auto processed = testing::run_command(
      kBosfuse + " process " + shell_quote(dir_ / "run") + " --mask " + shell_quote(dir_ / "holder-mask.png"), 120);
  ASSERT_EQ(processed.exit_code, 0) << processed.output;
  const auto made = testing::run_command(kBosfuse + " report " + shell_quote(dir_ / "run") + " -o " + shell_quote(out) +
                                             " --map-times 10,60 --contour 0.05 --px-per-mm 30",
                                         120);
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_NE(made.output.find("report.html"), std::string::npos) << made.output;

  // Files: every figure as PNG and SVG, data as CSV and JSON.
  for (const char* name : {"report.html", "report.json", "series.csv", "fits.csv", "curves_all.png", "curves_all.svg",
                           "curve_tc0.png", "curve_tc0.svg", "curve_tc1.png", "curve_tc1.svg",
                           "map_displacement_t10s.png", "map_displacement_t10s.svg", "map_displacement_t10s.csv",
                           "map_displacement_t60s.png", "map_displacement_t60s.svg", "map_displacement_t60s.csv"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  const auto json = nlohmann::json::parse(testing::file_bytes(out / "report.json"));
  ASSERT_EQ(json["series"].size(), 4u) << "two thermocouples and the BOS probes at them";
  for (int c = 0; c < 2; ++c) {
    const auto& k = json["series"][c]["fit"]["parameters"]["k_per_s"];
    EXPECT_NEAR(k["value"].get<double>(), truth.k_per_s[c], 0.02 * truth.k_per_s[c]) << "tc" << c;
    EXPECT_LT(k["interval"]["low"].get<double>(), k["interval"]["high"].get<double>());
    EXPECT_EQ(json["series"][c]["samples"].get<int>(), truth.samples - truth.bad_samples);
  }
  std::vector<nlohmann::json> displacement_maps;
  for (const auto& m : json["maps"]) {
    if (m["unit"] == "px") displacement_maps.push_back(m);
  }
  ASSERT_EQ(displacement_maps.size(), 2u);
  EXPECT_NEAR(displacement_maps[0]["max"].get<double>(), truth.frame_peak_px[0], 0.2 * truth.frame_peak_px[0]);
  EXPECT_GT(displacement_maps[0]["masked_cells"].get<int>(), 10) << "the holder's region is masked";
  EXPECT_GT(json["image_quality"]["q_mod"].get<double>(), 0.9);
  const std::string html = testing::file_bytes(out / "report.html");
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("Not processed yet"), std::string::npos);
  const std::size_t figures = json["figures"].size();
  EXPECT_EQ(figures, 11u);  // overview, four curves, two displacement and two temperature maps, two Bland–Altman

  if (!testing::have_chromium()) GTEST_FAIL() << "chromium is not installed (scripts/debian-packages.txt lists it)";

  // 1. Every <img> of the page decoded by the browser, at its size, not blank.
  const auto images = render_check(html, out / "check.html");
  ASSERT_EQ(images.size(), figures);
  for (std::size_t i = 0; i < images.size(); ++i) {
    EXPECT_TRUE(images[i].complete) << "image " << i;
    EXPECT_TRUE(images[i].size == "900x600" || images[i].size == "900x650")
        << "image " << i << " decoded as " << images[i].size;
    EXPECT_GT(images[i].spread, 100) << "image " << i << " is blank";
  }

  // 2. A screenshot of the unmodified page shows the figures: not blank, and
  //    with the maps' colours (the page's own styles are grey and yellow only).
  // Chromium's --screenshot can capture a loaded machine's page before its
  // large images are painted (virtual time does not cover image decoding):
  // the same file is shot up to three times and the best shot counts. The
  // window is taller than the page, so that its last maps are in the shot.
  std::size_t purple = 0, red = 0;
  for (int attempt = 0; attempt < 3 && (purple <= 2000u || red <= 500u); ++attempt) {
    const fs::path shot = dir_ / fmt::format("shot{}.png", attempt);
    const auto screenshot =
        chromium("--window-size=1100,8000 --virtual-time-budget=15000 --screenshot=" + shell_quote(shot) + " " +
                 shell_quote(fs::path("file://" + (out / "report.html").string())));
    ASSERT_EQ(screenshot.exit_code, 0) << screenshot.output.substr(0, 2000);
    const cv::Mat page = cv::imread(shot.string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(page.empty()) << "no screenshot";
    EXPECT_EQ(page.cols, 1100);
    std::size_t shot_purple = 0, shot_red = 0;
    for (int r = 0; r < page.rows; ++r) {
      for (int c = 0; c < page.cols; ++c) {
        const auto p = page.at<cv::Vec3b>(r, c);  // BGR
        if (p[0] > 60 && p[0] < 120 && p[1] < 40 && p[2] > 40 && p[2] < 100) ++shot_purple;  // viridis's purple
        if (p[2] > 180 && p[0] < 60 && p[1] < 80) ++shot_red;
      }
    }
    purple = std::max(purple, shot_purple);
    red = std::max(red, shot_red);
  }
  EXPECT_GT(purple, 2000u) << "the maps' viridis purple is not on the page";
  EXPECT_GT(red, 500u) << "the fits' and maps' red is not on the page";
}

// After `bosfuse process`, the report shows what it stored: BOS probe
// series, the agreement table, temperature maps; the map axes take the
// image scale from the run's [geometry].
TEST_F(ReportCli, AProcessedRunGetsProbesAgreementAndTemperatureMaps) {
  testrun::Truth truth;
  truth.config_toml = "[geometry]\npx_per_mm_flow = 25\n";
  testrun::create_run(dir_ / "run", true, truth);
  const auto processed = testing::run_command(kBosfuse + " process " + shell_quote(dir_ / "run"), 120);
  ASSERT_EQ(processed.exit_code, 0) << processed.output;
  const fs::path out = dir_ / "out";
  const auto made = testing::run_command(
      kBosfuse + " report " + shell_quote(dir_ / "run") + " -o " + shell_quote(out) + " --map-times 10,60", 120);
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const auto json = nlohmann::json::parse(testing::file_bytes(out / "report.json"));
  std::size_t probes = 0;
  for (const auto& s : json["series"]) {
    if (s["kind"] != "BOS probe") continue;
    ++probes;
    EXPECT_EQ(s["samples"].get<int>(), 2) << s["name"];
    EXPECT_FALSE(s["fit"].is_null()) << s["name"];
    EXPECT_GT(s["time_s"][0].get<double>(), 9.0) << "relative to the thermocouples' origin";
  }
  EXPECT_EQ(probes, 2u);
  ASSERT_EQ(json["agreements"].size(), 2u);
  EXPECT_EQ(json["agreements"][0]["thermocouple"], "tc0");
  std::size_t temperature_maps = 0, displacement_maps = 0;
  for (const auto& m : json["maps"]) {
    EXPECT_DOUBLE_EQ(m["px_per_mm"].get<double>(), 25.0) << "from the run's [geometry]";
    if (m["unit"] == "°C") ++temperature_maps;
    if (m["unit"] == "px") {
      ++displacement_maps;
      EXPECT_NE(m["source"].get<std::string>().find("stored"), std::string::npos) << "not evaluated again";
    }
  }
  EXPECT_EQ(temperature_maps, 2u);
  EXPECT_EQ(displacement_maps, 2u);
  const std::string html = testing::file_bytes(out / "report.html");
  EXPECT_EQ(html.find("Not processed yet"), std::string::npos);
  EXPECT_NE(html.find("tc0 (BOS)"), std::string::npos);
  std::size_t agreement_figures = 0, temperature_figures = 0;
  for (const auto& f : json["figures"]) {
    const std::string name = f.dump();
    agreement_figures += name.find("agreement_") != std::string::npos ? 1 : 0;
    temperature_figures += name.find("map_temperature_") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(agreement_figures, 2u) << json["figures"].dump() << "\n" << json["notes"].dump();
  EXPECT_EQ(temperature_figures, 2u) << json["figures"].dump();
}

TEST_F(ReportCli, RunWithoutFramesGetsAReportWithoutMapsAndANote) {
  testrun::create_run(dir_ / "run", false);
  const auto made =
      testing::run_command(kBosfuse + " report " + shell_quote(dir_ / "run") + " -o " + shell_quote(dir_ / "out"), 120);
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const std::string html = testing::file_bytes(dir_ / "out" / "report.html");
  EXPECT_NE(html.find("Thermocouples only: the run has no frames"), std::string::npos);
  EXPECT_EQ(html.find("Displacement maps"), std::string::npos) << "no BOS sections";
  EXPECT_FALSE(fs::exists(dir_ / "out" / "map_displacement_t10s.png"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "curve_tc0.svg"));
}

TEST_F(ReportCli, BadArgumentsAreRefusedWithAReason) {
  testrun::create_run(dir_ / "run", false);
  const auto no_out = testing::run_command(kBosfuse + " report " + shell_quote(dir_ / "run"));
  EXPECT_NE(no_out.exit_code, 0);
  EXPECT_NE(no_out.output.find("--out"), std::string::npos) << no_out.output;
  const auto bad_times = testing::run_command(kBosfuse + " report " + shell_quote(dir_ / "run") + " -o " +
                                              shell_quote(dir_ / "o") + " --map-times 10,x");
  EXPECT_NE(bad_times.exit_code, 0);
  EXPECT_NE(bad_times.output.find("'x' is not a time"), std::string::npos) << bad_times.output;
  const auto no_run =
      testing::run_command(kBosfuse + " report " + shell_quote(dir_ / "nothing") + " -o " + shell_quote(dir_ / "o"));
  EXPECT_NE(no_run.exit_code, 0);
}

}  // namespace
}  // namespace bosfuse
