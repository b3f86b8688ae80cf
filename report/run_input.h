#pragma once
// Builds a ReportInput from a run: its thermocouple samples (ok status
// only) and what `bosfuse process` stored (pipeline/process.h) — fits,
// BOS probe series, agreements, the stored displacement and temperature
// fields nearest the chosen times as maps, the image quality index and the
// settings used. Times are experiment seconds (storage/experiment_clock.h).
// It never evaluates frames or fits on its own: a run not processed yet
// shows its samples, and the report says to run `bosfuse process`.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fusion/displacement_field.h"
#include "report/report_input.h"
#include "storage/run_store.h"

namespace bosfuse::report {

struct RunReportOptions {
  std::vector<double> map_times_s{10, 60};  // experiment seconds; the nearest frame with a stored field is used
  std::optional<double> px_per_mm;          // map axes in mm; default: the run's stored geometry, else px
};

ReportInput build_report_input(const storage::RunStore& store, const RunReportOptions& options = {});

// The magnitude |(u, v)| of a displacement field as a map; vectors that are
// not measurements (flag other than kOk: masked, no texture, no peak, outside
// the ROI, and outliers replaced by their neighbours' median) are NaN and
// masked cells, as in the stored field's `valid` column.
MapField displacement_magnitude_map(const fusion::DisplacementField& field, cv::Size image_size_px);

}  // namespace bosfuse::report
