#include "acquisition/emf_conversion.h"

#include <algorithm>
#include <stdexcept>

namespace bosfuse::acquisition {

using storage::SampleStatus;

void convert_emf_readings(const std::vector<EmfConversion>& conversions, std::vector<ChannelReading>& readings) {
  for (const EmfConversion& c : conversions) {
    if (c.channel >= readings.size()) continue;
    ChannelReading& reading = readings[c.channel];
    if (!reading.value) continue;  // the device already said why there is none
    std::optional<double> cold_junction_c = c.input.cold_junction_c;
    if (c.cold_junction_index) {
      cold_junction_c =
          *c.cold_junction_index < readings.size() ? readings[*c.cold_junction_index].value : std::nullopt;
    }
    if (!cold_junction_c) {
      reading = {std::nullopt, reading.raw, SampleStatus::kInvalidValue};
      continue;
    }
    const TemperatureResult t = compensated_temperature_c(c.input.type, *reading.value, *cold_junction_c);
    reading = {t.temperature_c, reading.raw, t.status};
  }
}

EmfConvertingSource::EmfConvertingSource(std::unique_ptr<ThermocoupleSource> inner,
                                         const std::vector<std::optional<EmfInput>>& inputs)
    : inner_(std::move(inner)) {
  const auto channels = inner_->channel_infos();
  for (std::size_t i = 0; i < inputs.size() && i < channels.size(); ++i) {
    if (!inputs[i]) continue;
    EmfConversion conversion{i, *inputs[i], std::nullopt};
    if (!inputs[i]->cold_junction_c) {
      const auto cj = std::find_if(channels.begin(), channels.end(),
                                   [&](const auto& c) { return c.name == inputs[i]->cold_junction_channel; });
      if (cj == channels.end() || cj->name == channels[i].name) {
        throw std::invalid_argument("channel " + channels[i].name + ": no cold-junction channel '" +
                                    inputs[i]->cold_junction_channel + "' on its device");
      }
      conversion.cold_junction_index = static_cast<std::size_t>(cj - channels.begin());
    }
    conversions_.push_back(conversion);
  }
}

std::vector<storage::ChannelInfo> EmfConvertingSource::channel_infos() const {
  auto infos = inner_->channel_infos();
  for (const EmfConversion& c : conversions_) {
    infos[c.channel].kind = "thermocouple";
    infos[c.channel].unit = "degC";
    infos[c.channel].tc_type = std::string(to_string(c.input.type));
    infos[c.channel].resolution = c.input.resolution_c;
  }
  return infos;
}

std::vector<ChannelReading> EmfConvertingSource::read() {
  std::vector<ChannelReading> readings = inner_->read();
  convert_emf_readings(conversions_, readings);
  return readings;
}

std::unique_ptr<ThermocoupleSource> with_emf_conversion(std::unique_ptr<ThermocoupleSource> source,
                                                        const std::vector<std::optional<EmfInput>>& inputs) {
  if (std::none_of(inputs.begin(), inputs.end(), [](const auto& input) { return input.has_value(); })) return source;
  return std::make_unique<EmfConvertingSource>(std::move(source), inputs);
}

}  // namespace bosfuse::acquisition
