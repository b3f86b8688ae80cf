#pragma once
// The report's uncertainty section (uncertainty_section.h) from what
// `bosfuse process` stored in a run: each probe's samples' σ, each probe
// fit's systematic and combined intervals, and the Type-B budget of the
// processing's geometry and [geometry.uncertainty] at the hottest probe
// sample (the ambient resolved as `process` resolves it). Reads stored
// results only; what is not stored is said in a note, not recomputed.

#include "report/uncertainty_section.h"
#include "storage/experiment_clock.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"

namespace bosfuse::report {

UncertaintySummary stored_uncertainty(const storage::RunStore& store, const storage::ProcessingStore& results,
                                      const storage::ExperimentClock& clock);

}  // namespace bosfuse::report
