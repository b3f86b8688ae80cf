#pragma once
// A proposed "heater off" moment for a run that was not marked while it
// recorded: the knee of each thermocouple curve (fitting/knee.h), where its
// heating turns into cooling, combined over the channels. `bosfuse mark RUN
// "heater off" --estimate` prints it for the user to accept with --at; it
// writes nothing, so a guess never becomes a run's origin unseen.
//
// Each thermocouple channel with a knee gives t_k ± σ_k; the proposal is
// their inverse-variance mean, its σ scaled up by the Birge ratio
// sqrt(χ²/(m − 1)) when the channels disagree by more than their σ say
// (thermocouples with different lags do). Times are experiment seconds
// from the run's first sample, the form `mark --at +12.5s` takes.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fitting/knee.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {

struct ChannelKnee {
  std::string channel;
  fitting::KneeResult knee;  // t_s in experiment seconds from the first sample
};

struct HeaterOffEstimate {
  std::optional<double> offset_s;  // experiment seconds after the run's first sample
  double sigma_s = 0;              // its standard uncertainty
  std::int64_t t_ns = 0;           // the host-clock time of offset_s
  std::vector<ChannelKnee> channels;
  std::string reason;  // why there is no estimate

  // One line per channel and the combination, for stderr.
  std::string brief_report() const;
};

HeaterOffEstimate estimate_heater_off(const storage::RunStore& store);

}  // namespace bosfuse::pipeline
