#pragma once
// The report's data files: CSV for spreadsheets, JSON for programs. Numbers
// are written with enough digits to round-trip; a value that does not exist
// (a failed fit's k) is an empty CSV field and, in JSON, absent or a string
// saying why — never NaN text and never null, so a program reading
// report.json finds either a number or a reason.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "report/figures.h"
#include "report/report_input.h"
#include "report/summary.h"

namespace bosfuse::report {

// series,kind,t_s,temperature_c,fit_c,residual_c,fit_half_width_c — every
// sample of every series; the last is the half-width of the fitted curve's
// confidence band there (NewtonFit::temperature_half_width_at).
void write_series_csv(const ReportInput& input, const std::filesystem::path& path);

// One row per series: parameters with their interval bounds and diagnostics.
void write_fits_csv(const ReportInput& input, const std::filesystem::path& path);

// x_px,y_px,x_mm,y_mm,value,masked — one row per grid cell (mm columns empty without a scale); a cell
// masked or not measured (MapField::mask non-zero, or a value that is not finite) has value `nan` and masked 1.
void write_map_csv(const MapField& map, std::optional<double> px_per_mm, const std::filesystem::path& path);

// series,kind,compared_with,quantity,value,std_error,low,high,unit,note —
// the summary in long form, one row per quantity: a series' points, k, tau,
// T0, T_amb, residual_rms; a pair's (kind "agreement", compared_with the
// probe) delta_k, z, rms_difference, bias (low, high: the 95% limits of
// agreement) and verdict (in note). An empty value has its reason in note.
void write_summary_csv(const ReportSummary& summary, const std::filesystem::path& path);

// The fit in fitting/fit_json.h's layout without its nulls (a failed fit
// keeps "ok": false and its "error").
nlohmann::ordered_json fit_json(const fitting::NewtonFit& fit);
// The agreement in fit_json.h's layout; "k" or "series" that could not be
// computed (or, for a probe in px, are no temperatures) are the reason.
nlohmann::ordered_json agreement_json(const AgreementEntry& entry, const PairSummary& summary);
nlohmann::ordered_json summary_json(const ReportSummary& summary);

// Everything in the report; `figures` and `data_files` are listed by file name.
nlohmann::ordered_json report_json(const ReportInput& input, const ReportSummary& summary,
                                   const std::vector<FigureFiles>& figures,
                                   const std::vector<std::filesystem::path>& data_files);

}  // namespace bosfuse::report
