#pragma once
// The report's uncertainty section: what a BOS temperature is worth as a
// measurement, as `process` stored it. Three tables: the Type-B budget of
// the set-up (each input, its standard uncertainty, sensitivity and
// contribution in °C at a stated temperature, and the combined one), the
// random σ of each probe's samples, and each fit's parameters with their
// random, systematic and combined intervals. run_input.h fills it from a
// run; a run processed before the σ existed (schema version 4) gives empty
// tables and a note saying why, never invented numbers.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "fusion/temperature_budget.h"

namespace bosfuse::report {

// One probe's samples' σ (°C), over its valid samples that carry one.
struct ProbeUncertainty {
  std::string probe;
  std::size_t samples = 0;             // valid samples with a temperature
  std::size_t samples_with_sigma = 0;  // of those, carrying a random σ
  double median_random_c = 0, max_random_c = 0;
  std::optional<double> median_systematic_c;
};

// One fitted parameter of a series, as its stored fit gives it.
struct FitInterval {
  std::string series;
  std::string parameter;  // "k", "T0", "T_amb"
  std::string unit;       // "1/s", "°C"
  double value = 0;
  double std_error = 0;               // the fit's (random)
  std::optional<double> systematic;   // the budget through the fit
  double low = 0, high = 0;           // the combined interval (the fit's own when no systematic part)
  double confidence = 0.95;
};

struct UncertaintySummary {
  std::optional<fusion::TemperatureBudget> budget;
  std::string budget_basis;  // at which temperature and why, with which ambient
  std::vector<ProbeUncertainty> probes;
  std::vector<FitInterval> fits;
  std::vector<std::string> notes;  // what is missing and why
};

// The section as HTML (a heading and the three tables, or notes).
std::string uncertainty_html(const UncertaintySummary& u);

}  // namespace bosfuse::report
