#pragma once
// `evaluate --sequence`: its settings from the command line, and the
// pipeline's sequence run
// (pipeline/sequence_run.h), on the ranks of an MPI job when mpirun or srun
// started it (ranks.h), into one HDF5 file and its XDMF sidecar
// (report/sequence_export.h), with the progress on standard error
// (progress_display.h). A failed frame is a warning above the progress
// line, or, under --quiet where the display is silent, a warning all the
// same. The file appears under its name only once every frame is in.

#include <optional>
#include <string>

#include "app/evaluator_arguments.h"
#include "pipeline/sequence_run.h"

namespace bosfuse::app {

// The run's settings: the defaults, then `settings_file`'s [processing]
// table when given, then the options given, and evaluate's own choices.
// Throws CLI::ValidationError when they are not usable together, and
// std::runtime_error for a settings file in probe mode. The reference and
// the sequence are the caller's to set.
pipeline::SequenceRunOptions sequence_run_options(const std::string& settings_file, const EvaluatorArguments& args);

// Throws CommandFailure with kExitStopped when stopped on request (nothing
// is written), and with kExitSomeFramesFailed when some frames could not be
// evaluated (the file is written, their status in it).
void write_sequence_file(pipeline::SequenceRunOptions options, const std::string& hdf5_path,
                         std::optional<int> threads);

}  // namespace bosfuse::app
