#include "report/figures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <vector>

#include "report/test_data.h"
#include "tests/support/file_bytes.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

// A well-formedness check of XML, enough for the files cairo writes:
// elements nest and close in order, attributes are name="value" (or with
// single quotes), one root element, and declarations, comments and CDATA
// are skipped. `error` is empty when the text is well formed.
struct XmlCheck {
  std::string error;
  std::string root_name;
  std::string root_tag;  // the root's start tag, attributes included
};

XmlCheck check_xml(const std::string& text) {
  XmlCheck out;
  std::vector<std::string> open;
  bool root_closed = false;
  const auto blank = [&](std::size_t from, std::size_t to) { return text.find_first_not_of(" \t\r\n", from) >= to; };
  std::size_t i = 0;
  for (std::size_t steps = 0; i < text.size() && steps < 10'000'000; ++steps) {
    const std::size_t lt = text.find('<', i);
    if (open.empty() && !blank(i, lt == std::string::npos ? text.size() : lt)) {
      return {"text outside the root element", out.root_name, out.root_tag};
    }
    if (lt == std::string::npos) break;
    const auto skip_to = [&](const char* end) {
      const auto e = text.find(end, lt);
      return e == std::string::npos ? std::string::npos : e + std::strlen(end);
    };
    std::size_t next = std::string::npos;
    if (text.compare(lt, 2, "<?") == 0) {
      next = skip_to("?>");
    } else if (text.compare(lt, 4, "<!--") == 0) {
      next = skip_to("-->");
    } else if (text.compare(lt, 9, "<![CDATA[") == 0) {
      next = skip_to("]]>");
    } else if (text.compare(lt, 2, "<!") == 0) {
      next = skip_to(">");
    }
    if (text.compare(lt, 2, "<?") == 0 || text.compare(lt, 2, "<!") == 0) {
      if (next == std::string::npos) return {"unterminated declaration or comment", out.root_name, out.root_tag};
      i = next;
      continue;
    }
    // A tag: find its end outside quoted attribute values.
    std::size_t gt = lt + 1;
    char quote = 0;
    for (; gt < text.size(); ++gt) {
      if (quote) {
        if (text[gt] == quote) quote = 0;
      } else if (text[gt] == '"' || text[gt] == '\'') {
        quote = text[gt];
      } else if (text[gt] == '>') {
        break;
      }
    }
    if (gt >= text.size()) return {"unterminated tag", out.root_name, out.root_tag};
    std::string tag = text.substr(lt + 1, gt - lt - 1);
    if (!tag.empty() && tag[0] == '/') {
      const std::string name = tag.substr(1, tag.find_last_not_of(" \t\r\n"));
      if (open.empty() || open.back() != name)
        return {"</" + name + "> closes nothing open", out.root_name, out.root_tag};
      open.pop_back();
      root_closed = open.empty();
    } else {
      const bool self_closing = !tag.empty() && tag.back() == '/';
      if (self_closing) tag.pop_back();
      const auto name_end = tag.find_first_of(" \t\r\n");
      const std::string name = tag.substr(0, name_end);
      if (name.empty()) return {"empty tag name", out.root_name, out.root_tag};
      for (std::size_t p = name_end; p != std::string::npos && p < tag.size();) {
        p = tag.find_first_not_of(" \t\r\n", p);
        if (p == std::string::npos) break;
        const auto eq = tag.find('=', p);
        if (eq == std::string::npos) return {"attribute without value in <" + name + ">", out.root_name, out.root_tag};
        const auto value = tag.find_first_not_of(" \t\r\n", eq + 1);
        if (value == std::string::npos || (tag[value] != '"' && tag[value] != '\'')) {
          return {"unquoted attribute in <" + name + ">", out.root_name, out.root_tag};
        }
        const auto close = tag.find(tag[value], value + 1);
        if (close == std::string::npos) return {"unclosed attribute in <" + name + ">", out.root_name, out.root_tag};
        p = close + 1;
      }
      if (open.empty()) {
        if (root_closed || !out.root_name.empty())
          return {"a second root element <" + name + ">", out.root_name, out.root_tag};
        out.root_name = name;
        out.root_tag = text.substr(lt, gt - lt + 1);
      }
      if (!self_closing) {
        open.push_back(name);
      } else if (open.empty()) {
        root_closed = true;
      }
    }
    i = gt + 1;
  }
  if (!open.empty()) return {"<" + open.back() + "> is never closed", out.root_name, out.root_tag};
  if (out.root_name.empty()) return {"no element", out.root_name, out.root_tag};
  return out;
}

// The SVG is well-formed XML with an <svg> root whose viewBox is the figure's size.
void expect_svg(const std::filesystem::path& path, const FigureSize& size) {
  const auto xml = check_xml(testing::file_bytes(path));
  ASSERT_EQ(xml.error, "") << path;
  EXPECT_EQ(xml.root_name, "svg") << path;
  EXPECT_NE(xml.root_tag.find("viewBox=\"0 0 " + std::to_string(size.width_px) + " " + std::to_string(size.height_px)),
            std::string::npos)
      << xml.root_tag;
}

TEST(XmlCheck, TellsWellFormedFromBroken) {
  EXPECT_EQ(check_xml("<?xml version=\"1.0\"?>\n<svg a=\"1\"><g><path d='M 0 0'/></g><!-- c --></svg>\n").error, "");
  EXPECT_EQ(check_xml("<svg><g></svg>").error, "</svg> closes nothing open");
  EXPECT_EQ(check_xml("<svg><g>").error, "<g> is never closed");
  EXPECT_EQ(check_xml("<svg a=1></svg>").error, "unquoted attribute in <svg>");
  EXPECT_EQ(check_xml("<svg></svg><svg></svg>").error, "a second root element <svg>");
  EXPECT_EQ(check_xml("<svg></svg> trailing").error, "text outside the root element");
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

// The band is where the true curve may lie: light red around the red fitted
// line, wide enough to see on a short, noisy record. A fit without its
// covariance (stored before it was kept) has none, and the caption says so.
TEST(Figures, TheFittedCurveIsShadedWithItsConfidenceBand) {
  testing::TempDir dir;
  CurveSeries noisy = testdata::cooling_series("noisy", 0.02, 80, 22, 25, 4.0, 3.0, 6);
  noisy.fit = fitting::fit_newton(noisy.time_s, noisy.temperature_c);
  ASSERT_TRUE(noisy.fit->ok()) << noisy.fit->brief_report();
  ASSERT_GT(noisy.fit->temperature_half_width_at(50.0), 0.5);
  const auto band_pixels = [](const std::filesystem::path& png_file) {
    const cv::Mat png = cv::imread(png_file.string(), cv::IMREAD_COLOR);
    int count = 0;
    for (int r = 0; r < png.rows; ++r) {
      for (int c = 0; c < png.cols; ++c) {
        const auto p = png.at<cv::Vec3b>(r, c);  // BGR; (214, 39, 40) at 22% over white is about (246, 207, 207)
        count += std::abs(p[2] - 246) < 8 && std::abs(p[1] - 207) < 10 && std::abs(p[0] - 207) < 10;
      }
    }
    return count;
  };
  const auto files = write_curve_figure(noisy, {}, dir / "band", "experiment seconds since heater off");
  expect_png(files.png, {});
  expect_svg(files.svg, {});
  EXPECT_NE(files.caption.find("95% confidence band"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find("t in experiment seconds since heater off"), std::string::npos) << files.caption;
  const int with_band = band_pixels(files.png);
  std::printf("band-coloured pixels: %d with the band\n", with_band);
  EXPECT_GT(with_band, 1000);

  CurveSeries stored = noisy;
  stored.fit->covariance.reset();
  const auto without = write_curve_figure(stored, {}, dir / "no_band");
  EXPECT_NE(without.caption.find("no confidence band"), std::string::npos) << without.caption;
  const int without_band = band_pixels(without.png);  // anti-aliased edges of the red line and points
  std::printf("band-coloured pixels: %d without\n", without_band);
  EXPECT_LT(without_band, with_band / 10);
}

TEST(Figures, OverviewFigureHoldsEverySeries) {
  testing::TempDir dir;
  ReportInput input = testdata::sample_input(false);
  input.series.push_back(testdata::cooling_series("probe tc0", 0.01, 79, 22, 30, 13.0, 0.5, 4));
  input.series.back().kind = SeriesKind::kBosProbe;
  fit_missing(input);
  const FigureSize size{800, 500};
  const auto files = write_overview_figure(input.series, size, dir / "all", "s since heater off");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
  EXPECT_NE(files.caption.find("confidence band"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find("t in s since heater off"), std::string::npos) << files.caption;
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

// Pixels of the PNG within `tolerance` (per channel) of an RGB colour.
int pixels_near(const cv::Mat& png, std::array<int, 3> rgb, int tolerance) {
  int n = 0;
  for (int r = 0; r < png.rows; ++r) {
    for (int c = 0; c < png.cols; ++c) {
      const auto p = png.at<cv::Vec3b>(r, c);  // BGR
      if (std::abs(p[2] - rgb[0]) <= tolerance && std::abs(p[1] - rgb[1]) <= tolerance &&
          std::abs(p[0] - rgb[2]) <= tolerance) {
        ++n;
      }
    }
  }
  return n;
}

// Magnitudes in viridis (its yellow top and purple bottom, none of jet's
// dark red); values of both signs in a diverging map, white at zero.
TEST(Figures, MapsUseViridisForMagnitudesAndADivergingMapForSignedValues) {
  testing::TempDir dir;
  const auto bump = write_map_figure(testdata::bump_map(), 0, {}, std::nullopt, {900, 650}, dir / "bump");
  const cv::Mat magnitude = cv::imread(bump.png.string(), cv::IMREAD_COLOR);
  EXPECT_GT(pixels_near(magnitude, {253, 231, 37}, 30), 50) << "no viridis yellow at the bump's top";
  EXPECT_GT(pixels_near(magnitude, {68, 1, 84}, 20), 5000) << "no viridis purple at the bottom";
  EXPECT_EQ(pixels_near(magnitude, {128, 0, 0}, 30), 0) << "jet's dark red is still there";
  EXPECT_EQ(bump.caption.find("blue below zero"), std::string::npos);

  MapField ramp = testdata::bump_map();
  ramp.mask.setTo(0);
  for (int r = 0; r < ramp.values.rows; ++r) {
    for (int c = 0; c < ramp.values.cols; ++c) ramp.values.at<double>(r, c) = (c - 15.5) / 15.5;  // −1 … +1
  }
  const auto files = write_map_figure(ramp, 0, {}, std::nullopt, {900, 650}, dir / "ramp");
  const cv::Mat signed_map = cv::imread(files.png.string(), cv::IMREAD_COLOR);
  EXPECT_GT(pixels_near(signed_map, {33, 102, 172}, 30), 1000) << "no blue for the negative end";
  EXPECT_GT(pixels_near(signed_map, {178, 24, 43}, 30), 1000) << "no red for the positive end";
  EXPECT_NE(files.caption.find("blue below zero, red above, white at zero"), std::string::npos) << files.caption;
}

// Arrows only when asked, and only where something was measured.
TEST(Figures, ADisplacementMapDrawsArrowsWhenAsked) {
  testing::TempDir dir;
  MapField map = testdata::bump_map();
  map.u_px = cv::Mat(map.values.size(), CV_64F, cv::Scalar(0.3));
  map.v_px = cv::Mat(map.values.size(), CV_64F, cv::Scalar(-0.1));
  const auto count_dark = [](const std::filesystem::path& png_file) {
    const cv::Mat png = cv::imread(png_file.string(), cv::IMREAD_COLOR);
    int n = 0;
    for (int r = 0; r < png.rows; ++r) {
      for (int c = 0; c < png.cols; ++c) n += png.at<cv::Vec3b>(r, c)[1] < 40 && png.at<cv::Vec3b>(r, c)[2] < 40;
    }
    return n;
  };
  const auto plain = write_map_figure(map, 0, {}, std::nullopt, {900, 650}, dir / "plain");
  map.arrows = true;
  const auto arrows = write_map_figure(map, 0, {}, std::nullopt, {900, 650}, dir / "arrows");
  EXPECT_GT(count_dark(arrows.png), count_dark(plain.png) + 1000) << "no arrows drawn";
  EXPECT_NE(arrows.caption.find("Arrows: the measured displacement"), std::string::npos) << arrows.caption;
  EXPECT_EQ(plain.caption.find("Arrows"), std::string::npos);
  map.u_px = cv::Mat();
  EXPECT_THROW(write_map_figure(map, 0, {}, std::nullopt, {900, 650}, dir / "bad"), std::invalid_argument);
}

// A pair evaluated outside a run has no time: its map says none.
TEST(Figures, AMapWithoutATimeStatesNone) {
  testing::TempDir dir;
  MapField map = testdata::bump_map();
  map.time_s.reset();
  const auto files = write_map_figure(map, 0, {}, std::nullopt, {900, 650}, dir / "pair");
  EXPECT_EQ(files.title, "|displacement|");
  EXPECT_EQ(files.caption.find("t = "), std::string::npos) << files.caption;
}

// The plot frame of a map figure in PNG pixels: the black box plbox draws
// round the viewport (the colour bar's box, further right, is the second
// pair of long vertical lines and is not taken).
struct PlotFrame {
  int left = -1, right = -1, top = -1, bottom = -1;
};

bool dark(const cv::Vec3b& p) { return p[0] < 80 && p[1] < 80 && p[2] < 80; }
// A frame line, antialiased over half pixels: grey-dark, with no colour.
bool frame_ink(const cv::Vec3b& p) {
  return std::max({p[0], p[1], p[2]}) < 150 && std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}) < 30;
}

PlotFrame plot_frame(const cv::Mat& png) {
  PlotFrame f;
  auto longest_run = [&](int n, auto&& is_dark) {
    int best = 0, run = 0;
    for (int i = 0; i < n; ++i) best = std::max(best, run = is_dark(i) ? run + 1 : 0);
    return best;
  };
  for (int r = 0; r < png.rows; ++r) {
    if (longest_run(png.cols, [&](int c) { return frame_ink(png.at<cv::Vec3b>(r, c)); }) > png.cols / 3) {
      if (f.top < 0) f.top = r;
      f.bottom = r;
    }
  }
  std::vector<int> lines;
  for (int c = 0; c < png.cols && f.top >= 0; ++c) {
    if (longest_run(png.rows, [&](int r) { return frame_ink(png.at<cv::Vec3b>(r, c)); }) > (f.bottom - f.top) * 9 / 10) {
      if (lines.empty() || c > lines.back() + 3) lines.push_back(c);
    }
  }
  if (lines.size() >= 2) {
    f.left = lines[0];
    f.right = lines[1];
  }
  return f;
}

// Not measured: hatched, and no contour is computed from or through a
// node that holds no measurement. The cells round the mask (whose corners
// include a masked node) are where the old filled-in values made contours
// run up to the hatch; here they carry none.
TEST(Figures, AMapHatchesWhatWasNotMeasuredAndContoursNoneOfIt) {
  testing::TempDir dir;
  MapField map = testdata::bump_map();
  map.mask.setTo(0);
  const cv::Rect hole(12, 4, 9, 8);  // columns 12..20, rows 4..11 of the grid: across the bump's peak
  map.mask(hole).setTo(255);
  map.values(hole).setTo(std::numeric_limits<double>::quiet_NaN());
  const FigureSize size{900, 700};
  const auto files = write_map_figure(map, 0.01, {}, std::nullopt, size, dir / "map");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
  EXPECT_NE(files.caption.find("hatched grey: masked or not measured (72 of 768 cells)"), std::string::npos)
      << files.caption;
  EXPECT_NE(files.caption.find("no contour is drawn"), std::string::npos) << files.caption;

  const cv::Mat png = cv::imread(files.png.string(), cv::IMREAD_COLOR);
  const PlotFrame frame = plot_frame(png);
  ASSERT_GT(frame.right - frame.left, 300) << "no plot frame found";
  ASSERT_GT(frame.bottom - frame.top, 200);
  // World (image px) to PNG px: the axes span -0.5 .. extent - 0.5, y down.
  const auto px = [&](double x) {
    return frame.left + (x + 0.5) / map.image_size_px.width * (frame.right - frame.left);
  };
  const auto py = [&](double y) {
    return frame.top + (y + 0.5) / map.image_size_px.height * (frame.bottom - frame.top);
  };
  const auto node_x = [&](double c) { return map.x0_px + c * map.step_px; };
  const auto node_y = [&](double r) { return map.y0_px + r * map.step_px; };
  // The masked cells: grey and hatched.
  int hatch = 0, fill = 0, inside = 0;
  for (int r = static_cast<int>(py(node_y(hole.y - 0.5))) + 2; r < py(node_y(hole.y + hole.height - 0.5)) - 2; ++r) {
    for (int c = static_cast<int>(px(node_x(hole.x - 0.5))) + 2; c < px(node_x(hole.x + hole.width - 0.5)) - 2; ++c) {
      const auto p = png.at<cv::Vec3b>(r, c);
      ++inside;
      hatch += p[0] < 140 && p[0] > 80 && p[1] < 140 && p[1] > 80 && p[2] < 140 && p[2] > 80;  // the hatch (110)
      fill += p[0] > 175 && p[0] < 205 && p[1] > 175 && p[1] < 205 && p[2] > 175 && p[2] < 205;  // the grey (190)
    }
  }
  ASSERT_GT(inside, 2000);
  EXPECT_GT(hatch, inside / 20) << "the not-measured cells are not hatched";
  EXPECT_GT(fill, inside / 2) << "the not-measured cells are not grey";
  EXPECT_LT(hatch + fill, inside + 1);
  // No contour pixel (black) from the masked nodes out to the measured nodes round them.
  int contour_inside = 0, contour_outside = 0;
  const cv::Rect2d ring(px(node_x(hole.x - 1)) + 2, py(node_y(hole.y - 1)) + 2,
                        px(node_x(hole.x + hole.width)) - px(node_x(hole.x - 1)) - 4,
                        py(node_y(hole.y + hole.height)) - py(node_y(hole.y - 1)) - 4);
  for (int r = frame.top + 3; r < frame.bottom - 3; ++r) {
    for (int c = frame.left + 3; c < frame.right - 3; ++c) {
      if (!dark(png.at<cv::Vec3b>(r, c))) continue;
      (ring.contains(cv::Point2d(c, r)) ? contour_inside : contour_outside) += 1;
    }
  }
  EXPECT_EQ(contour_inside, 0) << "a contour is drawn where a corner of its cell was not measured";
  EXPECT_GT(contour_outside, 500) << "the measured part has its contours";
}

TEST(Figures, MapWithoutScaleUsesPixelsAndATooFineSpacingIsWidened) {
  testing::TempDir dir;
  const auto files = write_map_figure(testdata::bump_map(), 1e-5, {}, std::nullopt, {600, 400}, dir / "map");
  expect_png(files.png, {600, 400});
  EXPECT_NE(files.caption.find("Axes in px"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find("widened"), std::string::npos) << files.caption;
}

TEST(Figures, APerPixelFieldIsAveragedForDrawing) {
  testing::TempDir dir;
  MapField field;
  field.quantity = "temperature";
  field.unit = "°C";
  field.values = cv::Mat(600, 800, CV_32F);
  field.mask = cv::Mat::zeros(600, 800, CV_8U);
  for (int r = 0; r < 600; ++r) {
    for (int c = 0; c < 800; ++c)
      field.values.at<float>(r, c) = 22 + 40 * std::exp(-((c - 400) * (c - 400) + (r - 200) * (r - 200)) / 2e4);
  }
  field.mask(cv::Rect(350, 450, 100, 150)).setTo(255);
  field.x0_px = 0;
  field.y0_px = 0;
  field.step_px = 1;
  const FigureSize size{900, 650};
  const auto files = write_map_figure(field, 5.0, {{"tc0", {300, 150}}}, 30.0, size, dir / "temperature");
  expect_png(files.png, size);
  expect_svg(files.svg, size);
  EXPECT_NE(files.caption.find("averaged over 4×4 cells of the 800×600 grid"), std::string::npos) << files.caption;
  EXPECT_LT(std::filesystem::file_size(files.svg), 8'000'000u);
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

// Issue 29: the Bland–Altman plot shows the agreement's own pairs — one at
// each BOS frame (24, between the thermocouple's 200 readings), the
// thermocouple interpolated there and de-lagged by the agreement's τ — so
// its n is the frame count, and its points' mean and RMS are the
// agreement's bias and RMS difference, which fitting/ computed on its own.
TEST(Figures, AgreementFigurePlotsTheAgreementsPairsAtTheFramesDelagged) {
  testing::TempDir dir;
  constexpr double kK = 0.01, kTau = 3.0, kAmbient = 22, kRise = 58;
  CurveSeries a, b;
  a.name = "tc0";
  b.name = "tc0_probe";
  b.kind = SeriesKind::kBosProbe;
  std::mt19937 random(4);
  std::normal_distribution<double> noise(0, 0.05);
  for (int i = 0; i < 200; ++i) {  // a lagged sensor's reading: the amplitude over (1 − kτ)
    a.time_s.push_back(2.0 * i);
    a.temperature_c.push_back(kAmbient + kRise / (1 - kK * kTau) * std::exp(-kK * 2.0 * i) + noise(random));
  }
  for (int f = 0; f < 24; ++f) {  // the frames, between the readings
    b.time_s.push_back(5.3 + 15.0 * f);
    b.temperature_c.push_back(kAmbient + kRise * std::exp(-kK * b.time_s.back()) + 2 * noise(random));
  }
  fitting::NewtonFitOptions from_zero;
  from_zero.origin_s = 0.0;
  a.fit = fitting::fit_newton(a.time_s, a.temperature_c, from_zero);
  b.fit = fitting::fit_newton(b.time_s, b.temperature_c, from_zero);
  fitting::AgreementOptions given;
  given.a_time_constant_s = kTau;
  const auto agreement = fitting::compare_fits(*a.fit, *b.fit, fitting::clean_series(a.time_s, a.temperature_c, 0.0),
                                               fitting::clean_series(b.time_s, b.temperature_c, 0.0), given);
  ASSERT_TRUE(agreement.series);
  ASSERT_EQ(agreement.series->common_points, 24u);

  const AgreementPairs pairs = agreement_pairs(a, b, agreement);
  ASSERT_EQ(pairs.difference_c.size(), agreement.series->common_points) << "n is the BOS frames, not a's readings";
  EXPECT_EQ(pairs.time_s, b.time_s);
  EXPECT_EQ(pairs.time_constant_s, kTau);
  double sum = 0, sum_squares = 0;
  for (double d : pairs.difference_c) sum += d, sum_squares += d * d;
  EXPECT_NEAR(sum / 24, agreement.series->bias_c, 1e-12);
  EXPECT_NEAR(std::sqrt(sum_squares / 24), agreement.series->rms_difference_c, 1e-12);
  EXPECT_LT(std::abs(agreement.series->bias_c), 0.1) << "de-lagged, the lag is no bias";
  EXPECT_GT(std::abs(agreement.series->bias_as_read_c), 0.5) << "as read it would have been";
  for (std::size_t i = 0; i < pairs.mean_c.size(); ++i)
    EXPECT_NEAR(pairs.mean_c[i], b.temperature_c[i] + 0.5 * pairs.difference_c[i], 1e-12);

  const auto files = write_agreement_figure(a, b, agreement, {800, 500}, dir / "agreement");
  expect_png(files.png, {800, 500});
  EXPECT_NE(files.caption.find("n = 24"), std::string::npos) << files.caption;
  EXPECT_NE(files.caption.find("de-lagged by τ = 3 s"), std::string::npos) << files.caption;

  // A τ to remove but no fit of a to remove it with: no lagged pairs drawn in its place.
  CurveSeries unfitted = a;
  unfitted.fit.reset();
  EXPECT_TRUE(agreement_pairs(unfitted, b, agreement).mean_c.empty());
  EXPECT_THROW(write_agreement_figure(unfitted, b, agreement, {800, 500}, dir / "none"), std::invalid_argument);
}

TEST(Figures, ALongRecordIsThinnedForDrawingOnly) {
  testing::TempDir dir;
  CurveSeries long_record = testdata::cooling_series("long", 0.001, 80, 22, 200'000, 0.01, 0.2, 5);
  long_record.fit = fitting::fit_newton(long_record.time_s, long_record.temperature_c);
  ASSERT_TRUE(long_record.fit->ok());
  const auto files = write_curve_figure(long_record, {}, dir / "long");
  expect_png(files.png, {});
  expect_svg(files.svg, {});
  EXPECT_LT(std::filesystem::file_size(files.svg), 8'000'000u) << "the SVG must stay openable";
  EXPECT_NE(files.caption.find("200000 points"), std::string::npos) << files.caption;
}

TEST(Figures, AnUnwritableFileIsAnErrorNotAnExit) {
  testing::TempDir dir;
  std::filesystem::create_directory(dir / "taken.png");  // a folder where the PNG should go
  EXPECT_THROW(write_curve_figure(testdata::cooling_series("a", 0.01, 80, 20, 10, 1, 0.1, 1), {}, dir / "taken"),
               std::runtime_error);
}

}  // namespace
}  // namespace bosfuse::report
