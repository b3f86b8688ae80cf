// write_overview_figure() of figures.h: every series on one plot with its fit, and a legend.
#include <plplot.h>

#include <cmath>
#include <stdexcept>

#include "report/figure_frame.h"
#include "report/figures.h"
#include "report/fitted_curve_plot.h"

namespace bosfuse::report {

using namespace figure_frame;  // the frame every figure draws in (figure_frame.h)

namespace {

namespace fs = std::filesystem;

int series_colour(std::size_t i) { return kFirstSeries + static_cast<int>(i % kSeriesColours); }

// Each series' finite samples (thinned) and fitted curve, and the axes'
// ranges (padded) over all of them.
struct OverviewPlot {
  std::vector<std::vector<PLFLT>> ts, ys;
  std::vector<FittedCurve> curves;
  Range t_range, y_range;
};

OverviewPlot overview_plot(const std::vector<CurveSeries>& series) {
  OverviewPlot plot;
  plot.ts.resize(series.size());
  plot.ys.resize(series.size());
  plot.curves.resize(series.size());
  Range tr, yr;
  for (std::size_t s = 0; s < series.size(); ++s) {
    const auto& cs = series[s];
    if (cs.time_s.size() != cs.temperature_c.size()) {
      throw std::invalid_argument("series '" + cs.name + "': times and temperatures differ in length");
    }
    Range own;
    for (std::size_t i : plotted_indices(cs.time_s.size())) {
      if (!std::isfinite(cs.time_s[i]) || !std::isfinite(cs.temperature_c[i])) continue;
      plot.ts[s].push_back(cs.time_s[i]);
      plot.ys[s].push_back(cs.temperature_c[i]);
      tr.add(cs.time_s[i]);
      own.add(cs.time_s[i]);
      yr.add(cs.temperature_c[i]);
    }
    if (fitted(cs) && !own.empty()) {
      plot.curves[s] = fitted_curve(*cs.fit, own.low, own.high);
      add_curve(yr, plot.curves[s]);
    }
  }
  if (tr.empty()) throw std::invalid_argument("no finite samples to draw");
  plot.t_range = tr.padded(0.02);
  plot.y_range = yr.padded(0.05);
  return plot;
}

// Bands, then every fit line, then every series' points on top: a fit
// never hides the measurements it was fitted to.
void draw_series(const std::vector<CurveSeries>& series, const OverviewPlot& plot) {
  for (std::size_t s = 0; s < series.size(); ++s) draw_band(plot.curves[s], series_colour(s));
  for (std::size_t s = 0; s < series.size(); ++s) draw_line(plot.curves[s], series_colour(s));
  for (std::size_t s = 0; s < series.size(); ++s) {
    if (series[s].kind != SeriesKind::kBosProbe) draw_points(plot.ts[s], plot.ys[s], series_colour(s));
  }
  // BOS frames are few (tens): large bold crosses over the dense thermocouple dots.
  for (std::size_t s = 0; s < series.size(); ++s) {
    if (series[s].kind != SeriesKind::kBosProbe) continue;
    plcol0(series_colour(s));
    plwidth(2.5);
    plssym(0, 1.3);
    plpoin(static_cast<PLINT>(plot.ts[s].size()), plot.ts[s].data(), plot.ys[s].data(), 5);  // 5: ×
    plssym(0, 1);
    plwidth(1);
  }
}

// One entry per series, inside the plot's top right corner: its colour's
// line (when fitted) and its symbol.
void draw_legend(const std::vector<CurveSeries>& series, const std::vector<FittedCurve>& curves) {
  const auto n = static_cast<PLINT>(series.size());
  std::vector<PLINT> opts(n, PL_LEGEND_LINE | PL_LEGEND_SYMBOL), colours(n), styles(n, 1), symbol_numbers(n, 3),
      text_colours(n, kInk), box_colours(n, 0), box_patterns(n, 0);
  std::vector<PLFLT> widths(n, 2.0), symbol_scales(n, 0.8), box_scales(n, 0.8), box_widths(n, 1.0);
  std::vector<std::string> texts(n), symbols(n);
  std::vector<const char*> text_ptrs(n), symbol_ptrs(n);
  for (PLINT s = 0; s < n; ++s) {
    colours[s] = series_colour(s);
    if (curves[s].t.empty()) opts[s] = PL_LEGEND_SYMBOL;  // no fitted curve to show
    texts[s] = pl_text(series[s].name);
    symbols[s] = series[s].kind == SeriesKind::kBosProbe ? "×" : "•";
    text_ptrs[s] = texts[s].c_str();
    symbol_ptrs[s] = symbols[s].c_str();
  }
  PLFLT legend_width = 0, legend_height = 0;
  plschr(0, 0.85);
  pllegend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_RIGHT | PL_POSITION_TOP | PL_POSITION_INSIDE | PL_POSITION_VIEWPORT, 0.02, 0.02, 0.06,
           kBackground, kInk, 1, 0, 0, n, opts.data(), 1.0, 0.85, 2.0, 0.0, text_colours.data(), text_ptrs.data(),
           box_colours.data(), box_patterns.data(), box_scales.data(), box_widths.data(), colours.data(),
           styles.data(), widths.data(), colours.data(), symbol_scales.data(), symbol_numbers.data(),
           symbol_ptrs.data());
  plschr(0, 1);
}

}  // namespace

FigureFiles write_overview_figure(const std::vector<CurveSeries>& series, const FigureSize& size, const fs::path& base,
                                  const std::string& time_basis) {
  if (series.empty()) throw std::invalid_argument("no series to draw");
  FigureFiles files = files_for(base);
  files.title = "All cooling curves";
  files.caption =
      "Every series (points) with its fitted Newton curve (line of the same colour) and the curve's confidence band "
      "(shaded); thermocouples as dots, BOS probes as crosses. t in " +
      time_basis + ".";
  const OverviewPlot plot = overview_plot(series);
  render_png_and_svg(files, size, [&] {
    plvpor(0.1, 0.95, 0.12, 0.92);
    plwind(plot.t_range.low, plot.t_range.high, plot.y_range.low, plot.y_range.high);
    plcol0(kGrid);
    plbox("g", 0, 0, "g", 0, 0);
    plcol0(kInk);
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    pllab("", "temperature (°C)", "All cooling curves");
    bottom_label(kTimeAxisLabel, 3.2);
    draw_series(series, plot);
    draw_legend(series, plot.curves);
  });
  return files;
}

}  // namespace bosfuse::report
