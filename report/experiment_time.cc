#include "report/experiment_time.h"

#include "acquisition/clock.h"

namespace bosfuse::report {

double experiment_time_s(const storage::RunInfo& run, std::int64_t t_ns) {
  return static_cast<double>(t_ns - run.started_ns) * 1e-9;
}

std::string experiment_time_basis(const storage::RunInfo& run) {
  return "seconds since the run started (" + acquisition::format_iso8601_utc(run.started_ns, 3) +
         ", runs.started_ns = " + std::to_string(run.started_ns) + ")";
}

}  // namespace bosfuse::report
