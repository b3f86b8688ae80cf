#include "report/fitted_curve_plot.h"

#include <cmath>

namespace bosfuse::report::figure_frame {
namespace {

constexpr double kBandAlpha = 0.22;

}  // namespace

bool fitted(const CurveSeries& s) { return s.fit && s.fit->ok(); }

FittedCurve fitted_curve(const fitting::NewtonFit& fit, double t_low, double t_high) {
  constexpr int kPoints = 400;
  FittedCurve c;
  bool band = true;
  for (int i = 0; i < kPoints; ++i) {
    const double t = t_low + (t_high - t_low) * i / (kPoints - 1);
    const double half_width = fit.temperature_half_width_at(t);
    band = band && std::isfinite(half_width);
    c.t.push_back(t);
    c.temp.push_back(fit.temperature_at(t));
    c.low.push_back(c.temp.back() - half_width);
    c.high.push_back(c.temp.back() + half_width);
  }
  if (!band) {
    c.low.clear();
    c.high.clear();
  }
  return c;
}

void add_curve(Range& range, const FittedCurve& c) {
  for (const auto* values : {&c.temp, &c.low, &c.high})
    for (double v : *values) range.add(v);
}

void draw_band(const FittedCurve& c, int colour) {
  if (!c.has_band()) return;
  std::vector<PLFLT> x = c.t, y = c.high;
  x.insert(x.end(), c.t.rbegin(), c.t.rend());
  y.insert(y.end(), c.low.rbegin(), c.low.rend());
  const auto& rgb = kPalette[colour];
  plscol0a(kBandFill, rgb[0], rgb[1], rgb[2], kBandAlpha);
  plcol0(kBandFill);
  plfill(static_cast<PLINT>(x.size()), x.data(), y.data());
}

void draw_line(const FittedCurve& c, int colour) {
  if (c.t.empty()) return;  // no fit
  plcol0(colour);
  plwidth(2);
  plline(static_cast<PLINT>(c.t.size()), c.t.data(), c.temp.data());
  plwidth(1);
}

}  // namespace bosfuse::report::figure_frame
