// agreement_pairs() and write_agreement_figure() of figures.h: the Bland–Altman
// plot of a thermocouple against its BOS probe.
#include <fmt/format.h>
#include <plplot.h>

#include <array>
#include <cmath>
#include <stdexcept>

#include "fitting/sensor_lag.h"
#include "report/figure_frame.h"
#include "report/figures.h"
#include "report/fitted_curve_plot.h"
#include "report/html.h"

namespace bosfuse::report {

using namespace figure_frame;  // the frame every figure draws in (figure_frame.h)

namespace {

namespace fs = std::filesystem;

std::string agreement_caption(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement,
                              const AgreementPairs& pairs) {
  std::string caption = fmt::format(
      "Bland–Altman plot: {} − {} against their mean at the {} times of {} (n = {}; {} interpolated there{})", a.name,
      b.name, pairs.mean_c.size(), b.name, pairs.mean_c.size(), a.name,
      pairs.time_constant_s > 0 ? fmt::format(", de-lagged by τ = {} s", display_number(pairs.time_constant_s, "{:.3g}"))
                                : std::string());
  if (const auto& stats = agreement.series) {
    caption +=
        fmt::format("; red: bias {} °C, dashed: limits of agreement [{}, {}] °C",
                    display_number(stats->bias_c, "{:.3g}"), display_number(stats->limits_of_agreement_low_c, "{:.3g}"),
                    display_number(stats->limits_of_agreement_high_c, "{:.3g}"));
  }
  return caption + ". " + agreement.verdict;
}

}  // namespace

AgreementPairs agreement_pairs(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement) {
  AgreementPairs pairs;
  pairs.time_constant_s = agreement.lag.time_constant_s;
  auto sa = fitting::clean_series(a.time_s, a.temperature_c, 0.0);
  if (pairs.time_constant_s > 0) {
    if (!fitted(a)) return pairs;  // no slope to de-lag with: lagged pairs would not be the agreement's
    sa = fitting::delagged(sa, *a.fit, pairs.time_constant_s);
  }
  const auto sb = fitting::clean_series(b.time_s, b.temperature_c, 0.0);
  for (std::size_t i = 0; i < sb.size(); ++i) {
    const auto reading = fitting::interpolate(sa, sb.time_s[i]);
    if (!reading) continue;
    pairs.time_s.push_back(sb.time_s[i]);
    pairs.mean_c.push_back(0.5 * (*reading + sb.temperature_c[i]));
    pairs.difference_c.push_back(*reading - sb.temperature_c[i]);
  }
  return pairs;
}

FigureFiles write_agreement_figure(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement,
                                   const FigureSize& size, const fs::path& base) {
  const AgreementPairs pairs = agreement_pairs(a, b, agreement);
  if (pairs.mean_c.size() < 2) {
    throw std::invalid_argument(a.name + " and " + b.name + " share fewer than two times: nothing to compare");
  }
  // Thinned for drawing only: the caption's n and the statistics are of every pair.
  std::vector<PLFLT> mean, difference;
  Range mr, dr;
  for (const std::size_t i : plotted_indices(pairs.mean_c.size())) {
    mean.push_back(pairs.mean_c[i]);
    difference.push_back(pairs.difference_c[i]);
    mr.add(mean.back());
    dr.add(difference.back());
  }
  const auto& stats = agreement.series;
  if (stats) {
    dr.add(stats->limits_of_agreement_low_c);
    dr.add(stats->limits_of_agreement_high_c);
  }
  dr.add(0);
  FigureFiles files = files_for(base);
  files.title = fmt::format("Agreement of {} and {}", a.name, b.name);
  files.caption = agreement_caption(a, b, agreement, pairs);
  const Range x = mr.padded(0.03), y = dr.padded(0.1);
  render_png_and_svg(files, size, [&] {
    plvpor(0.1, 0.95, 0.12, 0.92);
    plwind(x.low, x.high, y.low, y.high);
    plcol0(kGrid);
    plbox("g", 0, 0, "g", 0, 0);
    plcol0(kInk);
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    const std::string xl = pl_text(fmt::format("mean of {} and {} (°C)", a.name, b.name));
    const std::string yl = pl_text(fmt::format("{} − {} (°C)", a.name, b.name));
    const std::string title = pl_text(files.title);
    pllab(xl.c_str(), yl.c_str(), title.c_str());
    draw_points(mean, difference, kFirstSeries);
    const std::array<PLFLT, 2> lx{x.low, x.high};
    auto hline = [&](double value, int colour, int style) {
      if (!std::isfinite(value)) return;  // a line where there is no number would be a lie
      const std::array<PLFLT, 2> ly{value, value};
      plcol0(colour);
      pllsty(style);
      plwidth(2);
      plline(2, lx.data(), ly.data());
      plwidth(1);
      pllsty(1);
    };
    hline(0, kMaskHatch, 1);
    if (stats) {
      hline(stats->bias_c, kFirstSeries + 1, 1);
      hline(stats->limits_of_agreement_low_c, kFirstSeries + 1, 2);
      hline(stats->limits_of_agreement_high_c, kFirstSeries + 1, 2);
    }
  });
  return files;
}

}  // namespace bosfuse::report
