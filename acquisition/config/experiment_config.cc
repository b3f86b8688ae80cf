#include "acquisition/config/experiment_config.h"

#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "acquisition/config/folder_name.h"
#include "acquisition/cameras/genicam_source.h"
#include "acquisition/cameras/recorded_frame_source.h"
#include "storage/disk_space.h"

namespace bosfuse::acquisition {
namespace {

using std::chrono::duration_cast;

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
  e.unit_id = r.integer_in("unit_id", 1, 0, 247);
  if (e.transport == ModbusTransport::kTcp) {
    e.host = r.string("host");
    e.port = r.integer_in("port", 502, 1, 65535);
  } else {
    e.serial_port = r.string("serial_port");
    e.baud = r.integer_in("baud", 9600, 300, 4'000'000);
    const std::string parity = r.optional_string("parity").value_or("N");
    if (parity != "N" && parity != "E" && parity != "O") r.fail("parity", "expected \"N\", \"E\" or \"O\"");
    e.parity = parity[0];
    e.data_bits = r.integer_in("data_bits", 8, 5, 8);
    e.stop_bits = r.integer_in("stop_bits", 1, 1, 2);
  }
  return e;
}

template <typename Channel>
void read_position(const TomlReader& r, Channel& c) {
  if (const auto position = r.optional_pair("position_px", "[x, y] in image pixels")) {
    c.image_x_px = position->first;
    c.image_y_px = position->second;
  }
}

// A thermocouple's response time: from 0 (none) to an hour, beyond which it
// is a typo rather than a sensor.
constexpr double kLongestTimeConstantS = 3600;

template <typename Channel>
void read_time_constant(const TomlReader& r, Channel& c) {
  if (!r.has("time_constant_s")) return;
  c.time_constant_s =
      r.number_in("time_constant_s", 0.0, 0.0, kLongestTimeConstantS, "the sensor's first-order response time in s");
}

// A channel's resolution, the smallest step of its values in its unit
// (0.1 for a module that reports tenths of a degree): it sets the digits
// its values are printed with. Above 0, and below any sensible range.
template <typename Channel>
void read_resolution(const TomlReader& r, Channel& c) {
  if (!r.has("resolution")) return;
  c.resolution = r.number_in("resolution", 0.0, 1e-12, 1e6, "a step in the channel's unit");
}

template <typename Channel>
void read_alarms(const TomlReader& r, Channel& c) {
  c.alarms.low = r.optional_number("alarm_low");
  c.alarms.high = r.optional_number("alarm_high");
  c.alarms.rate_per_min = r.optional_number("alarm_rate_per_min");
  c.alarms.stale_s = r.optional_number("alarm_stale_s");
  if (const auto problem = c.alarms.problem()) r.fail(problem->key, problem->message);
}

// What a channel measures, where it is in the image and when it is alarming:
// the keys every kind of channel shares.
template <typename Channel>
void read_channel_identity(const TomlReader& r, Channel& c) {
  c.name = r.string("name");
  if (auto kind = r.optional_string("kind")) c.kind = *kind;
  if (auto unit = r.optional_string("unit")) c.unit = *unit;
  read_position(r, c);
  read_time_constant(r, c);
  read_resolution(r, c);
  read_alarms(r, c);
}

// `emf_type` marks a channel that delivers millivolts from a thermocouple;
// its cold junction is another channel of the device or a fixed temperature.
std::optional<EmfInput> read_emf_input(const TomlReader& r) {
  const auto type_text = r.optional_string("emf_type");
  if (!type_text) {
    if (r.has("cold_junction") || r.has("cold_junction_c")) r.fail("emf_type", "cold junction given without emf_type");
    return std::nullopt;
  }
  const auto type = parse_thermocouple_type(*type_text);
  if (!type) r.fail("emf_type", "expected a thermocouple type: B, E, J, K, N, R, S or T");
  // Absolute zero to beyond the hottest thermocouple type (B, 1820 °C).
  const auto fixed_c = r.has("cold_junction_c")
                           ? std::optional(r.number_in("cold_junction_c", 0, -273.15, 2000, "a temperature in °C"))
                           : std::nullopt;
  EmfInput input{*type, r.optional_string("cold_junction").value_or(""), fixed_c, std::nullopt};
  if (input.cold_junction_channel.empty() == !input.cold_junction_c) {
    r.fail("", "a millivolt channel needs exactly one of cold_junction (a channel name) and cold_junction_c");
  }
  return input;
}

// Cold-junction channels must exist on the same device.
void check_cold_junctions(const TomlReader& device, const std::vector<std::optional<EmfInput>>& inputs,
                          const std::set<std::string>& channel_names) {
  const auto tables = device.tables("channels");
  for (std::size_t i = 0; i < inputs.size() && i < tables.size(); ++i) {
    if (inputs[i] && !inputs[i]->cold_junction_c && !channel_names.count(inputs[i]->cold_junction_channel)) {
      tables[i].fail("cold_junction", "no channel \"" + inputs[i]->cold_junction_channel + "\" on this device");
    }
  }
}

template <typename Channel>
void read_validity(const TomlReader& r, Channel& c) {
  if (r.has("open_circuit_codes")) c.open_circuit_codes = r.numbers("open_circuit_codes");
  if (const auto valid = r.optional_pair("valid_range", "[min, max]")) {
    c.valid_min = valid->first;
    c.valid_max = valid->second;
  }
}

template <typename Device>
void read_schedule(const TomlReader& r, Device& d) {
  d.poll_period = r.seconds("poll_period_s", 1.0, kShortestPollPeriodS);
  d.poll_count = r.optional_integer_in("poll_count", 1, std::numeric_limits<std::int64_t>::max());
  d.timeout = std::chrono::duration_cast<std::chrono::milliseconds>(r.seconds("timeout_s", 0.5, 0.001));
}

// Register fields, required for a generic channel, optional overrides
// otherwise.
void read_register_map(const TomlReader& r, ModbusChannel& c, bool generic) {
  if (generic || r.has("register")) {
    const std::string kind = r.string("register");
    if (kind != "holding" && kind != "input") r.fail("register", "expected \"holding\" or \"input\"");
    c.function = kind == "holding" ? RegisterKind::kHolding : RegisterKind::kInput;
  }
  if (generic || r.has("address")) c.address = r.integer_in("address", 0, 0, 65535);
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
  if (r.has("out_of_range_codes")) c.out_of_range_codes = r.numbers("out_of_range_codes");
  read_validity(r, c);
}

ModbusChannel profile_channel(const TomlReader& r, const ModbusProfile& profile) {
  const toml::node* input = r.node("input");
  if (!input) r.fail("", "missing required key 'input' (an input number, or \"cold-junction\")");
  if (input->is_string() && input->value<std::string>() == "cold-junction") {
    return profile_cold_junction_channel(profile.name);
  }
  if (!input->is_integer()) r.fail("input", "expected an input number or \"cold-junction\"");
  const auto number = static_cast<int>(r.integer_in("input", 0, profile.input_count - 1));
  const std::string tc_type = r.optional_string("tc_type").value_or("K");
  try {
    return profile_input_channel(profile.name, number, tc_type);
  } catch (const std::invalid_argument& e) {
    r.fail("input", e.what());
  }
}

ModbusChannel read_channel(const TomlReader& r, const ModbusProfile& profile) {
  const bool generic = profile.input_count == 0;
  ModbusChannel c = generic ? ModbusChannel{} : profile_channel(r, profile);
  read_channel_identity(r, c);
  if (generic) c.tc_type = r.optional_string("tc_type");
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
  d.host_key = r.where("host");
  read_schedule(r, d);
  std::set<std::string> names;
  for (const TomlReader& channel : r.tables("channels")) {
    d.emf_inputs.push_back(read_emf_input(channel));
    d.channels.push_back(read_channel(channel, *profile));
    if (d.emf_inputs.back()) d.emf_inputs.back()->resolution_c = d.channels.back().resolution;
    names.insert(d.channels.back().name);
  }
  if (d.channels.empty()) r.fail("", "a device needs at least one [[devices.channels]] entry");
  check_cold_junctions(r, d.emf_inputs, names);
  r.reject_unknown_keys();
  return d;
}

HidChannel mcc_channel(const TomlReader& r, HidProtocol& protocol) {
  const toml::node* input = r.node("input");
  if (!input) r.fail("", "missing required key 'input' (0-7, \"cold-junction-0\" or \"cold-junction-1\")");
  for (int cj = 0; cj < 2; ++cj) {
    if (input->value<std::string>() == "cold-junction-" + std::to_string(cj))
      return mcc_usb_tc_channel(kMccColdJunction0 + cj);
  }
  if (!input->is_integer()) r.fail("input", "expected 0-7, \"cold-junction-0\" or \"cold-junction-1\"");
  const auto channel_input = static_cast<int>(r.integer_in("input", 0, 7));
  HidChannel c = mcc_usb_tc_channel(channel_input);
  c.tc_type = r.optional_string("tc_type").value_or("K");
  const auto code = mcc_tc_type_code(*c.tc_type);
  if (!code) r.fail("tc_type", "the USB-TC takes types J, K, T, E, R, S, B or N");
  protocol.setup_requests.push_back(mcc_set_tc_type_request(channel_input, *code));
  return c;
}

HidChannel generic_hid_channel(const TomlReader& r) {
  HidChannel c;
  c.request = r.bytes("request");
  if (c.request.empty()) r.fail("", "missing required key 'request' (the report to send, report id first)");
  if (const auto id = r.optional_integer_in("reply_report_id", 0, 255))
    c.reply_report_id = static_cast<std::uint8_t>(*id);
  c.value_offset = r.integer_in("value_offset", 0, 0, 63);
  if (const auto type = r.optional_string("type")) {
    const auto parsed = parse_hid_value_type(*type);
    if (!parsed) r.fail("type", "expected int16, uint16, int32, uint32 or float32");
    c.type = *parsed;
  }
  const std::string order = r.optional_string("byte_order").value_or("little");
  if (order != "little" && order != "big") r.fail("byte_order", "expected \"little\" or \"big\"");
  c.big_endian = order == "big";
  if (auto v = r.optional_number("scale")) c.scale = *v;
  if (auto v = r.optional_number("offset")) c.offset = *v;
  c.tc_type = r.optional_string("tc_type");
  return c;
}

HidChannel read_hid_channel(const TomlReader& r, const std::string& profile, HidProtocol& protocol) {
  HidChannel c;
  if (profile == "mcc-usb-tc") {
    c = mcc_channel(r, protocol);
  } else if (profile == "temper") {
    c = temper_channel(r.optional_number("divisor").value_or(256.0));
  } else {
    c = generic_hid_channel(r);
  }
  read_channel_identity(r, c);
  read_validity(r, c);
  if (const std::string problem = c.Validate(); !problem.empty()) r.fail("", problem);
  r.reject_unknown_keys();
  return c;
}

std::uint16_t usb_id(const TomlReader& r, std::string_view key) {
  return static_cast<std::uint16_t>(r.integer_in(key, 0, 0xFFFF));  // required: a missing id is no default
}

HidMatch read_hid_match(const TomlReader& r, const std::string& profile) {
  HidMatch m;
  if (profile == "mcc-usb-tc") {
    m = {kMccVendorId, kMccUsbTcProductId, std::nullopt, std::nullopt};
  } else if (profile == "temper") {
    m = {kTemperVendorId, kTemperProductId, kTemperInterface, std::nullopt};
  }
  // A generic device has no ids of its own; integer_in() reports a missing key.
  const bool ids_required = profile == "generic-hid";
  if (ids_required || r.has("vendor_id")) m.vendor_id = usb_id(r, "vendor_id");
  if (ids_required || r.has("product_id")) m.product_id = usb_id(r, "product_id");
  if (r.has("interface")) m.interface_number = r.integer_in("interface", 0, 0, 255);
  m.serial = r.optional_string("serial");
  return m;
}

HidDeviceConfig read_hid_device(const TomlReader& r) {
  HidDeviceConfig d;
  d.name = r.string("name");
  d.profile = r.string("profile");
  if (d.profile != "mcc-usb-tc" && d.profile != "temper" && d.profile != "generic-hid") {
    r.fail("profile", "unknown HID profile \"" + d.profile + "\" (mcc-usb-tc, temper or generic-hid)");
  }
  d.match = read_hid_match(r, d.profile);
  read_schedule(r, d);
  if (d.profile == "mcc-usb-tc") {
    d.protocol.burnout_request = mcc_burnout_request();
    d.protocol.burnout_reply_report_id = d.protocol.burnout_request->front();
  }
  for (auto& request : r.byte_arrays("setup_requests")) d.protocol.setup_requests.push_back(std::move(request));
  std::set<std::string> names;
  for (const TomlReader& channel : r.tables("channels")) {
    d.emf_inputs.push_back(read_emf_input(channel));
    d.protocol.channels.push_back(read_hid_channel(channel, d.profile, d.protocol));
    if (d.emf_inputs.back()) d.emf_inputs.back()->resolution_c = d.protocol.channels.back().resolution;
    names.insert(d.protocol.channels.back().name);
  }
  if (d.protocol.channels.empty()) r.fail("", "a device needs at least one [[devices.channels]] entry");
  check_cold_junctions(r, d.emf_inputs, names);
  r.reject_unknown_keys();
  return d;
}

UsbTc32Channel read_usb_tc32_channel(const TomlReader& r) {
  UsbTc32Channel c;
  c.name = r.string("name");
  c.input = static_cast<int>(r.integer_in("input", 0, 63));
  c.cold_junction = r.optional_string("kind").value_or("thermocouple") == "cold-junction";
  const std::string type = r.optional_string("tc_type").value_or("K");
  if (type.size() != 1 || !tc32_type_code(type[0]))
    r.fail("tc_type", "the USB-TC-32 takes types J, K, T, E, R, S, B or N");
  c.tc_type = type[0];
  read_position(r, c);
  read_time_constant(r, c);
  read_resolution(r, c);
  read_alarms(r, c);
  r.reject_unknown_keys();
  return c;
}

UsbDeviceConfig read_usb_device(const TomlReader& r) {
  UsbDeviceConfig d;
  d.name = r.string("name");
  d.profile = r.string("profile");
  if (d.profile != "usb-tc-32") r.fail("profile", "unknown USB profile \"" + d.profile + "\" (usb-tc-32)");
  d.serial = r.optional_string("serial");
  read_schedule(r, d);
  for (const TomlReader& channel : r.tables("channels")) d.channels.push_back(read_usb_tc32_channel(channel));
  if (d.channels.empty()) r.fail("", "a device needs at least one [[devices.channels]] entry");
  r.reject_unknown_keys();
  return d;
}

std::string read_device(const TomlReader& r, ExperimentConfig& config) {
  const std::string kind = r.optional_string("kind").value_or("modbus");
  if (kind == "modbus") {
    config.modbus_devices.push_back(read_modbus_device(r));
    return config.modbus_devices.back().name;
  }
  if (kind == "hid") {
    config.hid_devices.push_back(read_hid_device(r));
    return config.hid_devices.back().name;
  }
  if (kind == "usb") {
    config.usb_devices.push_back(read_usb_device(r));
    return config.usb_devices.back().name;
  }
  r.fail("kind", "unknown device kind \"" + kind + "\" (modbus, hid or usb)");
}

GenicamTrigger read_genicam_trigger(const TomlReader& r, GenicamOptions& g) {
  const std::string trigger = r.optional_string("trigger").value_or("free-run");
  if (trigger == "free-run") return GenicamTrigger::kFreeRun;
  if (trigger == "software") {
    g.software_trigger_period = r.seconds("trigger_period_s", 1.0, 1e-4);
    if (!r.has("trigger_period_s")) r.fail("trigger", "a software trigger needs trigger_period_s");
    return GenicamTrigger::kSoftware;
  }
  if (trigger == "hardware") {
    g.trigger_line = r.optional_string("line").value_or("Line1");
    const std::string edge = r.optional_string("edge").value_or("rising");
    if (edge == "rising") {
      g.trigger_edge = "RisingEdge";
    } else if (edge == "falling") {
      g.trigger_edge = "FallingEdge";
    } else {
      r.fail("edge", "expected \"rising\" or \"falling\", got \"" + edge + "\"");
    }
    return GenicamTrigger::kHardware;
  }
  r.fail("trigger", "expected \"free-run\", \"software\" or \"hardware\", got \"" + trigger + "\"");
}

// features = { Name = value }: any other GenICam feature, set by name.
std::vector<GenicamFeature> read_genicam_features(const TomlReader& r) {
  std::vector<GenicamFeature> out;
  const std::optional<TomlReader> table = r.table("features");
  if (!table) return out;
  for (const auto& [key, value] : *r.node("features")->as_table()) {
    GenicamFeature f{std::string(key.str()), std::int64_t{0}};
    table->node(key.str());
    if (const auto* i = value.as_integer()) {
      f.value = i->get();
    } else if (const auto* d = value.as_floating_point()) {
      f.value = d->get();
    } else if (const auto* b = value.as_boolean()) {
      f.value = b->get();
    } else if (const auto* s = value.as_string()) {
      f.value = s->get();
    } else {
      table->fail(key.str(), "expected a number, a boolean or a string (an enumeration's entry)");
    }
    out.push_back(std::move(f));
  }
  return out;
}

void read_genicam(const TomlReader& r, CameraConfig& c) {
  GenicamOptions& g = c.genicam;
  g.device = r.string("device");
  c.genicam_key = r.where("device");
  g.pixel_format = r.optional_string("pixel_format").value_or("");
  g.exposure_us = r.optional_number("exposure_us");
  g.gain_db = r.optional_number("gain_db");
  g.frame_rate_hz = r.optional_number("frame_rate_hz");
  const std::vector<double> roi = r.numbers("roi_px");
  if (!roi.empty()) {
    if (roi.size() != 4) r.fail("roi_px", "expected [x, y, width, height] in pixels");
    g.roi = GenicamRoi{std::llround(roi[0]), std::llround(roi[1]), std::llround(roi[2]), std::llround(roi[3])};
  }
  g.trigger = read_genicam_trigger(r, g);
  g.features = read_genicam_features(r);
  g.packet_resend = r.optional_bool("packet_resend").value_or(true);
  g.buffer_count = r.integer_in("buffers", 16, 2, 1024);
  g.frame_timeout = duration_cast<std::chrono::milliseconds>(r.seconds("frame_timeout_s", 2.0, 0.1));
  g.clock_report_period = duration_cast<std::chrono::milliseconds>(r.seconds("clock_report_s", 10.0, 0.1));
  // Each problem names the key it is about.
  const std::string problem = g.Validate();
  if (problem.empty()) return;
  for (const char* key : {"pixel_format", "exposure_us", "gain_db", "frame_rate_hz", "roi_px", "trigger_period_s"}) {
    if (problem.starts_with(key)) r.fail(key, problem);
  }
  r.fail("device", problem);
}

CameraConfig read_camera(const TomlReader& r) {
  CameraConfig c;
  c.name = r.string("name");
  if (const std::string problem = folder_name_problem(c.name); !problem.empty()) {
    r.fail("name", "a camera name names its frame folder (frames/<name>/): it " + problem);
  }
  c.source = r.string("source");
  if (c.source == "video") {
    c.target = r.string("device");
    c.recorder.interval = r.seconds("interval_s", 1.0, 0.001);
  } else if (c.source == "folder") {
    c.folder.folder = r.string("folder");
    c.folder.settle = std::chrono::duration_cast<std::chrono::milliseconds>(r.seconds("settle_s", 0.5, 0.0));
    c.folder.camera_clock_offset_s =
        r.number_in("camera_clock_offset_s", 0.0, -kLargestClockOffsetS, kLargestClockOffsetS, "seconds");
  } else if (c.source == "replay") {
    c.target = r.string("run");
    c.run_key = r.where("run");
    c.replay_camera = r.string("camera");
    c.replay_speed = r.number_in("speed", 1.0, 1e-3, 1e4, "a speed-up");
  } else if (c.source == "genicam") {
    read_genicam(r, c);  // frames as the camera sends them
  } else {
    r.fail("source",
           "expected \"video\" (a camera, video file or URL), \"folder\" (files a camera writes), \"genicam\" "
           "(a GigE Vision or USB3 Vision camera) or \"replay\"");
  }
  c.recorder.reference_frames = r.integer_in("reference_frames", 1, 0, 1'000'000);
  c.reference_flag = r.optional_string("reference_flag").value_or("reference.flag");
  r.reject_unknown_keys();
  return c;
}

// A millivolt channel is recorded (and alarmed) in °C once converted. A
// device built in code may have no emf_inputs at all.
std::string recorded_unit(const std::string& unit, const std::vector<std::optional<EmfInput>>& emf_inputs,
                          std::size_t channel) {
  return channel < emf_inputs.size() && emf_inputs[channel] ? "degC" : unit;
}

// The channel names of the file so far, each with where it is, so that a
// duplicate (channel_name_key) is refused naming both places.
class ChannelNames {
 public:
  void add_device(const TomlReader& device) {
    for (const TomlReader& channel : device.tables("channels")) {
      const std::string name = channel.string("name");
      const auto [first, added] = first_seen_.emplace(channel_name_key(name), std::pair(name, channel.where("name")));
      if (added) continue;
      const auto& [other_name, other_where] = first->second;
      channel.fail("name",
                   "duplicate channel name \"" + name + "\"" +
                       (other_name == name ? "" : " (the same as \"" + other_name + "\" but for case or spaces)") +
                       ", already at " + other_where + "; channel names must be unique across all devices");
    }
  }

 private:
  std::map<std::string, std::pair<std::string, std::string>> first_seen_;  // comparable name: (name, where)
};
// At most 2^40 MB, so the bytes fit in 64 bits.
void read_min_free(const TomlReader& run, ExperimentConfig& config) {
  constexpr std::int64_t kMostMb = std::int64_t{1} << 40;
  if (!run.has("min_free_mb")) {
    config.min_free_key = run.where("min_free_mb") + " (default 100)";
    return;
  }
  config.min_free_mb = run.integer_in("min_free_mb", 0, kMostMb);
  config.min_free_key = run.where("min_free_mb");
}

// [agreement]: the equivalence margins of the thermocouple–BOS verdict.
void read_agreement(const TomlReader& agreement, ExperimentConfig& config) {
  config.agreement.margin_c =
      agreement.number_in("margin_c", config.agreement.margin_c, 1e-6, 1000, "a temperature margin in °C");
  config.agreement.margin_k_relative = agreement.number_in("margin_k_relative", config.agreement.margin_k_relative,
                                                           1e-6, 10, "a margin of k as a fraction of k");
  agreement.reject_unknown_keys();
}

}  // namespace

std::string channel_name_key(std::string_view name) {
  std::string key;
  for (const unsigned char c : name) {
    if (std::isspace(c)) {
      if (!key.empty() && key.back() != ' ') key += ' ';
    } else {
      key += static_cast<char>(std::tolower(c));
    }
  }
  if (!key.empty() && key.back() == ' ') key.pop_back();
  return key;
}

ExperimentConfig parse_experiment(std::string_view text, const std::string& source_name) {
  const toml::table root = parse_toml(text, source_name);
  const TomlReader reader(root, "", source_name);
  ExperimentConfig config;
  config.source_text = std::string(text);
  if (const auto run = reader.table("run")) {
    config.run_name = run->optional_string("name").value_or("");
    config.description = run->optional_string("description").value_or("");
    config.time_scale = run->number_in("time_scale", 1.0, kSmallestTimeScale, kLargestTimeScale,
                                       "experiment seconds per recorded second");
    config.origin_event = run->optional_string("origin");
    if (config.origin_event && config.origin_event->empty()) run->fail("origin", "expected the name of a marker event");
    read_min_free(*run, config);
    run->reject_unknown_keys();
  }
  if (config.min_free_key.empty()) config.min_free_key = source_name + ": run.min_free_mb (default 100)";
  std::set<std::string> names;
  ChannelNames channel_names;
  for (const TomlReader& device : reader.tables("devices")) {
    const std::string name = read_device(device, config);
    if (!names.insert(name).second) device.fail("name", "duplicate device name \"" + name + "\"");
    channel_names.add_device(device);
  }
  // The optical set-up and camera alignment are for processing (bosfuse
  // process reads and checks them); the logger only keeps them in the run.
  reader.node("geometry");
  reader.node("alignment");
  if (const auto agreement = reader.table("agreement")) read_agreement(*agreement, config);
  for (const TomlReader& camera : reader.tables("cameras")) {
    config.cameras.push_back(read_camera(camera));
    if (!names.insert(config.cameras.back().name).second) {
      camera.fail("name", "duplicate device name \"" + config.cameras.back().name + "\"");
    }
  }
  reader.reject_unknown_keys();
  return config;
}

storage::RunInfo run_info(const ExperimentConfig& config, std::int64_t started_ns) {
  storage::RunInfo info;
  info.name = config.run_name.empty() ? std::string("run") : config.run_name;
  info.started_ns = started_ns;
  info.config_toml = config.source_text;
  info.time_scale = config.time_scale;
  info.origin_event = config.origin_event;
  return info;
}

ExperimentConfig load_experiment(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError("cannot read experiment file '" + path.string() + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_experiment(text.str(), path.string());
}

std::map<std::string, double> channel_time_constants(const ExperimentConfig& config) {
  std::map<std::string, double> out;
  const auto add = [&](const auto& channels) {
    for (const auto& c : channels) {
      if (c.time_constant_s) out[channel_name_key(c.name)] = *c.time_constant_s;
    }
  };
  for (const auto& d : config.modbus_devices) add(d.channels);
  for (const auto& d : config.hid_devices) add(d.protocol.channels);
  for (const auto& d : config.usb_devices) add(d.channels);
  return out;
}

std::vector<ChannelAlarmLimits> alarm_limits(const ExperimentConfig& config) {
  std::vector<ChannelAlarmLimits> out;
  const auto add = [&](const std::string& device, const std::string& channel, const std::string& unit,
                       const AlarmLimits& limits) {
    if (limits.any()) out.push_back({device, channel, unit, limits});
  };
  for (const ModbusDeviceConfig& d : config.modbus_devices) {
    for (std::size_t i = 0; i < d.channels.size(); ++i) {
      add(d.name, d.channels[i].name, recorded_unit(d.channels[i].unit, d.emf_inputs, i), d.channels[i].alarms);
    }
  }
  for (const HidDeviceConfig& d : config.hid_devices) {
    const auto& channels = d.protocol.channels;
    for (std::size_t i = 0; i < channels.size(); ++i) {
      add(d.name, channels[i].name, recorded_unit(channels[i].unit, d.emf_inputs, i), channels[i].alarms);
    }
  }
  for (const UsbDeviceConfig& d : config.usb_devices) {
    for (const UsbTc32Channel& c : d.channels) add(d.name, c.name, "degC", c.alarms);
  }
  return out;
}

void check_hosts_resolve(const ExperimentConfig& config) {
  for (const ModbusDeviceConfig& d : config.modbus_devices) {
    try {
      check_endpoint_resolves(d.endpoint);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(d.host_key + ": device \"" + d.name + "\": " + e.what());
    }
  }
}

void check_replayed_runs(const ExperimentConfig& config) {
  for (const CameraConfig& c : config.cameras) {
    if (c.source != "replay") continue;
    try {
      load_recorded_frames(c.target, c.replay_camera, c.replay_speed);
    } catch (const std::exception& e) {
      throw ConfigError(c.run_key + ": camera \"" + c.name + "\": " + e.what());
    }
  }
}

void check_genicam_cameras(const ExperimentConfig& config, const std::function<void(const std::string&)>& warn) {
  for (const CameraConfig& c : config.cameras) {
    if (c.source != "genicam") continue;
    try {
      GenicamSource::check_settings(c.genicam);
    } catch (const GenicamSettingRefused& e) {
      throw ConfigError(c.genicam_key + ": camera \"" + c.name + "\": " + e.what());
    } catch (const DeviceError& e) {
      warn("camera \"" + c.name + "\": " + e.what() + "; logging starts and keeps trying to reach it");
    }
  }
}

void check_free_space(const ExperimentConfig& config, const std::filesystem::path& run_dir) {
  if (config.min_free_mb == 0) return;
  const std::uint64_t wanted = static_cast<std::uint64_t>(config.min_free_mb) << 20;
  std::uint64_t free = 0;
  try {
    free = storage::free_bytes(run_dir);
  } catch (const std::exception& e) {
    throw ConfigError(config.min_free_key + ": " + e.what());
  }
  if (free >= wanted) return;
  throw ConfigError(config.min_free_key + ": the disk of '" + run_dir.string() + "' has " + storage::bytes_text(free) +
                    " free, less than the " + std::to_string(config.min_free_mb) +
                    " MB asked for; free some space, log elsewhere, or lower min_free_mb (0 turns the check off)");
}

}  // namespace bosfuse::acquisition
