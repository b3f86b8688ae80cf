#pragma once
// The frame every report figure is drawn in, shared by the writers of
// figures.h (one .cc per figure kind): the colours (cmap0 palette, cmap1
// colour maps), text as PLplot wants it, axis ranges, the thinning of long
// records, and render_png_and_svg(), which runs one drawing routine once per
// device — pngcairo, then svgcairo — each in its own PLplot stream on a page
// of the figure's size, so the PNG and the SVG show the same thing.
// Internal to report/'s figures; everyone else includes figures.h.

#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "report/figures.h"

namespace bosfuse::report::figure_frame {

// cmap0 of every figure: 0 background, 1 foreground, 2 grid, 3 mask grey,
// 4 mask hatch, then series colours (Tableau 10).
inline constexpr int kBackground = 0, kInk = 1, kGrid = 2, kMaskFill = 3, kMaskHatch = 4, kFirstSeries = 5;
inline constexpr std::array<std::array<int, 3>, 15> kPalette{{{255, 255, 255},
                                                              {0, 0, 0},
                                                              {200, 200, 200},
                                                              {190, 190, 190},
                                                              {110, 110, 110},
                                                              {31, 119, 180},
                                                              {214, 39, 40},
                                                              {44, 160, 44},
                                                              {255, 127, 14},
                                                              {148, 103, 189},
                                                              {140, 86, 75},
                                                              {227, 119, 194},
                                                              {127, 127, 127},
                                                              {188, 189, 34},
                                                              {23, 190, 207}}};
inline constexpr int kSeriesColours = static_cast<int>(kPalette.size()) - kFirstSeries;
// A spare cmap0 slot after the palette, set to a translucent series colour to shade a band.
inline constexpr int kBandFill = static_cast<int>(kPalette.size());

// Short, as a journal's axes are; the time basis (origin, scale) is in
// every time figure's caption.
inline constexpr const char* kTimeAxisLabel = "t (s)";

// cmap1 for signed quantities: blue – white – red (ColorBrewer RdBu),
// white at zero, so the sign is read from the hue. Every stream starts with
// viridis, for magnitudes.
void use_diverging_colour_map();

// `text` with PLplot's escape character '#' made literal.
std::string pl_text(const std::string& text);

// Characters of a UTF-8 string, for estimating how wide a label is drawn.
std::size_t codepoints(const std::string& utf8);

// A label under the plot, `disp` character heights below it, written
// smaller when it would be wider than the figure.
void bottom_label(const std::string& text, double disp);

struct Range {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  bool empty() const { return !(low <= high); }
  // Widened by a margin on both sides, never zero width.
  Range padded(double fraction) const {
    if (empty()) return {0, 1};
    const double span = high - low;
    const double pad = span > 0 ? span * fraction : std::max(std::abs(high) * 0.05, 0.5);
    return {low - pad, high + pad};
  }
};

// The indices of a record of n samples that are drawn: every one up to a few
// thousand, evenly thinned beyond (for drawing only; captions count them all).
std::vector<std::size_t> plotted_indices(std::size_t n);

// Samples as dots in `colour`, smaller the more there are.
void draw_points(const std::vector<PLFLT>& x, const std::vector<PLFLT>& y, int colour);

// The PNG and SVG paths of a figure at `base` (no titles yet).
FigureFiles files_for(const std::filesystem::path& base);

// Runs `draw` once into each of files.png and files.svg, under the process-wide
// PLplot lock, each file put in place only once both are whole. Throws
// std::invalid_argument for a size outside 100..10000 px and
// std::runtime_error when the cairo devices are missing or a file cannot be written.
void render_png_and_svg(const FigureFiles& files, const FigureSize& size, const std::function<void()>& draw);

}  // namespace bosfuse::report::figure_frame
