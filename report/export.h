#pragma once
// The report's data files: CSV for spreadsheets, JSON for programs. Numbers
// are written with enough digits to round-trip; a value that does not exist
// (a failed fit's k) is an empty CSV field and a JSON null, never NaN text.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "report/figures.h"
#include "report/report_input.h"

namespace bosfuse::report {

// series,kind,t_s,temperature_c,fit_c,residual_c — every sample of every series.
void write_series_csv(const ReportInput& input, const std::filesystem::path& path);

// One row per series: parameters with their interval bounds and diagnostics.
void write_fits_csv(const ReportInput& input, const std::filesystem::path& path);

// x_px,y_px,x_mm,y_mm,value,masked — one row per grid cell (mm columns empty without a scale).
void write_map_csv(const MapField& map, std::optional<double> px_per_mm, const std::filesystem::path& path);

nlohmann::ordered_json fit_json(const fitting::NewtonFit& fit);
nlohmann::ordered_json agreement_json(const AgreementEntry& entry);

// Everything in the report; `figures` and `data_files` are listed by file name.
nlohmann::ordered_json report_json(const ReportInput& input, const std::vector<FigureFiles>& figures,
                                   const std::vector<std::filesystem::path>& data_files);

}  // namespace bosfuse::report
