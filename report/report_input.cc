#include "report/report_input.h"

#include <algorithm>

namespace bosfuse::report {

const char* to_string(SeriesKind kind) {
  switch (kind) {
    case SeriesKind::kThermocouple:
      return "thermocouple";
    case SeriesKind::kBosProbe:
      return "BOS probe";
  }
  return "series";
}

bool ReportInput::has_probes() const {
  return std::any_of(series.begin(), series.end(),
                     [](const CurveSeries& s) { return s.kind == SeriesKind::kBosProbe; });
}

void fit_missing(ReportInput& input, const fitting::NewtonFitOptions& options) {
  fitting::NewtonFitOptions own = options;
  if (!own.origin_s) own.origin_s = 0.0;  // the run's origin: every T0 is the temperature at the run's start
  for (auto& s : input.series) {
    if (s.fit) continue;
    s.fit = fitting::fit_newton(s.time_s, s.temperature_c, own);
  }
}

}  // namespace bosfuse::report
