#pragma once
// fusion/ logs nothing: what an evaluation, a scene match or a quality check
// has to tell comes back in its result (EvaluationSummary's warnings and
// notes, SceneMatch's and QualityReport's warnings), and the program logs it
// through these where the result arrives, at the level and with the text
// fusion once logged it with.

#include <string>
#include <vector>

#include "fusion/evaluation.h"

namespace bosfuse::pipeline {

// Each at warning level.
void log_warnings(const std::vector<std::string>& warnings);

// The summary's notes at debug level, then its warnings.
void log_evaluation(const fusion::EvaluationSummary& summary);

}  // namespace bosfuse::pipeline
