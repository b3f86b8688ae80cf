#pragma once
// The BOS probe samples `bosfuse process` stored, as CSV: what `bosfuse
// export RUN --probes` writes. Long form, one row per probe and frame:
// `probe,frame_id,t_s,u_px,v_px,shift_px,temperature_c,valid,sigma_u_px,
// sigma_v_px,sigma_shift_px,sigma_random_c,sigma_systematic_c`, t_s in
// experiment seconds (storage/experiment_clock.h, the frame's time), every
// σ a standard uncertainty (docs/SCHEMA.md, version 5). A cell is empty
// where the store holds NULL (no temperature; a σ not estimated, as in a
// run processed before the σ existed), never 0.

#include <ostream>

#include "storage/run_store.h"

namespace bosfuse::report {

// Throws StorageError when the run holds no processing results to read.
void write_probe_samples_csv(const storage::RunStore& store, std::ostream& out);

}  // namespace bosfuse::report
