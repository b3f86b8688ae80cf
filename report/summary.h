#pragma once
// The summary a scientist reads first: for every series (thermocouple or BOS
// probe) the fitted k with its interval, τ, T0, T_amb, the residual RMS and
// the points used; for every thermocouple–probe pair Δk ± σ, z, the verdict,
// the RMS temperature difference, the Bland–Altman bias and the 95% limits
// of agreement. summarize() decides once which numbers exist and, for those
// that do not, why (the fit failed, the probe is in px, the series share too
// few times); the page (summary_html), report.json and summary.csv
// (export.h) only render that decision, so the three cannot disagree and
// none of them shows NaN, inf or null where a number belongs.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "report/report_input.h"

namespace bosfuse::report {

// One number of the summary, or the reason it could not be computed.
struct SummaryQuantity {
  std::optional<double> value;  // absent: not computed, `reason` says why
  std::optional<double> std_error;
  std::optional<double> low;  // interval of a fitted parameter; limits of agreement of a bias
  std::optional<double> high;
  bool fixed = false;  // held constant by the fit (a fixed ambient)
  std::string unit;    // "1/s", "s", "°C", "px", or empty for a count or a z-score
  std::string reason;  // why there is no value; empty when there is one
};

struct SeriesSummary {
  std::string name;
  SeriesKind kind = SeriesKind::kThermocouple;
  std::size_t points = 0;  // used by the fit; the samples when not fitted
  SummaryQuantity k, tau, t0, ambient, residual_rms;
  std::vector<std::string> notes;  // warnings of the fit, its origin when not t = 0, left-out samples
};

struct PairSummary {
  std::string thermocouple;
  std::string probe;
  SummaryQuantity delta_k;  // k_tc − k_probe with the combined standard error
  SummaryQuantity z;
  std::optional<bool> k_agree;
  std::string verdict;
  // The equivalence test (fitting/agreement.h): agree, differ or
  // inconclusive, decided by `deciding` (k, T0 or T_amb), whose z and
  // margin are shown; empty with a reason in deciding_z when not tested.
  std::string equivalence;
  std::string deciding;
  SummaryQuantity deciding_z;
  SummaryQuantity margin;            // ± in the deciding parameter's unit
  std::optional<std::size_t> pairs;  // Bland–Altman n: BOS frames in the overlap
  SummaryQuantity rms_difference;
  SummaryQuantity bias;  // low, high: the 95% limits of agreement
};

struct ReportSummary {
  std::string time_basis;
  double confidence = 0.95;  // of the fits' intervals
  std::vector<SeriesSummary> series;
  std::vector<PairSummary> pairs;
};

ReportSummary summarize(const ReportInput& input);

// The series table and, when there are pairs, the pair table, each with a
// caption stating the time basis and footnotes giving every reason a cell
// shows "—".
std::string summary_html(const ReportSummary& summary);

}  // namespace bosfuse::report
