#include "report/figures.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>

#include "report/test_data.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The SVG is XML with an <svg> root whose viewBox is the figure's size.
void expect_svg(const std::filesystem::path& path, const FigureSize& size) {
  const std::string text = read_text(path);
  ASSERT_FALSE(text.empty()) << path;
  std::smatch root;
  ASSERT_TRUE(std::regex_search(text, root, std::regex(R"(<svg\b[^>]*>)"))) << "no <svg> element in " << path;
  const auto prolog = text.substr(0, root.position(0));
  EXPECT_EQ(prolog.find('<', prolog.find("?>") == std::string::npos ? 0 : prolog.find("?>") + 2), std::string::npos)
      << "<svg> must be the root element";
  EXPECT_NE(root.str().find("viewBox=\"0 0 " + std::to_string(size.width_px) + " " + std::to_string(size.height_px)),
            std::string::npos)
      << root.str();
  EXPECT_NE(text.rfind("</svg>"), std::string::npos) << "SVG not closed";
  // Balanced: as many opening <g as closing </g>.
  const auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<g>") + count("<g "), count("</g>"));
}

void expect_png(const std::filesystem::path& path, const FigureSize& size) {
  const cv::Mat png = cv::imread(path.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty()) << path << " does not decode";
  EXPECT_EQ(png.cols, size.width_px);
  EXPECT_EQ(png.rows, size.height_px);
  cv::Scalar mean, stddev;
  cv::meanStdDev(png, mean, stddev);
  EXPECT_GT(stddev[0] + stddev[1] + stddev[2], 5.0) << "blank figure " << path;
}

TEST(Figures, CairoDevicesAreThere) { EXPECT_TRUE(cairo_devices_available()); }

TEST(Figures, CurveFigureWritesPngAndSvgOfTheRequestedSize) {
  testing::TempDir dir;
  ReportInput input = testdata::sample_input(false);
  fit_missing(input);
  const FigureSize size{700, 500};
  const auto files = write_curve_figure(input.series[0], size, dir / "curve_tc0");
  EXPECT_EQ(files.png, dir / "curve_tc0.png");
  EXPECT_EQ(files.svg, dir / "curve_tc0.svg");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
  EXPECT_NE(files.caption.find("k ="), std::string::npos) << files.caption;
}

TEST(Figures, UnfittedSeriesIsDrawnWithoutAFitAndSaysWhy) {
  testing::TempDir dir;
  CurveSeries flat = testdata::cooling_series("flat#1", 0.0, 22, 22, 50, 1.0, 0.0, 3);
  flat.fit = fitting::fit_newton(flat.time_s, flat.temperature_c);
  ASSERT_FALSE(flat.fit->ok());
  const auto files = write_curve_figure(flat, {}, dir / "flat");
  expect_png(files.png, {});
  EXPECT_NE(files.caption.find("No Newton fit"), std::string::npos) << files.caption;
}

TEST(Figures, OverviewFigureHoldsEverySeries) {
  testing::TempDir dir;
  ReportInput input = testdata::sample_input(false);
  input.series.push_back(testdata::cooling_series("probe tc0", 0.01, 79, 22, 30, 13.0, 0.5, 4));
  input.series.back().kind = SeriesKind::kBosProbe;
  fit_missing(input);
  const FigureSize size{800, 500};
  const auto files = write_overview_figure(input.series, size, dir / "all");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
}

TEST(Figures, MapFigureHasColourMaskContoursAndMarkers) {
  testing::TempDir dir;
  const MapField map = testdata::bump_map();
  const FigureSize size{900, 650};
  const auto files = write_map_figure(map, 0.05, {{"tc0", {136, 72}}}, 30.0, size, dir / "map");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
  EXPECT_NE(files.caption.find("contours every 0.05 px"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find("Axes in mm"), std::string::npos) << files.caption;
  // Colour and the mask's grey are both in the PNG.
  const cv::Mat png = cv::imread(files.png.string(), cv::IMREAD_COLOR);
  int saturated = 0, grey = 0;
  for (int r = 0; r < png.rows; ++r) {
    for (int c = 0; c < png.cols; ++c) {
      const auto p = png.at<cv::Vec3b>(r, c);
      const int spread = std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]});
      if (spread > 120) ++saturated;
      if (spread < 8 && p[0] > 170 && p[0] < 200) ++grey;  // the mask fill (190)
    }
  }
  EXPECT_GT(saturated, 5000) << "the map has no colour";
  EXPECT_GT(grey, 200) << "the masked region is not shown";
}

TEST(Figures, MapWithoutScaleUsesPixelsAndATooFineSpacingIsWidened) {
  testing::TempDir dir;
  const auto files = write_map_figure(testdata::bump_map(), 1e-5, {}, std::nullopt, {600, 400}, dir / "map");
  expect_png(files.png, {600, 400});
  EXPECT_NE(files.caption.find("Axes in px"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find("widened"), std::string::npos) << files.caption;
}

TEST(Figures, FullyMaskedAndSingleRowMapsStillDraw) {
  testing::TempDir dir;
  MapField masked = testdata::bump_map(4, 5);
  masked.mask.setTo(255);
  const auto a = write_map_figure(masked, 0.1, {}, 30.0, {600, 400}, dir / "masked");
  expect_png(a.png, {600, 400});
  EXPECT_NE(a.caption.find("Every cell is masked"), std::string::npos);
  MapField row = testdata::bump_map(1, 6);
  const auto b = write_map_figure(row, 0.1, {}, std::nullopt, {600, 400}, dir / "row");
  expect_png(b.png, {600, 400});
}

TEST(Figures, BadInputIsRefused) {
  testing::TempDir dir;
  CurveSeries empty;
  empty.name = "empty";
  EXPECT_THROW(write_curve_figure(empty, {}, dir / "x"), std::invalid_argument);
  EXPECT_THROW(write_map_figure(MapField{}, 0.1, {}, std::nullopt, {}, dir / "y"), std::invalid_argument);
  EXPECT_THROW(write_curve_figure(testdata::cooling_series("a", 0.01, 80, 20, 10, 1, 0.1, 1), {10, 10}, dir / "z"),
               std::invalid_argument);
}

TEST(Figures, AgreementFigureIsABlandAltmanPlot) {
  testing::TempDir dir;
  auto a = testdata::cooling_series("tc0", 0.01, 80, 22, 200, 2.0, 0.1, 1);
  auto b = testdata::cooling_series("probe", 0.01, 80.5, 22, 40, 10.0, 0.3, 2);
  b.kind = SeriesKind::kBosProbe;
  fitting::NewtonFitOptions from_zero;
  from_zero.origin_s = 0.0;
  a.fit = fitting::fit_newton(a.time_s, a.temperature_c, from_zero);
  b.fit = fitting::fit_newton(b.time_s, b.temperature_c, from_zero);
  const auto agreement = fitting::compare_fits(*a.fit, *b.fit, fitting::clean_series(a.time_s, a.temperature_c, 0.0),
                                               fitting::clean_series(b.time_s, b.temperature_c, 0.0));
  ASSERT_TRUE(agreement.series);
  const FigureSize size{800, 500};
  const auto files = write_agreement_figure(a, b, agreement, size, dir / "agreement");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
  EXPECT_NE(files.caption.find("bias"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find(agreement.verdict), std::string::npos);

  auto later = b;
  for (auto& t : later.time_s) t += 10000;
  EXPECT_THROW(write_agreement_figure(a, later, agreement, size, dir / "none"), std::invalid_argument);
}

TEST(Figures, AnUnwritableFileIsAnErrorNotAnExit) {
  testing::TempDir dir;
  std::filesystem::create_directory(dir / "taken.png");  // a folder where the PNG should go
  EXPECT_THROW(write_curve_figure(testdata::cooling_series("a", 0.01, 80, 20, 10, 1, 0.1, 1), {}, dir / "taken"),
               std::runtime_error);
}

}  // namespace
}  // namespace bosfuse::report
