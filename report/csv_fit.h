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

// The ambient model and the robust loss by the names `bosfuse fit`
// --ambient and --loss take (and the Python module's fit_newton): free,
// fixed:VALUE or prior:VALUE,SIGMA; none, huber:SCALE or cauchy:SCALE (°C).
// Throws std::runtime_error naming `option` and what it expects.
fitting::AmbientModel parse_ambient(const std::string& text, const std::string& option);
fitting::RobustLoss parse_loss(const std::string& text, const std::string& option);

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
