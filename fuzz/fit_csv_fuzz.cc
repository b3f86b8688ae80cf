// The fit CSV reader. `bosfuse fit FILE.csv` reads its two columns with
// report::read_csv_series() (report/sample_csv.h, beside the writer of
// `bosfuse export --csv`); this target fuzzes it, then hands the columns on
// the way run_fit() does: fitting::clean_series and fitting::fit_newton
// (the fit only for series of at most 64 rows, to keep executions fast).
// The input is the CSV text, with the columns chosen as the command does
// when no --time-column/--temperature-column is given.
// Invariants: reading either returns or throws a std::exception with a
// message; the two columns have the same length and are named by header
// cells; ISO-8601 times are relative to the earliest one (never negative);
// the cleaned series is finite and sorted, with the dropped rows counted;
// fit_newton never throws on read data, a fit reported ok has finite k, τ,
// T0 and ambient, a positive k with k·τ = 1, and a failed fit has a reason.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdint>
#include <sstream>
#include <string>

#include <glog/logging.h>

#include "fitting/newton_fit.h"
#include "fitting/series.h"
#include "fuzz/fuzz_support.h"
#include "report/sample_csv.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  FLAGS_minloglevel = google::GLOG_FATAL;  // as run_fit() does: Ceres' own logging is noise here
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  bosfuse::report::CsvSeries series;
  try {
    series = bosfuse::report::read_csv_series(in, "", "");
  } catch (const std::exception& e) {
    FUZZ_CHECK(e.what()[0] != '\0');
    return 0;
  }
  FUZZ_CHECK(series.time_s.size() == series.temperature_c.size());
  if (series.iso_origin_ns) {
    for (double t : series.time_s) FUZZ_CHECK(t >= 0);
  }

  const auto clean = bosfuse::fitting::clean_series(series.time_s, series.temperature_c);
  FUZZ_CHECK(clean.time_s.size() == clean.temperature_c.size());
  FUZZ_CHECK(clean.size() + clean.rejected_non_finite == series.time_s.size());
  for (std::size_t i = 0; i < clean.size(); ++i) {
    FUZZ_CHECK(std::isfinite(clean.time_s[i]) && std::isfinite(clean.temperature_c[i]));
    if (i > 0) FUZZ_CHECK(clean.time_s[i - 1] <= clean.time_s[i]);
  }

  if (series.time_s.size() > 64) return 0;
  const bosfuse::fitting::NewtonFit fit = bosfuse::fitting::fit_newton(series.time_s, series.temperature_c);
  if (fit.ok()) {
    FUZZ_CHECK(std::isfinite(fit.k_per_s.value) && fit.k_per_s.value > 0);
    FUZZ_CHECK(std::isfinite(fit.tau_s.value) && std::isfinite(fit.t0_c.value) && std::isfinite(fit.ambient_c.value));
    FUZZ_CHECK(std::fabs(fit.k_per_s.value * fit.tau_s.value - 1) < 1e-9);
  } else {
    FUZZ_CHECK(!fit.summary.message.empty());
  }
  return 0;
}
