// write_curve_figure() of figures.h: one series, its fit and band, and the residuals below.
#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "report/figure_frame.h"
#include "report/figures.h"
#include "report/fitted_curve_plot.h"
#include "report/html.h"

namespace bosfuse::report {

using namespace figure_frame;  // the frame every figure draws in (figure_frame.h)

namespace {

namespace fs = std::filesystem;

std::string format_estimate(const fitting::Estimate& e, const char* unit) {
  if (e.fixed) return fmt::format("{} {} (fixed)", display_number(e.value, "{:.4g}"), unit);
  return fmt::format("{} {} [{}, {}]", display_number(e.value, "{:.4g}"), unit, display_number(e.low, "{:.4g}"),
                     display_number(e.high, "{:.4g}"));
}

std::string value_label(const CurveSeries& s) {
  return pl_text(s.unit == "°C" ? std::string("temperature (°C)") : "value (" + s.unit + ")");
}

std::string band_caption(const CurveSeries& s) {
  if (s.fit->covariance) {
    return fmt::format(", shaded with its {:.0f}% confidence band", 100 * s.fit->summary.confidence);
  }
  return " (no confidence band: the stored fit has no covariance)";
}

std::string curve_caption(const CurveSeries& series, const std::string& time_basis) {
  if (!fitted(series)) {
    return fmt::format("Samples of {} ({} points). No Newton fit: {}. t in {}.", series.name, series.time_s.size(),
                       series.fit ? series.fit->summary.message : std::string("not fitted"), time_basis);
  }
  return fmt::format(
      "Samples of {} ({} points) with the fitted Newton curve (red){}; below, the residuals "
      "(data − fit). k = {}, τ = {}. t in {}.",
      series.name, series.time_s.size(), band_caption(series), format_estimate(series.fit->k_per_s, "1/s"),
      format_estimate(series.fit->tau_s, "s"), time_basis);
}

// What the figure draws: the finite samples (thinned), their residuals and
// the fitted curve when there is a fit, and the axes' ranges.
struct CurvePlot {
  bool has_fit = false;
  std::vector<PLFLT> t, temp, residual;
  FittedCurve curve;
  Range t_range, temp_range;  // padded
  double residual_max = 1.0;  // the residual axis is symmetric about zero
};

CurvePlot curve_plot(const CurveSeries& series) {
  CurvePlot plot;
  plot.has_fit = fitted(series);
  Range t_range, temp_range, residual_range;
  for (std::size_t i : plotted_indices(series.time_s.size())) {
    if (!std::isfinite(series.time_s[i]) || !std::isfinite(series.temperature_c[i])) continue;
    plot.t.push_back(series.time_s[i]);
    plot.temp.push_back(series.temperature_c[i]);
    t_range.add(plot.t.back());
    temp_range.add(plot.temp.back());
    if (plot.has_fit) {
      plot.residual.push_back(plot.temp.back() - series.fit->temperature_at(plot.t.back()));
      residual_range.add(plot.residual.back());
    }
  }
  if (plot.t.empty()) throw std::invalid_argument("series '" + series.name + "' has no finite samples to draw");
  if (plot.has_fit) {
    plot.curve = fitted_curve(*series.fit, t_range.low, t_range.high);
    add_curve(temp_range, plot.curve);
  }
  plot.t_range = t_range.padded(0.02);
  plot.temp_range = temp_range.padded(0.05);
  if (!residual_range.empty()) {
    plot.residual_max = std::max({std::abs(residual_range.low), std::abs(residual_range.high), 1e-6}) * 1.1;
  }
  return plot;
}

// The upper panel (the whole figure without a fit): samples over the band and the fitted line.
void draw_samples(const CurveSeries& series, const CurvePlot& plot, const std::string& title) {
  plvpor(0.1, 0.95, plot.has_fit ? 0.40 : 0.12, 0.92);
  plwind(plot.t_range.low, plot.t_range.high, plot.temp_range.low, plot.temp_range.high);
  plcol0(kGrid);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(kInk);
  plbox(plot.has_fit ? "bcst" : "bcnst", 0, 0, "bcnstv", 0, 0);
  plmtex("l", 4.5, 0.5, 0.5, value_label(series).c_str());
  plmtex("t", 1.5, 0.5, 0.5, title.c_str());
  draw_band(plot.curve, kFirstSeries + 1);
  draw_line(plot.curve, kFirstSeries + 1);  // under the points, so no sample is hidden by its fit
  draw_points(plot.t, plot.temp, kFirstSeries);
}

// The fit's parameters in the upper panel's corner, and the residuals' panel below it.
void draw_fit_and_residuals(const CurveSeries& series, const CurvePlot& plot) {
  const auto& f = *series.fit;
  const std::string fit_text =
      pl_text(fmt::format("k = {:.4g} 1/s [{:.4g}, {:.4g}]   T0 = {:.2f} {}   T_amb = {:.2f} {}", f.k_per_s.value,
                          f.k_per_s.low, f.k_per_s.high, f.t0_c.value, series.unit, f.ambient_c.value, series.unit));
  plcol0(kInk);
  plschr(0, 0.8);
  plmtex("t", -1.5, 0.97, 1.0, fit_text.c_str());
  plschr(0, 1);

  const Range& tr = plot.t_range;
  plvpor(0.1, 0.95, 0.10, 0.34);
  plwind(tr.low, tr.high, -plot.residual_max, plot.residual_max);
  plcol0(kGrid);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(kInk);
  plbox("bcnst", 0, 0, "bcnstv", 0, 3);
  const std::array<PLFLT, 2> zx{tr.low, tr.high}, zy{0, 0};
  plcol0(kFirstSeries + 1);
  plline(2, zx.data(), zy.data());
  draw_points(plot.t, plot.residual, kFirstSeries);
  plcol0(kInk);
  plmtex("l", 4.5, 0.5, 0.5, "residual (°C)");
}

void draw_why_not_fitted(const CurveSeries& series) {
  const std::string why = pl_text(
      "no Newton fit: " + (series.fit ? std::string(fitting::to_string(series.fit->summary.status)) : "not fitted"));
  plcol0(kFirstSeries + 1);
  plschr(0, 0.8);
  plmtex("t", -1.5, 0.97, 1.0, why.c_str());
  plschr(0, 1);
}

}  // namespace

FigureFiles write_curve_figure(const CurveSeries& series, const FigureSize& size, const fs::path& base,
                               const std::string& time_basis) {
  if (series.time_s.size() != series.temperature_c.size()) {
    throw std::invalid_argument("series '" + series.name + "': times and temperatures differ in length");
  }
  if (series.time_s.empty()) throw std::invalid_argument("series '" + series.name + "' has no samples to draw");
  FigureFiles files = files_for(base);
  files.title = fmt::format("{} {}", to_string(series.kind), series.name);
  files.caption = curve_caption(series, time_basis);
  const CurvePlot plot = curve_plot(series);
  render_png_and_svg(files, size, [&] {
    draw_samples(series, plot, pl_text(files.title));
    if (plot.has_fit) {
      draw_fit_and_residuals(series, plot);
    } else {
      draw_why_not_fitted(series);
    }
    plcol0(kInk);
    bottom_label(kTimeAxisLabel, 3.0);
  });
  return files;
}

}  // namespace bosfuse::report
