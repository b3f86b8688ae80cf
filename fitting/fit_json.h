#pragma once
// Fits and agreements as JSON, in one layout for every tool that writes them:
// `bosfuse fit --json`, the fits and agreements `bosfuse process` stores in a
// run, and the report's report.json (docs/FITTING.md describes the fields).
// Numbers that do not exist (a failed fit's parameters, a NaN) are null.
// Callers add what only they know (the input file, the quantity fitted).

#include <nlohmann/json.hpp>

#include "fitting/agreement.h"
#include "fitting/newton_fit.h"

namespace bosfuse::fitting {

nlohmann::ordered_json to_json(const Estimate& estimate, double confidence);
// model, origin_s, ok, status, error (when failed), parameters, uncertainty, diagnostics, warnings.
nlohmann::ordered_json to_json(const NewtonFit& fit);
// verdict, k (difference, z, ...), series (RMS difference, Bland–Altman).
nlohmann::ordered_json to_json(const Agreement& agreement);

}  // namespace bosfuse::fitting
