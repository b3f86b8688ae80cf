#pragma once
// Fits and agreements as JSON, in one layout for every tool that writes them:
// `bosfuse fit --json`, the fits and agreements `bosfuse process` stores in a
// run, and the report's report.json (docs/FITTING.md describes the fields).
// Numbers that do not exist (a failed fit's parameters, a NaN) are null;
// a quantity that does not apply (reduced χ² without a known σ) is absent.
// Callers add what only they know (the input file, the quantity fitted).

#include <nlohmann/json.hpp>

#include "fitting/agreement.h"
#include "fitting/newton_fit.h"

namespace bosfuse::fitting {

// A finite number as itself, NaN and infinities as null (JSON has neither).
nlohmann::ordered_json number_or_null(double value);

nlohmann::ordered_json to_json(const Estimate& estimate, double confidence);
// model, origin_s, t0_reference_s and t0_at_origin (where T0 is given), ok,
// status, error (when failed), parameters, uncertainty,
// diagnostics (with t_critical when ok), covariance (when ok: "parameters"
// ["log_tau", "delta_c", "ambient_c"] and the 3 × 3 "matrix"), warnings.
nlohmann::ordered_json to_json(const NewtonFit& fit);
// verdict (sentences), k (difference, z, ...), series (RMS difference,
// Bland–Altman, as read and de-lagged), confidence, equivalence (the
// agree / differ / inconclusive test of each curve parameter), lag.
nlohmann::ordered_json to_json(const Agreement& agreement);

// The readers of these layouts, for what a run stored. They live here, next
// to the writers, so a key cannot drift between the two: whatever to_json
// writes comes back (tested); a null or missing number comes back NaN; the
// residuals of a fit are not stored and stay empty. A fit stored without a
// covariance (written before it was) comes back with none, without
// t_critical gets it from its dof and confidence, and without
// t0_reference_s has T0 at its origin (where it always was then). Throw
// nlohmann::json::exception on a document that is not of this layout.
NewtonFit fit_from_json(const nlohmann::json& j);
Agreement agreement_from_json(const nlohmann::json& j);

}  // namespace bosfuse::fitting
