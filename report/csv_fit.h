#pragma once
// Newton's law of cooling fitted to a time and a temperature column of a
// plain CSV file (sample_csv.h), as `bosfuse fit` does it: the fit's t = 0
// taken from the file, the line that says what was fitted against what, and
// the fit's JSON with where its data came from. Use it wherever a CSV series
// is fitted outside a run store.

#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>

#include "fitting/newton_fit.h"
#include "report/sample_csv.h"

namespace bosfuse::report {

// t = 0 of the fit: the file's own t = 0 (an export's experiment seconds, so
// T0 is the temperature at the experiment's origin; ISO-8601 times count
// from the earliest), unless the times are epoch-scale seconds, which the
// fit counts from the earliest sample.
fitting::NewtonFitOptions with_csv_origin(fitting::NewtonFitOptions options, const CsvSeries& series);

// "FILE: 'T' against 't_s' (t = 0 at ...; N rows with an empty cell skipped)";
// `file` "-" is standard input.
void print_csv_fit_header(std::ostream& out, const CsvSeries& series, const std::string& file, double origin_s);

// The shared fit layout (fitting/fit_json.h) plus the file and its columns,
// its time scale and its UTC origin where it has them.
nlohmann::ordered_json csv_fit_json(const fitting::NewtonFit& fit, const CsvSeries& series, const std::string& file);

}  // namespace bosfuse::report
