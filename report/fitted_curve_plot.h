#pragma once
// A series' fitted Newton curve as the curve and overview figures draw it:
// sampled over the record's time span with its confidence band
// (NewtonFit::temperature_half_width_at), the band shaded translucent under
// the samples and the line drawn over the band. Internal to report/'s
// figures (figure_frame.h is the frame they draw in).

#include <plplot.h>

#include <vector>

#include "fitting/newton_fit.h"
#include "report/figure_frame.h"
#include "report/report_input.h"

namespace bosfuse::report::figure_frame {

// The series has a fit that converged.
bool fitted(const CurveSeries& s);

// The fitted curve on [t_low, t_high] with its confidence band; no band
// when the fit has no covariance (one stored before it was kept).
struct FittedCurve {
  std::vector<PLFLT> t, temp, low, high;
  bool has_band() const { return !low.empty(); }
};

FittedCurve fitted_curve(const fitting::NewtonFit& fit, double t_low, double t_high);

// Widens `range` to hold the curve and its band.
void add_curve(Range& range, const FittedCurve& c);

// Shaded in a translucent `colour`, under the points and the line.
void draw_band(const FittedCurve& c, int colour);

// The curve as a line in `colour`; nothing for a series without a fit.
void draw_line(const FittedCurve& c, int colour);

}  // namespace bosfuse::report::figure_frame
