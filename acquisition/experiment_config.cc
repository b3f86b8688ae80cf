#include "acquisition/experiment_config.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace bosfuse::acquisition {
namespace {

using std::chrono::duration_cast;

std::chrono::nanoseconds seconds_to_ns(double seconds) {
  return std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(seconds * 1e9)));
}

double positive_seconds(const TomlReader& r, std::string_view key, double fallback, double minimum) {
  const double value = r.optional_number(key).value_or(fallback);
  if (value < minimum) r.fail(key, "must be at least " + std::to_string(minimum) + " s");
  return value;
}

int integer_in(const TomlReader& r, std::string_view key, int fallback, int low, int high) {
  const std::int64_t value = r.optional_integer(key).value_or(fallback);
  if (value < low || value > high) {
    r.fail(key, "must be between " + std::to_string(low) + " and " + std::to_string(high));
  }
  return static_cast<int>(value);
}

ModbusTransport read_transport(const TomlReader& r, const ModbusProfile& profile) {
  const auto text = r.optional_string("transport");
  if (!text) {
    if (!profile.usual_transport) r.fail("", "missing required key 'transport' (\"tcp\" or \"rtu\")");
    return *profile.usual_transport;
  }
  if (*text == "tcp") return ModbusTransport::kTcp;
  if (*text == "rtu") return ModbusTransport::kRtu;
  r.fail("transport", "expected \"tcp\" or \"rtu\", got \"" + *text + "\"");
}

ModbusEndpoint read_endpoint(const TomlReader& r, const ModbusProfile& profile) {
  ModbusEndpoint e;
  e.transport = read_transport(r, profile);
  e.unit_id = integer_in(r, "unit_id", 1, 0, 247);
  if (e.transport == ModbusTransport::kTcp) {
    e.host = r.string("host");
    e.port = integer_in(r, "port", 502, 1, 65535);
  } else {
    e.serial_port = r.string("serial_port");
    e.baud = integer_in(r, "baud", 9600, 300, 4'000'000);
    const std::string parity = r.optional_string("parity").value_or("N");
    if (parity != "N" && parity != "E" && parity != "O") r.fail("parity", "expected \"N\", \"E\" or \"O\"");
    e.parity = parity[0];
    e.data_bits = integer_in(r, "data_bits", 8, 5, 8);
    e.stop_bits = integer_in(r, "stop_bits", 1, 1, 2);
  }
  return e;
}

void read_placement(const TomlReader& r, ModbusChannel& channel) {
  const std::vector<double> position = r.numbers("position_px");
  if (position.empty()) return;
  if (position.size() != 2) r.fail("position_px", "expected [x, y] in image pixels");
  channel.image_x_px = position[0];
  channel.image_y_px = position[1];
}

// Register fields, required for a generic channel, optional overrides
// otherwise.
void read_register_map(const TomlReader& r, ModbusChannel& c, bool generic) {
  if (generic || r.has("register")) {
    const std::string kind = r.string("register");
    if (kind != "holding" && kind != "input") r.fail("register", "expected \"holding\" or \"input\"");
    c.function = kind == "holding" ? RegisterKind::kHolding : RegisterKind::kInput;
  }
  if (generic || r.has("address")) c.address = integer_in(r, "address", 0, 0, 65535);
  if (const auto type = r.optional_string("type")) {
    const auto parsed = parse_data_type(*type);
    if (!parsed) r.fail("type", "expected int16, uint16, int32, uint32 or float32");
    c.type = *parsed;
  }
  if (const auto order = r.optional_string("word_order")) {
    const auto parsed = parse_word_order(*order);
    if (!parsed) r.fail("word_order", "expected ABCD, CDAB, BADC or DCBA");
    c.order = *parsed;
  }
  if (auto v = r.optional_number("scale")) c.scale = *v;
  if (auto v = r.optional_number("offset")) c.offset = *v;
  if (const auto linear = r.table("linear")) {
    const auto raw = linear->numbers("raw");
    const auto value = linear->numbers("value");
    if (raw.size() != 2) linear->fail("raw", "expected [raw_low, raw_high]");
    if (value.size() != 2) linear->fail("value", "expected [value_low, value_high]");
    c.linear = LinearMapping{raw[0], raw[1], value[0], value[1]};
    linear->reject_unknown_keys();
  }
  if (r.has("open_circuit_codes")) c.open_circuit_codes = r.numbers("open_circuit_codes");
  if (r.has("out_of_range_codes")) c.out_of_range_codes = r.numbers("out_of_range_codes");
  const std::vector<double> valid = r.numbers("valid_range");
  if (!valid.empty()) {
    if (valid.size() != 2) r.fail("valid_range", "expected [min, max]");
    c.valid_min = valid[0];
    c.valid_max = valid[1];
  }
}

ModbusChannel profile_channel(const TomlReader& r, const ModbusProfile& profile) {
  const toml::node* input = r.node("input");
  if (!input) r.fail("", "missing required key 'input' (an input number, or \"cold-junction\")");
  if (input->is_string() && input->value<std::string>() == "cold-junction") {
    return profile_cold_junction_channel(profile.name);
  }
  if (!input->is_integer()) r.fail("input", "expected an input number or \"cold-junction\"");
  const std::string tc_type = r.optional_string("tc_type").value_or("K");
  try {
    return profile_input_channel(profile.name, static_cast<int>(*input->value<std::int64_t>()), tc_type);
  } catch (const std::invalid_argument& e) {
    r.fail("input", e.what());
  }
}

ModbusChannel read_channel(const TomlReader& r, const ModbusProfile& profile) {
  const bool generic = profile.input_count == 0;
  ModbusChannel c = generic ? ModbusChannel{} : profile_channel(r, profile);
  c.name = r.string("name");
  if (auto kind = r.optional_string("kind")) c.kind = *kind;
  if (auto unit = r.optional_string("unit")) c.unit = *unit;
  if (generic) c.tc_type = r.optional_string("tc_type");
  read_placement(r, c);
  read_register_map(r, c, generic);
  if (const std::string problem = c.Validate(); !problem.empty()) r.fail("", problem);
  r.reject_unknown_keys();
  return c;
}

ModbusDeviceConfig read_modbus_device(const TomlReader& r) {
  ModbusDeviceConfig d;
  d.name = r.string("name");
  d.profile = r.string("profile");
  const ModbusProfile* profile = find_modbus_profile(d.profile);
  if (!profile) r.fail("profile", "unknown profile \"" + d.profile + "\" (adam-6018, icpdas-m7018 or generic)");
  d.endpoint = read_endpoint(r, *profile);
  d.poll_period = seconds_to_ns(positive_seconds(r, "poll_period_s", 1.0, 0.001));
  d.timeout = duration_cast<std::chrono::milliseconds>(seconds_to_ns(positive_seconds(r, "timeout_s", 0.5, 0.001)));
  std::set<std::string> names;
  for (const TomlReader& channel : r.tables("channels")) {
    d.channels.push_back(read_channel(channel, *profile));
    if (!names.insert(d.channels.back().name).second) {
      channel.fail("name", "duplicate channel name \"" + d.channels.back().name + "\"");
    }
  }
  if (d.channels.empty()) r.fail("", "a device needs at least one [[devices.channels]] entry");
  r.reject_unknown_keys();
  return d;
}

void read_device(const TomlReader& r, ExperimentConfig& config) {
  const std::string kind = r.optional_string("kind").value_or("modbus");
  if (kind != "modbus") r.fail("kind", "unknown device kind \"" + kind + "\" (supported: modbus)");
  config.modbus_devices.push_back(read_modbus_device(r));
}

}  // namespace

ExperimentConfig parse_experiment(std::string_view text, const std::string& source_name) {
  const toml::table root = parse_toml(text, source_name);
  const TomlReader reader(root, "", source_name);
  ExperimentConfig config;
  config.source_text = std::string(text);
  if (const auto run = reader.table("run")) {
    config.run_name = run->optional_string("name").value_or("");
    config.description = run->optional_string("description").value_or("");
    run->reject_unknown_keys();
  }
  std::set<std::string> names;
  for (const TomlReader& device : reader.tables("devices")) {
    read_device(device, config);
    if (!names.insert(config.modbus_devices.back().name).second) {
      device.fail("name", "duplicate device name \"" + config.modbus_devices.back().name + "\"");
    }
  }
  reader.reject_unknown_keys();
  return config;
}

ExperimentConfig load_experiment(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError("cannot read experiment file '" + path.string() + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_experiment(text.str(), path.string());
}

}  // namespace bosfuse::acquisition
