#include "pipeline/heater_off_estimate.h"

#include <fmt/format.h>

#include <cmath>

#include "fitting/uncertainty_digits.h"
#include "storage/experiment_clock.h"

namespace bosfuse::pipeline {
namespace {

// A channel's ok samples on the experiment-seconds axis from `first_ns`.
fitting::KneeResult channel_knee(const storage::RunStore& store, const storage::ChannelInfo& channel,
                                 std::int64_t first_ns, double time_scale) {
  std::vector<double> t_s, temperature_c;
  for (const storage::Sample& s : store.read_samples(channel.id)) {
    if (s.status != storage::SampleStatus::kOk || !s.value) continue;
    t_s.push_back(static_cast<double>(s.t_ns - first_ns) * 1e-9 * time_scale);
    temperature_c.push_back(*s.value);
  }
  return fitting::find_knee(t_s, temperature_c);
}

std::string at_sigma(double value, double sigma) { return fitting::format_at_uncertainty(value, sigma); }

}  // namespace

HeaterOffEstimate estimate_heater_off(const storage::RunStore& store) {
  HeaterOffEstimate estimate;
  const auto first_ns = store.first_sample_ns();
  if (!first_ns) {
    estimate.reason = "the run has no samples";
    return estimate;
  }
  const double time_scale = store.run().time_scale;
  double weight_sum = 0, weighted_sum = 0;
  std::vector<fitting::Knee> knees;
  for (const storage::ChannelInfo& channel : store.channels()) {
    if (channel.kind != "thermocouple") continue;
    estimate.channels.push_back({channel.name, channel_knee(store, channel, *first_ns, time_scale)});
    const auto& knee = estimate.channels.back().knee.knee;
    if (!knee || !(knee->sigma_t_s > 0)) continue;
    knees.push_back(*knee);
    const double w = 1 / (knee->sigma_t_s * knee->sigma_t_s);
    weight_sum += w;
    weighted_sum += w * knee->t_s;
  }
  if (knees.empty()) {
    estimate.reason = estimate.channels.empty() ? "the run has no thermocouple channel"
                                                : "no thermocouple curve turns from heating to cooling";
    return estimate;
  }
  const double mean = weighted_sum / weight_sum;
  double chi2 = 0;
  for (const auto& k : knees) chi2 += std::pow((k.t_s - mean) / k.sigma_t_s, 2);
  const double birge = knees.size() > 1 ? std::max(1.0, std::sqrt(chi2 / static_cast<double>(knees.size() - 1))) : 1;
  estimate.offset_s = mean;
  estimate.sigma_s = birge / std::sqrt(weight_sum);
  estimate.t_ns = *first_ns + static_cast<std::int64_t>(std::llround(mean / time_scale * 1e9));
  return estimate;
}

std::string HeaterOffEstimate::brief_report() const {
  std::string text;
  for (const ChannelKnee& c : channels) {
    if (c.knee.knee) {
      const fitting::Knee& k = *c.knee.knee;
      text += fmt::format("  {}: knee at +{} ± {} s (slope {:+.3g} then {:+.3g} °C/s, {} samples)\n", c.channel,
                          at_sigma(k.t_s, k.sigma_t_s), at_sigma(k.sigma_t_s, k.sigma_t_s), k.slope_before_per_s,
                          k.slope_after_per_s, k.points);
    } else {
      text += fmt::format("  {}: no knee ({})\n", c.channel, c.knee.reason);
    }
  }
  if (!offset_s) return text + "no heater-off time can be proposed: " + reason + "\n";
  return text + fmt::format("heater off proposed at +{} ± {} s from the first sample ({}); a lagging "
                            "thermocouple's knee comes up to its time constant late\n",
                            at_sigma(*offset_s, sigma_s), at_sigma(sigma_s, sigma_s),
                            storage::format_iso8601_utc(t_ns, 3));
}

}  // namespace bosfuse::pipeline
