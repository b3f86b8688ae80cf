#pragma once
// The report's figures, drawn with PLplot and written twice: as PNG (device
// pngcairo) and as SVG (device svgcairo), from one drawing routine so both
// show the same thing. `base` is a path without extension; the writers add
// ".png" and ".svg". A PNG is exactly width_px × height_px; an SVG's
// viewBox is the same size (its width and height are in points).
//
// PLplot keeps global state: these functions draw one figure at a time
// (a process-wide lock), each in its own PLplot stream ended before they
// return; other PLplot users in the process must not run meanwhile. They throw
// std::runtime_error when the cairo devices are missing (Debian package
// plplot-driver-cairo) or the input has nothing to draw.
//
// Each kind of figure is drawn in its own file (curve_figure.cc,
// overview_figure.cc, agreement_figure.cc, map_figure.cc), all in the frame
// of figure_frame.h.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "report/report_input.h"

namespace bosfuse::report {

struct FigureSize {
  int width_px = 900;
  int height_px = 600;
};

struct FigureFiles {
  std::filesystem::path png;
  std::filesystem::path svg;
  std::string title;    // short, for the HTML
  std::string caption;  // a sentence or two saying what is drawn
};

// True when PLplot has both the pngcairo and the svgcairo device.
bool cairo_devices_available();

// One series: its samples, the fitted Newton curve (when fitted) shaded with
// its confidence band (NewtonFit::temperature_half_width_at, at the fit's
// confidence) and, below, the residuals (data − fit). The time axis is
// labelled with `time_basis` (ReportInput::time_basis).
FigureFiles write_curve_figure(const CurveSeries& series, const FigureSize& size, const std::filesystem::path& base,
                               const std::string& time_basis = kDefaultTimeBasis);

// Every series on one plot with its fitted curve and band, for comparison.
FigureFiles write_overview_figure(const std::vector<CurveSeries>& series, const FigureSize& size,
                                  const std::filesystem::path& base, const std::string& time_basis = kDefaultTimeBasis);

// The pairs of a thermocouple (a) and its BOS probe (b) that the agreement
// compares (fitting/agreement.h): one at each of b's times — the BOS frames —
// within a's record, a interpolated there and de-lagged by the agreement's
// τ (with a's own fit, as the agreement does; a τ > 0 without a fit of a
// leaves no pairs rather than lagged ones). So their count is the
// agreement's common_points, and their differences give its bias and RMS.
struct AgreementPairs {
  std::vector<double> time_s;        // b's
  std::vector<double> mean_c;        // (a + b) / 2
  std::vector<double> difference_c;  // a − b
  double time_constant_s = 0;        // the τ removed from a
};
AgreementPairs agreement_pairs(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement);

// Bland–Altman plot of a thermocouple (a) against its BOS probe (b): the
// difference a − b against the mean of the two at agreement_pairs' pairs,
// with the bias and the limits of agreement of `agreement` when it has
// series statistics. Throws std::invalid_argument when there are fewer
// than two pairs.
FigureFiles write_agreement_figure(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement,
                                   const FigureSize& size, const std::filesystem::path& base);

struct MapMarker {
  std::string name;
  cv::Point2d image_px;
};

// A map like the paper's figures: colour-filled bands, contour lines every
// `contour_spacing` (in the map's unit; 0: none), a colour bar, masked cells
// hatched grey, thermocouple markers, and axes in mm when px_per_mm is
// given (else in px), y pointing down as in the image.
FigureFiles write_map_figure(const MapField& map, double contour_spacing, const std::vector<MapMarker>& markers,
                             std::optional<double> px_per_mm, const FigureSize& size,
                             const std::filesystem::path& base);

// The base of a figure named by its PNG ("map.png" → "map"; the SVG goes
// beside it). Throws std::invalid_argument for a name not ending in .png.
std::filesystem::path figure_base(const std::filesystem::path& png_path);

}  // namespace bosfuse::report
