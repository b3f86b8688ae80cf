#pragma once
// ProcessTimes: where a processing's time went, frame by frame and at the
// end. process_run (process.h) reports it; one frame's work
// (process_frame.h) adds to it, so both include this, and process_frame.h
// need not include process.h.

namespace bosfuse::pipeline {

// Where a processing's time went, in wall seconds summed over the frames it
// evaluated. With frames decoded ahead, decode_s runs beside the evaluation
// and wait_for_frames_s is what of it the frame loop still waited for;
// likewise, finished aside, the temperature field and the field files run
// beside the next frame's evaluation and wait_for_finishing_s is what the
// loop waited for them.
struct ProcessTimes {
  double decode_s = 0;              // reading and decoding frames, on whichever thread did it
  double wait_for_frames_s = 0;     // the frame loop held up by decoding
  double evaluation_s = 0;          // displacement fields or probes
  double temperature_field_s = 0;   // the physical model's field (full fields only), on whichever thread
  double csv_s = 0;                 // writing the field files, on whichever thread
  double wait_for_finishing_s = 0;  // the frame loop held up by a frame's temperature field and files
  double staging_s = 0;             // storing each frame's results (one transaction per frame)
  double finishing_s = 0;           // fits, agreements, quality index, the swap into the current results
};

}  // namespace bosfuse::pipeline
