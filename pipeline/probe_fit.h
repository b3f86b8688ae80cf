#pragma once
// A BOS probe's series as its Newton fit sees it, and that fit with the
// probe's uncertainties: `process` fits every probe this way.
//
// The points are weighted by each sample's random σ (its temperature's,
// else its shift's when the series is in px): a frame known poorly pulls
// the curve little. The σ are absolute, so when the scatter about the curve
// is larger than they say (reduced χ² above 1: the vectors' σ leave out
// what moves a probe from frame to frame but not within a frame), the
// weights are kept and the σ scaled by √χ² (the Birge ratio, as the PDG and
// CODATA apply it: whenever it exceeds 1), with intervals at Student t of
// the fit's n − p (the scale is estimated from those residuals), so they
// are never narrower than the scatter supports; the factor is stored with
// the fit. The residuals' lag-1 autocorrelation, which an AR(1) effective
// n would widen by, is negative on the demo (the frames' errors are not
// positively correlated in time); and a common error of every frame (the
// shared reference image's noise) moves T_amb and T0 together, not k. A series in which some valid sample has no σ is
// fitted unweighted (scaled uncertainties), as before σ existed.
//
// The systematic part is common to every sample of the series, so it is not
// in the weights: each input of the sample's Type-B budget (the physical
// model's: temperature_budget.h with the run's [geometry.uncertainty], the
// window term as stored; a calibration's: its slope) is propagated through
// the fit (fitting/fit_systematics.h), and stored beside the fit's own
// intervals with a combined interval.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fitting/fit_systematics.h"
#include "fitting/newton_fit.h"
#include "fusion/bos_geometry.h"
#include "fusion/temperature_budget.h"
#include "storage/experiment_clock.h"
#include "storage/processing_store.h"

namespace bosfuse::pipeline {

struct ProbeSeries {
  fitting::CleanSeries series;  // sigma_c: each sample's random σ, or empty (unweighted)
  std::string quantity;         // temperature_c or shift_px
  std::string weights;          // in words: by what the points are weighted, or why not
  std::vector<fitting::SystematicInput> systematic;  // aligned with the series' samples
};

// What converted the probe's shifts into temperatures, for its systematic
// inputs: the physical model's geometry and the set-up's uncertainties, or
// a calibration (whose samples carry |shift| · σ of the slope).
struct ProbeConversion {
  const fusion::BosGeometry* geometry = nullptr;  // the physical model; null under a calibration or none
  fusion::TypeBUncertainties uncertainties;
  bool calibrated = false;
};

// The valid samples in experiment seconds on the host clock (frame time +
// `offset_s`): temperatures when every valid sample has one, else the shift.
ProbeSeries probe_fit_series(const std::vector<storage::ProbeSampleRecord>& samples,
                             const storage::ExperimentClock& clock, double offset_s,
                             const ProbeConversion& conversion);

struct ProbeFit {
  fitting::NewtonFit fit;
  double sigma_scale = 1;  // the Birge ratio the σ were scaled by (1: not scaled)
  fitting::FitSystematics systematics;
};

// Fitted from the experiment's origin (t = 0), with the ambient free.
ProbeFit fit_probe(const ProbeSeries& probe);

// Adds to a fit's JSON (fit_json.h's layout, whose keys stay as they are):
// "weights" (what weighted the points, the σ scale), and when systematics
// were propagated, parameters.k_per_s.systematic_per_s,
// parameters.{T0_c,T_amb_c}.systematic_c, each with "combined_std_error" and
// "combined_interval" (value ± the fit's critical value × √(σ² + σ_sys²)),
// and "systematic": each input's shift of k, T0 and T_amb.
void add_uncertainty_json(const ProbeFit& fit, const ProbeSeries& probe, nlohmann::ordered_json& fit_json);

}  // namespace bosfuse::pipeline
