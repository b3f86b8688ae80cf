#include "report/probe_csv.h"

#include <fmt/format.h>

#include <optional>

#include "report/csv_cell.h"
#include "storage/experiment_clock.h"
#include "storage/processing_store.h"

namespace bosfuse::report {
namespace {

// Full precision, so a value read back is the stored double.
std::string cell(std::optional<double> value) { return value ? fmt::format("{}", *value) : std::string(); }

}  // namespace

void write_probe_samples_csv(const storage::RunStore& store, std::ostream& out) {
  const storage::ProcessingStore results(store.dir());
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  out << "probe,frame_id,t_s,u_px,v_px,shift_px,temperature_c,valid,sigma_u_px,sigma_v_px,sigma_shift_px,"
         "sigma_random_c,sigma_systematic_c\n";
  for (const auto& probe : results.probes()) {
    const std::string name = csv_text_cell(probe.name);
    for (const auto& s : results.probe_samples(probe.id)) {
      out << name << ',' << s.frame_id << ',' << cell(clock.seconds(s.t_ns)) << ',' << cell(s.u_px) << ','
          << cell(s.v_px) << ',' << cell(s.shift_px) << ',' << cell(s.temperature_c) << ',' << (s.valid ? 1 : 0)
          << ',' << cell(s.sigma_u_px) << ',' << cell(s.sigma_v_px) << ',' << cell(s.sigma_shift_px) << ','
          << cell(s.sigma_random_c) << ',' << cell(s.sigma_systematic_c) << '\n';
    }
  }
}

}  // namespace bosfuse::report
