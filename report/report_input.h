#pragma once
// What a cooling-curve report shows, held in memory so that any source can
// feed it: build_report_input() (run_input.h) fills it from a run store's
// thermocouple samples and frames, and the stored results of `bosfuse
// process` (BOS probe series, fits, agreement, temperature fields) plug into
// the same fields. write_report() (report.h) turns it into HTML, figures and
// data files.
//
// Conventions (DESIGN.md): times in seconds relative to the run's origin,
// said in words by ReportInput::time_basis (every axis, caption and
// report.json repeats it, so a reader never has to guess the time base),
// temperatures in °C, image coordinates in pixels with the origin at the
// top-left pixel's centre, x right, y down.

#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fitting/agreement.h"
#include "fitting/newton_fit.h"
#include "fusion/image_quality.h"
#include "report/uncertainty_section.h"

namespace bosfuse::report {

enum class SeriesKind { kThermocouple, kBosProbe };
const char* to_string(SeriesKind kind);  // "thermocouple", "BOS probe"

// One temperature record and, when fitted, its Newton fit. The fit must have
// been made on these times (any origin: residuals use fit.temperature_at()).
struct CurveSeries {
  std::string name;  // channel name ("tc0") or probe name
  SeriesKind kind = SeriesKind::kThermocouple;
  std::vector<double> time_s;  // relative to the run's origin
  std::vector<double> temperature_c;
  // "°C", or "px" for a BOS probe without a calibration (its shift
  // magnitude): a px series has a rate but no temperature to compare.
  std::string unit = "°C";
  std::optional<cv::Point2d> image_px;  // where it sits in the camera image (a map marker)
  std::size_t excluded_samples = 0;     // samples left out (non-ok status), said in the report
  std::optional<fitting::NewtonFit> fit;
};

// A thermocouple compared with the BOS probe at its position (fitting/agreement.h).
struct AgreementEntry {
  std::string thermocouple;
  std::string probe;
  fitting::Agreement agreement;
};

// A scalar field on a regular grid in image coordinates: |displacement| in
// px, or temperature in °C. Value (r, c) sits at (x0_px + c·step_px,
// y0_px + r·step_px). Masked cells (the holder's zone, windows without a
// measurement) are drawn hatched grey, never coloured as data.
struct MapField {
  std::string quantity = "|displacement|";  // shown in titles and the colour bar
  std::string unit = "px";                  // "px" or "°C"
  std::optional<double> time_s;             // relative to the run's origin; none for a pair outside a run
  std::string source;                       // e.g. "frame 12 (t = 10.2 s) against reference frame 1"
  cv::Mat values;                           // CV_64FC1 (other depths are converted), rows × cols
  cv::Mat mask;                             // CV_8UC1 of the same size, non-zero: not a measurement; may be empty
  double x0_px = 0;
  double y0_px = 0;
  double step_px = 1;
  cv::Size image_size_px;      // extent of the axes; empty: the grid's own extent
  double contour_spacing = 0;  // in `unit`; 0: ReportOptions' default for this unit
  // A displacement map's vectors (px, CV_64FC1 of the values' size, NaN
  // where not measured), drawn as arrows over the colours when `arrows`.
  cv::Mat u_px, v_px;
  bool arrows = false;
};

struct QualityInfo {
  fusion::QualityIndex index;
  std::string compared;  // what was compared with what, e.g. "frame 9 against reference frame 1"
};

inline constexpr const char* kDefaultTimeBasis = "s since the run's origin";

struct ReportInput {
  std::string run_name;
  // What t counts from, in words, e.g. "experiment seconds since heater off
  // (2026-11-30T02:00:00.000Z); recorded at 16×".
  std::string time_basis = kDefaultTimeBasis;
  std::string run_dir;
  std::string started_utc;          // ISO-8601
  std::string status;               // running, complete, interrupted
  std::vector<CurveSeries> series;  // thermocouples and BOS probes, in display order
  std::vector<AgreementEntry> agreements;
  std::vector<MapField> displacement_maps;
  std::vector<MapField> temperature_maps;
  std::optional<double> px_per_mm;  // map axes in mm when known, else in px
  std::optional<QualityInfo> quality;
  // Why there are no displacement maps when there are none (e.g. "the run has no frames").
  std::string displacement_maps_note;
  std::vector<std::string> notes;  // anything else a reader should know, shown near the top
  // Why BOS has nothing in this run (e.g. "the run has no frames"): then the
  // report is the thermocouples' alone, without the BOS sections. Empty: a
  // run with frames to evaluate.
  std::string thermocouples_only;
  // Why the BOS results are missing when the run has frames but they are (a
  // processing that failed says what failed); empty: "not processed yet".
  std::string bos_missing;
  UncertaintySummary uncertainty;  // the budget, the probes' σ and the fits' intervals (empty: not processed)

  bool has_probes() const;
};

// Fits every series that has no fit yet (origin: the run's origin, t = 0).
void fit_missing(ReportInput& input, const fitting::NewtonFitOptions& options = {});

}  // namespace bosfuse::report
