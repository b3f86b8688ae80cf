#pragma once
// Builds a ReportInput from what a run store holds today: thermocouple
// samples (ok status only; times in seconds since the run's first sample),
// fitted with Newton's law; and, when the run has frames, the displacement
// magnitude maps of the frames nearest the chosen times against the
// reference frame, and the image quality index of the last frame against the
// reference. BOS probe series (with their fits), their agreement with the
// thermocouples, temperature maps and displacement fields come from what
// `bosfuse process` stored (storage/processing_store.h, docs/REPORT.md
// "Stored results"); stored displacement fields replace evaluating the
// frames. Until a run has them, the report says they are not processed yet
// (it never invents them).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fitting/newton_fit.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/displacement_field.h"
#include "report/report_input.h"
#include "storage/run_store.h"

namespace bosfuse::report {

struct RunReportOptions {
  std::vector<double> map_times_s{10, 60};  // since the run's first sample; the nearest frame is used
  std::optional<double> px_per_mm;          // map axes in mm when given
  fusion::EvaluatorOptions evaluator;       // default: cross-correlation, window 16 px, step 8 px
  cv::Mat mask;  // the frames' size, non-zero: not evaluated (e.g. the heater's holder); shown hatched in the maps
  fitting::NewtonFitOptions fit;                        // origin: the run's first sample unless set
  std::function<void(const std::string&)> on_progress;  // one line per step of the long work, when set
};

ReportInput build_report_input(const storage::RunStore& store, const RunReportOptions& options = {});

// The magnitude |(u, v)| of a displacement field as a map; vectors that are
// not measurements (masked, no texture, no peak, outside the ROI) are masked
// cells, outliers replaced by their neighbours' median are shown.
MapField displacement_magnitude_map(const fusion::DisplacementField& field, cv::Size image_size_px);

// Nanoseconds since the epoch as ISO-8601 UTC with milliseconds, e.g. 2026-11-23T11:17:20.123Z.
std::string iso8601_utc(std::int64_t t_ns);

}  // namespace bosfuse::report
