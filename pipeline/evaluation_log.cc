#include "pipeline/evaluation_log.h"

#include <spdlog/spdlog.h>

namespace bosfuse::pipeline {

void log_warnings(const std::vector<std::string>& warnings) {
  for (const auto& warning : warnings) spdlog::warn("{}", warning);
}

void log_evaluation(const fusion::EvaluationSummary& summary) {
  for (const auto& note : summary.notes) spdlog::debug("{}", note);
  log_warnings(summary.warnings);
}

}  // namespace bosfuse::pipeline
