#pragma once
// The cooling-curve report: write_report() turns a ReportInput into a folder
// holding
//   report.html   one self-contained page (inline CSS, figures embedded as
//                 base64 PNG data URIs; no script, no network): first the
//                 summary (summary.h: fits and thermocouple–probe pairs),
//                 then the image quality index, the cooling curves with their
//                 confidence bands, the Bland–Altman plots and the maps;
//   *.png, *.svg  every figure, drawn with PLplot (figures.h);
//   summary.csv   the summary, one row per quantity;
//   series.csv    every sample of every series with the fitted curve, residual and band half-width;
//   fits.csv      one row per series: parameters with their intervals and diagnostics;
//   map_*.csv     each map's grid (x, y in px and mm, value, masked);
//   report.json   all of the above (data included) for other tools.
// Sections without data say why (e.g. BOS probes "not processed yet — run
// bosfuse process"), they never show made-up numbers, and no file shows
// NaN, inf or null where a number belongs: "—", absent or empty, with the
// reason beside it.

#include <filesystem>
#include <string>
#include <vector>

#include "report/figures.h"
#include "report/report_input.h"

namespace bosfuse::report {

struct ReportOptions {
  std::string title;  // default: "Cooling report — <run name>"
  FigureSize curve_size{900, 600};
  FigureSize map_size{900, 650};
  double displacement_contour_px = 0.05;  // contour spacing of displacement maps, px
  double temperature_contour_c = 1.0;     // contour spacing of temperature maps, °C
};

struct ReportFiles {
  std::filesystem::path html;
  std::filesystem::path json;
  std::vector<std::filesystem::path> csv;
  std::vector<FigureFiles> figures;
};

// Creates `out_dir` if needed and replaces the files it writes there, all
// at the end (written into a hidden staging folder inside it first), so a
// report that fails leaves the earlier one whole. Throws
// storage::OutputRefused for a run's own folder (storage/output_path.h),
// std::runtime_error when a file cannot be written or PLplot lacks
// its cairo devices.
ReportFiles write_report(const ReportInput& input, const ReportOptions& options, const std::filesystem::path& out_dir);

}  // namespace bosfuse::report
