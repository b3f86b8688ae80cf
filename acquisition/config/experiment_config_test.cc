#include "acquisition/config/experiment_config.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

namespace bosfuse::acquisition {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_experiment(text, "exp.toml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

constexpr const char* kTwoDevices = R"(
[run]
name = "cool"

[[devices]]
name = "adam"
profile = "adam-6018"
host = "127.0.0.1"
port = 1502
poll_period_s = 0.25

  [[devices.channels]]
  name = "tc0"
  input = 0
  position_px = [10.5, 20.0]

  [[devices.channels]]
  name = "tc1"
  input = 1
  tc_type = "J"

[[devices]]
name = "m7018"
profile = "icpdas-m7018"
serial_port = "/dev/ttyUSB0"
baud = 19200
unit_id = 3

  [[devices.channels]]
  name = "cj"
  input = "cold-junction"
)";

TEST(ExperimentConfig, ReadsDevicesChannelsAndDefaults) {
  const ExperimentConfig config = parse_experiment(kTwoDevices, "exp.toml");
  EXPECT_EQ(config.run_name, "cool");
  ASSERT_EQ(config.modbus_devices.size(), 2u);
  const ModbusDeviceConfig& adam = config.modbus_devices[0];
  EXPECT_EQ(adam.endpoint.transport, ModbusTransport::kTcp);
  EXPECT_EQ(adam.endpoint.port, 1502);
  EXPECT_EQ(adam.poll_period, std::chrono::milliseconds(250));
  ASSERT_EQ(adam.channels.size(), 2u);
  EXPECT_EQ(adam.channels[0].tc_type, "K");
  EXPECT_EQ(adam.channels[0].image_x_px, 10.5);
  EXPECT_EQ(adam.channels[1].tc_type, "J");
  EXPECT_DOUBLE_EQ(adam.channels[1].linear->value_high, 760.0);
  const ModbusDeviceConfig& m7018 = config.modbus_devices[1];
  EXPECT_EQ(m7018.endpoint.transport, ModbusTransport::kRtu) << "the profile's usual transport";
  EXPECT_EQ(m7018.endpoint.baud, 19200);
  EXPECT_EQ(m7018.channels[0].kind, "cold-junction");
  EXPECT_EQ(config.source_text, kTwoDevices);
}

TEST(ExperimentConfig, ExamplesParse) {
  for (const char* name : {"cylinder-cooling.toml", "generic-modbus.toml", "usb-thermometers.toml"}) {
    const auto config = load_experiment(std::string(BOSFUSE_SOURCE_DIR) + "/examples/" + name);
    EXPECT_GT(config.device_count(), 0u) << name;
  }
}

TEST(ExperimentConfig, UsbTcChannelsSetTheirTypesAndReadBurnout) {
  const auto config = load_experiment(std::string(BOSFUSE_SOURCE_DIR) + "/examples/usb-thermometers.toml");
  ASSERT_EQ(config.hid_devices.size(), 2u);
  ASSERT_EQ(config.usb_devices.size(), 1u);
  EXPECT_TRUE(config.usb_devices[0].channels[1].cold_junction);
  const HidDeviceConfig& tc = config.hid_devices[0];
  EXPECT_EQ(tc.match.vendor_id, kMccVendorId);
  EXPECT_EQ(tc.protocol.setup_requests,
            (std::vector<std::vector<std::uint8_t>>{{0x49, 0, 0x10, 1}, {0x49, 0, 0x11, 1}}));  // inputs 0, 1: K
  EXPECT_EQ(tc.protocol.channels[2].request, (std::vector<std::uint8_t>{0x18, 0x80, 0}));
  EXPECT_TRUE(tc.protocol.burnout_request.has_value());
  const HidDeviceConfig& room = config.hid_devices[1];
  EXPECT_EQ(room.match.interface_number, kTemperInterface);
  EXPECT_DOUBLE_EQ(room.protocol.channels[0].scale, 1.0 / 256);
}

TEST(ExperimentConfig, UsbTc32ChannelsAndMistakes) {
  const std::string device = "[[devices]]\nname = \"tc32\"\nkind = \"usb\"\nprofile = \"usb-tc-32\"\n";
  const auto config =
      parse_experiment(device + "[[devices.channels]]\nname = \"a\"\ninput = 40\ntc_type = \"T\"\n" +
                           "[[devices.channels]]\nname = \"cj\"\ninput = 40\nkind = \"cold-junction\"\n",
                       "exp.toml");
  ASSERT_EQ(config.usb_devices.size(), 1u);
  EXPECT_EQ(config.usb_devices[0].channels[0].tc_type, 'T');
  EXPECT_TRUE(config.usb_devices[0].channels[1].cold_junction);
  EXPECT_EQ(error_of(device + "[[devices.channels]]\nname = \"a\"\ninput = 64\n"),
            "exp.toml:7: devices[0].channels[0].input: must be between 0 and 63");
  EXPECT_EQ(error_of(device + "[[devices.channels]]\nname = \"a\"\n"),
            "exp.toml:5: devices[0].channels[0]: missing required key 'input'");
}

TEST(ExperimentConfig, MillivoltChannelsNameTheirColdJunction) {
  const std::string device =
      "[[devices]]\nname = \"g\"\nprofile = \"generic\"\ntransport = \"tcp\"\nhost = \"localhost\"\n";
  const std::string cj = "[[devices.channels]]\nname = \"cj\"\nregister = \"input\"\naddress = 8\n";
  const std::string mv = "[[devices.channels]]\nname = \"tc\"\nregister = \"input\"\naddress = 0\nemf_type = \"K\"\n";
  const auto config = parse_experiment(device + cj + mv + "cold_junction = \"cj\"\n", "exp.toml");
  const auto& inputs = config.modbus_devices[0].emf_inputs;
  ASSERT_EQ(inputs.size(), 2u);
  EXPECT_FALSE(inputs[0].has_value());
  EXPECT_EQ(inputs[1]->cold_junction_channel, "cj");
  EXPECT_EQ(error_of(device + cj + mv + "cold_junction = \"cjj\"\n"),
            "exp.toml:15: devices[0].channels[1].cold_junction: no channel \"cjj\" on this device");
  EXPECT_EQ(error_of(device + cj + mv),
            "exp.toml:10: devices[0].channels[1]: a millivolt channel needs exactly one "
            "of cold_junction (a channel name) and cold_junction_c");
  EXPECT_EQ(error_of(device + cj + "cold_junction_c = 20\n"),
            "exp.toml:6: devices[0].channels[0].emf_type: cold junction given without emf_type");
}

TEST(ExperimentConfig, CamerasAndTheirMistakes) {
  const auto config = parse_experiment(
      "[[cameras]]\nname = \"cam\"\nsource = \"video\"\ndevice = \"0\"\ninterval_s = 2.5\n"
      "[[cameras]]\nname = \"dslr\"\nsource = \"folder\"\nfolder = \"/data/shots\"\ncamera_clock_offset_s = -3600\n"
      "reference_frames = 3\n",
      "exp.toml");
  ASSERT_EQ(config.cameras.size(), 2u);
  EXPECT_EQ(config.cameras[0].target, "0");
  EXPECT_EQ(config.cameras[0].recorder.interval, std::chrono::milliseconds(2500));
  EXPECT_EQ(config.cameras[1].folder.folder, "/data/shots");
  EXPECT_DOUBLE_EQ(config.cameras[1].folder.camera_clock_offset_s, -3600.0);
  EXPECT_EQ(config.cameras[1].recorder.reference_frames, 3);
  EXPECT_EQ(config.cameras[1].reference_flag, "reference.flag");
  EXPECT_EQ(error_of("[[cameras]]\nname = \"c\"\nsource = \"webcam\"\n").substr(0, 31),
            "exp.toml:3: cameras[0].source: ");
  EXPECT_EQ(error_of("[[cameras]]\nname = \"my cam\"\nsource = \"video\"\ndevice = \"0\"\n").substr(0, 29),
            "exp.toml:2: cameras[0].name: ");
  EXPECT_EQ(error_of("[[cameras]]\nname = \"c\"\nsource = \"folder\"\n"),
            "exp.toml:1: cameras[0]: missing required key 'folder'");
}

TEST(ExperimentConfig, GenicamCamerasTakeTheirSettingsAndFeatures) {
  const auto config = parse_experiment(
      "[[cameras]]\nname = \"mv\"\nsource = \"genicam\"\ndevice = \"Basler-21234567\"\npixel_format = \"Mono12p\"\n"
      "exposure_us = 800\ngain_db = 2.5\nframe_rate_hz = 20\nroi_px = [16, 8, 1024, 1024]\ntrigger = \"hardware\"\n"
      "line = \"Line2\"\nedge = \"falling\"\nfeatures = { BlackLevel = 4, ReverseX = true, GammaEnable = \"Off\", "
      "Gamma = 1.0 }\npacket_resend = false\n",
      "exp.toml");
  ASSERT_EQ(config.cameras.size(), 1u);
  const GenicamOptions& g = config.cameras[0].genicam;
  EXPECT_EQ(g.device, "Basler-21234567");
  EXPECT_EQ(g.pixel_format, "Mono12p");
  EXPECT_EQ(g.exposure_us, 800.0);
  EXPECT_EQ(g.gain_db, 2.5);
  EXPECT_EQ(g.frame_rate_hz, 20.0);
  ASSERT_TRUE(g.roi);
  EXPECT_EQ(g.roi->width_px, 1024);
  EXPECT_EQ(g.trigger, GenicamTrigger::kHardware);
  EXPECT_EQ(g.trigger_line, "Line2");
  EXPECT_EQ(g.trigger_edge, "FallingEdge");
  ASSERT_EQ(g.features.size(), 4u);
  EXPECT_FALSE(g.packet_resend);
  EXPECT_EQ(config.cameras[0].recorder.interval, std::chrono::nanoseconds(0));  // as the camera sends them
  const std::string camera = "[[cameras]]\nname = \"c\"\nsource = \"genicam\"\ndevice = \"127.0.0.1\"\n";
  EXPECT_EQ(error_of(camera), "no error");
  const std::pair<std::string, std::string> mistakes[] = {
      {"pixel_format = \"RGB8\"\n", "exp.toml:5: cameras[0].pixel_format: "},
      {"exposure_us = -3\n", "exp.toml:5: cameras[0].exposure_us: "},
      {"roi_px = [1, 2, 3]\n", "exp.toml:5: cameras[0].roi_px: "},
      {"trigger = \"software\"\n", "exp.toml:5: cameras[0].trigger: "},
      {"trigger = \"hardware\"\nedge = \"both\"\n", "exp.toml:6: cameras[0].edge: "},
      {"features = { Gain = [1] }\n", "exp.toml:5: cameras[0].features.Gain: "},
      {"exposure = 3\n", "exp.toml:5: cameras[0].exposure: unknown key"},
  };
  for (const auto& [line, error] : mistakes) {
    EXPECT_TRUE(error_of(camera + line).starts_with(error)) << line << " gave " << error_of(camera + line);
  }
}

TEST(ExperimentConfig, HidMistakesNameTheKeyAndLine) {
  const std::string usb_tc = "[[devices]]\nname = \"u\"\nkind = \"hid\"\nprofile = \"mcc-usb-tc\"\n";
  EXPECT_EQ(error_of(usb_tc + "[[devices.channels]]\nname = \"t\"\ninput = 8\n"),
            "exp.toml:7: devices[0].channels[0].input: must be between 0 and 7");
  EXPECT_EQ(error_of(usb_tc + "[[devices.channels]]\nname = \"t\"\ninput = 0\ntc_type = \"C\"\n"),
            "exp.toml:8: devices[0].channels[0].tc_type: the USB-TC takes types J, K, T, E, R, S, B or N");
  const std::string generic = "[[devices]]\nname = \"g\"\nkind = \"hid\"\nprofile = \"generic-hid\"\n";
  EXPECT_EQ(error_of(generic + "vendor_id = 1\nproduct_id = 2\n[[devices.channels]]\nname = \"t\"\n"
                               "request = [1, 300]\n"),
            "exp.toml:9: devices[0].channels[0].request: expected integers 0-255 (bytes)");
  EXPECT_EQ(error_of(generic + "[[devices.channels]]\nname = \"t\"\nrequest = [1]\n"),
            "exp.toml:1: devices[0]: missing required key 'vendor_id'");
}

TEST(ExperimentConfig, GenericChannelSpellsOutItsRegisters) {
  const auto config = load_experiment(std::string(BOSFUSE_SOURCE_DIR) + "/examples/generic-modbus.toml");
  const ModbusChannel& c = config.modbus_devices[0].channels[0];
  EXPECT_EQ(c.function, RegisterKind::kInput);
  EXPECT_EQ(c.type, DataType::kFloat32);
  EXPECT_EQ(c.order, WordOrder::kCDAB);
  EXPECT_EQ(c.open_circuit_codes, std::vector<double>{9999.0});
  EXPECT_EQ(c.valid_max, 600.0);
  const ModbusChannel& v = config.modbus_devices[0].channels[1];
  EXPECT_EQ(v.unit, "V");
  EXPECT_DOUBLE_EQ(v.to_value(4095), 10.0);
}

TEST(ExperimentConfig, SyntaxErrorNamesTheLine) {
  EXPECT_EQ(error_of("[run]\nname = \"x\"\nbroken = \n").substr(0, 11), "exp.toml:3:");
}

TEST(ExperimentConfig, BadValuesNameTheKeyAndLine) {
  const std::string device = "[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\n";
  const std::string channel = "[[devices.channels]]\nname = \"t\"\ninput = 0\n";
  EXPECT_EQ(error_of(device + "port = 70000\n" + channel), "exp.toml:5: devices[0].port: must be between 1 and 65535");
  EXPECT_EQ(error_of(device + "port = \"502\"\n" + channel), "exp.toml:5: devices[0].port: expected an integer");
  EXPECT_EQ(error_of(device + "pol_period_s = 1\n" + channel),
            "exp.toml:5: devices[0].pol_period_s: unknown key (a typo?)");
  EXPECT_EQ(error_of(device + "[[devices.channels]]\nname = \"t\"\ninput = 9\n"),
            "exp.toml:7: devices[0].channels[0].input: must be between 0 and 7");
  EXPECT_EQ(error_of(device + "[[devices.channels]]\nname = \"t\"\ninput = 0\nposition_px = [1]\n"),
            "exp.toml:8: devices[0].channels[0].position_px: expected [x, y] in image pixels");
  EXPECT_EQ(error_of(device), "exp.toml:1: devices[0]: a device needs at least one [[devices.channels]] entry");
  EXPECT_EQ(error_of("[[devices]]\nname = \"a\"\nprofile = \"adam-7000\"\n").substr(0, 32),
            "exp.toml:3: devices[0].profile: ");
}

// libmodbus's plain TCP back end takes IPv4 addresses only, so a host name
// was once accepted here and then retried for the whole run. The names
// used here resolve (or fail) on this machine without asking a DNS server:
// localhost from /etc/hosts, and a label over 63 characters, which the
// resolver refuses before sending anything.
TEST(ExperimentConfig, HostNamesResolveOrAreRefusedNamingTheKey) {
  const auto device = [](const std::string& host) {
    return parse_experiment("[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"" + host +
                                "\"\n[[devices.channels]]\nname = \"t\"\ninput = 0\n",
                            "exp.toml");
  };
  EXPECT_NO_THROW(check_hosts_resolve(device("localhost")));
  const ExperimentConfig unresolvable = device(
      "unresolvable-because-this-first-label-is-longer-than-sixty-three-chars.invalid");  // parsing resolves nothing
  try {
    check_hosts_resolve(unresolvable);
    ADD_FAILURE() << "an unresolvable name passed";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).substr(0, 143),
              "exp.toml:4: devices[0].host: device \"a\": cannot resolve host "
              "\"unresolvable-because-this-first-label-is-longer-than-sixty-three-chars.invalid\": ");
  }
}

// Found by fuzzing: periods beyond ~292 years became a negative poll
// period in int64 nanoseconds (nan and inf were already refused).
TEST(ExperimentConfig, APeriodThatIsNoNumberOfSecondsIsRefused) {
  const auto error_for = [](const std::string& period) {
    return error_of("[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\npoll_period_s = " +
                    period + "\n[[devices.channels]]\nname = \"t\"\ninput = 0\n");
  };
  for (const char* period : {"1e300", "3.2e7"}) {
    EXPECT_NE(error_for(period).find("exp.toml:5: devices[0].poll_period_s: must be a number of seconds from"),
              std::string::npos)
        << period << ": " << error_for(period);
  }
  for (const char* period : {"nan", "inf", "-inf"}) {
    EXPECT_NE(error_for(period).find("exp.toml:5: devices[0].poll_period_s: "), std::string::npos) << period;
  }
}

TEST(ExperimentConfig, GenericChannelsNeedTheirRegisters) {
  const std::string text =
      "[[devices]]\nname = \"g\"\nprofile = \"generic\"\ntransport = \"tcp\"\nhost = \"localhost\"\n"
      "[[devices.channels]]\nname = \"x\"\naddress = 4\n";
  EXPECT_EQ(error_of(text), "exp.toml:6: devices[0].channels[0]: missing required key 'register'");
}

TEST(ExperimentConfig, DuplicateNamesAreRefused) {
  const std::string device = "[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\n";
  const std::string channel = "[[devices.channels]]\nname = \"t\"\ninput = 0\n";
  EXPECT_NE(error_of(device + channel + channel).find("duplicate channel name"), std::string::npos);
  EXPECT_NE(error_of(device + channel + device + channel).find("duplicate device name"), std::string::npos);
}

TEST(ExperimentConfig, ChannelsOfEveryKindTakeAlarmLimits) {
  const std::string text =
      "[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\n"
      "[[devices.channels]]\nname = \"T1\"\ninput = 0\nalarm_low = -5\nalarm_high = 80.5\n"
      "alarm_rate_per_min = 10\nalarm_stale_s = 30\n"
      "[[devices.channels]]\nname = \"T2\"\ninput = 1\n"
      "[[devices]]\nname = \"g\"\nprofile = \"generic\"\ntransport = \"tcp\"\nhost = \"localhost\"\n"
      "[[devices.channels]]\nname = \"mv\"\nregister = \"input\"\naddress = 0\nunit = \"mV\"\n"
      "emf_type = \"K\"\ncold_junction_c = 20\nalarm_high = 300\n"
      "[[devices]]\nname = \"room\"\nkind = \"hid\"\nprofile = \"temper\"\n"
      "[[devices.channels]]\nname = \"air\"\nalarm_stale_s = 5\n"
      "[[devices]]\nname = \"tc32\"\nkind = \"usb\"\nprofile = \"usb-tc-32\"\n"
      "[[devices.channels]]\nname = \"a\"\ninput = 3\nalarm_low = 0\n";
  const ExperimentConfig config = parse_experiment(text, "exp.toml");
  const AlarmLimits& t1 = config.modbus_devices[0].channels[0].alarms;
  EXPECT_EQ(t1.low, -5.0);
  EXPECT_EQ(t1.high, 80.5);
  EXPECT_EQ(t1.rate_per_min, 10.0);
  EXPECT_EQ(t1.stale_s, 30.0);
  EXPECT_TRUE(t1.any());
  EXPECT_FALSE(config.modbus_devices[0].channels[1].alarms.any());
  EXPECT_EQ(config.hid_devices[0].protocol.channels[0].alarms.stale_s, 5.0);
  EXPECT_EQ(config.usb_devices[0].channels[0].alarms.low, 0.0);

  // What the live page lists: only channels with limits, in the unit they
  // are recorded in (a millivolt channel converted with emf_type is in °C).
  const auto listed = alarm_limits(config);
  ASSERT_EQ(listed.size(), 4u);
  EXPECT_EQ(listed[0].device, "adam");
  EXPECT_EQ(listed[0].channel, "T1");
  EXPECT_EQ(listed[0].unit, "degC");
  EXPECT_EQ(listed[0].limits.high, 80.5);
  EXPECT_EQ(listed[1].channel, "mv");
  EXPECT_EQ(listed[1].unit, "degC");
  EXPECT_EQ(listed[1].limits.high, 300.0);
  EXPECT_EQ(listed[2].device, "room");
  EXPECT_EQ(listed[2].limits.stale_s, 5.0);
  EXPECT_EQ(listed[3].device, "tc32");
  EXPECT_EQ(listed[3].limits.low, 0.0);
  // The stored text of a run reads back to the same list.
  EXPECT_EQ(alarm_limits(parse_experiment(config.source_text, "run")).size(), 4u);
}

TEST(ExperimentConfig, BadAlarmLimitsNameTheKeyAndLine) {
  const std::string channel =
      "[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\n"
      "[[devices.channels]]\nname = \"t\"\ninput = 0\n";  // its keys from line 8
  EXPECT_EQ(error_of(channel + "alarm_low = 80\nalarm_high = 20\n"),
            "exp.toml:9: devices[0].channels[0].alarm_high: must be above alarm_low (80)");
  EXPECT_EQ(error_of(channel + "alarm_low = 50\nalarm_high = 50\n"),
            "exp.toml:9: devices[0].channels[0].alarm_high: must be above alarm_low (50)");
  EXPECT_EQ(error_of(channel + "alarm_rate_per_min = 0\n"),
            "exp.toml:8: devices[0].channels[0].alarm_rate_per_min: expected a positive rate of change "
            "(the channel's unit per minute)");
  EXPECT_EQ(error_of(channel + "alarm_rate_per_min = -3\n").substr(0, 54),
            "exp.toml:8: devices[0].channels[0].alarm_rate_per_min:");
  EXPECT_EQ(error_of(channel + "alarm_stale_s = 0\n"),
            "exp.toml:8: devices[0].channels[0].alarm_stale_s: expected a number of seconds above 0, at most a year");
  EXPECT_EQ(error_of(channel + "alarm_stale_s = 1e300\n").substr(0, 49),
            "exp.toml:8: devices[0].channels[0].alarm_stale_s:");
  EXPECT_EQ(error_of(channel + "alarm_high = nan\n"),
            "exp.toml:8: devices[0].channels[0].alarm_high: expected a finite number");
  EXPECT_EQ(error_of(channel + "alarm_low = -inf\n"),
            "exp.toml:8: devices[0].channels[0].alarm_low: expected a finite number");
  EXPECT_EQ(error_of(channel + "alarm_high = \"80\"\n"),
            "exp.toml:8: devices[0].channels[0].alarm_high: expected a number");
  EXPECT_EQ(error_of(channel + "alarm_hihg = 80\n"),
            "exp.toml:8: devices[0].channels[0].alarm_hihg: unknown key (a typo?)");
  // The same checks for the other kinds of device.
  EXPECT_EQ(error_of("[[devices]]\nname = \"u\"\nkind = \"usb\"\nprofile = \"usb-tc-32\"\n"
                     "[[devices.channels]]\nname = \"a\"\ninput = 3\nalarm_stale_s = -1\n"),
            "exp.toml:8: devices[0].channels[0].alarm_stale_s: expected a number of seconds above 0, at most a year");
  EXPECT_EQ(error_of("[[devices]]\nname = \"r\"\nkind = \"hid\"\nprofile = \"temper\"\n"
                     "[[devices.channels]]\nname = \"air\"\nalarm_high = 1\nalarm_low = 2\n"),
            "exp.toml:7: devices[0].channels[0].alarm_high: must be above alarm_low (2)");
}

// Every integer key, read as TOML's 64-bit integer and range-checked
// before it is narrowed: 4294967296 (2^32) was once Modbus input 0.
struct IntegerKey {
  std::string document;  // with {} where the key goes
  std::string path;      // the table holding it
  std::string key;
  std::int64_t low, high;
};

std::string with_key(const IntegerKey& k, const std::string& value) {
  std::string text = k.document;
  return text.replace(text.find("{}"), 2, k.key + " = " + value);
}

int line_of_key(const IntegerKey& k) {
  return 1 + static_cast<int>(std::count(k.document.begin(), k.document.begin() + k.document.find("{}"), '\n'));
}

TEST(ExperimentConfig, EveryIntegerKeyIsRangeCheckedBeforeNarrowing) {
  const std::string adam = "[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\n";
  const std::string m7018 = "[[devices]]\nname = \"m\"\nprofile = \"icpdas-m7018\"\nserial_port = \"/dev/ttyUSB0\"\n";
  const std::string channel = "[[devices.channels]]\nname = \"t\"\ninput = 0\n";
  const std::string generic = "[[devices]]\nname = \"g\"\nprofile = \"generic\"\ntransport = \"tcp\"\nhost = \"h\"\n";
  const std::string mcc = "[[devices]]\nname = \"u\"\nkind = \"hid\"\nprofile = \"mcc-usb-tc\"\n";
  const std::string hid = "[[devices]]\nname = \"g\"\nkind = \"hid\"\nprofile = \"generic-hid\"\n";
  const std::string hid_channel = "[[devices.channels]]\nname = \"t\"\nrequest = [1]\n";
  const std::string tc32 = "[[devices]]\nname = \"u\"\nkind = \"usb\"\nprofile = \"usb-tc-32\"\n";
  const std::int64_t most = std::numeric_limits<std::int64_t>::max();
  const std::vector<IntegerKey> keys = {
      {adam + "{}\n" + channel, "devices[0]", "unit_id", 0, 247},
      {adam + "{}\n" + channel, "devices[0]", "port", 1, 65535},
      {adam + "{}\n" + channel, "devices[0]", "poll_count", 1, most},
      {m7018 + "{}\n" + channel, "devices[0]", "baud", 300, 4'000'000},
      {m7018 + "{}\n" + channel, "devices[0]", "data_bits", 5, 8},
      {m7018 + "{}\n" + channel, "devices[0]", "stop_bits", 1, 2},
      {adam + "[[devices.channels]]\nname = \"t\"\n{}\n", "devices[0].channels[0]", "input", 0, 7},
      {m7018 + "[[devices.channels]]\nname = \"t\"\n{}\n", "devices[0].channels[0]", "input", 0, 7},
      {generic + "[[devices.channels]]\nname = \"x\"\nregister = \"input\"\n{}\n", "devices[0].channels[0]", "address",
       0, 65535},
      {mcc + "[[devices.channels]]\nname = \"t\"\n{}\n", "devices[0].channels[0]", "input", 0, 7},
      {hid + "product_id = 2\n{}\n" + hid_channel, "devices[0]", "vendor_id", 0, 65535},
      {hid + "vendor_id = 1\n{}\n" + hid_channel, "devices[0]", "product_id", 0, 65535},
      {hid + "vendor_id = 1\nproduct_id = 2\n{}\n" + hid_channel, "devices[0]", "interface", 0, 255},
      {hid + "vendor_id = 1\nproduct_id = 2\n" + hid_channel + "{}\n", "devices[0].channels[0]", "reply_report_id", 0,
       255},
      {hid + "vendor_id = 1\nproduct_id = 2\n" + hid_channel + "{}\n", "devices[0].channels[0]", "value_offset", 0, 63},
      {tc32 + "[[devices.channels]]\nname = \"t\"\n{}\n", "devices[0].channels[0]", "input", 0, 63},
      {"[[cameras]]\nname = \"c\"\nsource = \"video\"\ndevice = \"0\"\n{}\n", "cameras[0]", "reference_frames", 0,
       1'000'000},
  };
  for (const IntegerKey& k : keys) {
    SCOPED_TRACE(k.path + "." + k.key);
    EXPECT_EQ(error_of(with_key(k, std::to_string(k.low))), "no error");
    if (k.high != most) {
      EXPECT_EQ(error_of(with_key(k, std::to_string(k.high))), "no error");
    }
    const std::string refusal = "exp.toml:" + std::to_string(line_of_key(k)) + ": " + k.path + "." + k.key +
                                ": must be between " + std::to_string(k.low) + " and " + std::to_string(k.high);
    std::vector<std::string> outside = {std::to_string(k.low - 1), "-1", "-4294967296"};
    if (k.high != most) outside.insert(outside.end(), {std::to_string(k.high + 1), "4294967296", "4294967297"});
    for (const std::string& value : outside) {
      if (value == "-1" && k.low < 0) continue;
      EXPECT_EQ(error_of(with_key(k, value)), refusal) << value;
    }
  }
}

// Channel names are unique across devices: an export names its columns by
// channel, and once wrote two "T0 [degC]" columns.
TEST(ExperimentConfig, AChannelNameOnTwoDevicesIsRefusedNamingBothPlaces) {
  const auto device = [](const std::string& name, const std::string& channel) {
    return "[[devices]]\nname = \"" + name + "\"\nprofile = \"adam-6018\"\nhost = \"localhost\"\n" +
           "[[devices.channels]]\nname = \"" + channel + "\"\ninput = 0\n";
  };
  EXPECT_EQ(error_of(device("a", "T0") + device("b", "T0")),
            "exp.toml:13: devices[1].channels[0].name: duplicate channel name \"T0\", already at exp.toml:6: "
            "devices[0].channels[0].name; channel names must be unique across all devices");
  for (const char* other : {"t0", " T0", "T0 "}) {
    EXPECT_NE(error_of(device("a", "T0") + device("b", other))
                  .find("(the same as \"T0\" but for case or spaces), already at exp.toml:6: devices[0].channels[0]"),
              std::string::npos)
        << other;
  }
  const std::string usb =
      "[[devices]]\nname = \"u\"\nkind = \"usb\"\nprofile = \"usb-tc-32\"\n"
      "[[devices.channels]]\nname = \"T0\"\ninput = 3\n";
  EXPECT_NE(error_of(device("a", "T0") + usb).find("exp.toml:13: devices[1].channels[0].name: duplicate"),
            std::string::npos);
  EXPECT_EQ(error_of(device("a", "T0") + device("b", "T1")), "no error");
  EXPECT_EQ(error_of(device("a", "T0") + device("b", "T 0")), "no error") << "a space inside a name counts";
}

// Floats with a physical meaning have a stated range: a time scale of
// 1e308 or 1e-300 was once taken.
TEST(ExperimentConfig, TimeScaleAndOtherPhysicalNumbersHaveAStatedRange) {
  const auto scale = [](const std::string& value) { return error_of("[run]\ntime_scale = " + value + "\n"); };
  for (const char* value : {"1e308", "1e-300", "0", "-1", "1000001", "0.000999"}) {
    EXPECT_NE(scale(value).find("exp.toml:2: run.time_scale: expected experiment seconds per recorded second from "
                                "0.001 to 1e+06, not "),
              std::string::npos)
        << value << ": " << scale(value);
  }
  for (const char* value : {"nan", "inf"}) {
    EXPECT_EQ(scale(value).substr(0, 27), "exp.toml:2: run.time_scale:") << value;
  }
  for (const char* value : {"0.001", "1", "1e6"}) EXPECT_EQ(scale(value), "no error") << value;
  EXPECT_DOUBLE_EQ(parse_experiment("[run]\ntime_scale = 1e6\n", "exp.toml").time_scale, 1e6);

  const std::string folder = "[[cameras]]\nname = \"c\"\nsource = \"folder\"\nfolder = \"/x\"\n";
  EXPECT_NE(error_of(folder + "camera_clock_offset_s = 1e300\n").find("exp.toml:5: cameras[0].camera_clock_offset_s:"),
            std::string::npos);
  EXPECT_EQ(error_of(folder + "camera_clock_offset_s = -8e8\n"), "no error") << "a clock 25 years off";
  const std::string replay = "[[cameras]]\nname = \"c\"\nsource = \"replay\"\nrun = \"/r\"\ncamera = \"c\"\n";
  EXPECT_NE(error_of(replay + "speed = 1e-300\n").find("exp.toml:6: cameras[0].speed: expected a speed-up from"),
            std::string::npos);
  const std::string mv =
      "[[devices]]\nname = \"g\"\nprofile = \"generic\"\ntransport = \"tcp\"\nhost = \"h\"\n"
      "[[devices.channels]]\nname = \"x\"\nregister = \"input\"\naddress = 0\nunit = \"mV\"\n"
      "emf_type = \"K\"\n";
  EXPECT_NE(error_of(mv + "cold_junction_c = 1e308\n").find("exp.toml:12: devices[0].channels[0].cold_junction_c:"),
            std::string::npos);
  EXPECT_NE(error_of(mv + "cold_junction_c = -300\n").find("cold_junction_c: expected a temperature"),
            std::string::npos);
  EXPECT_EQ(error_of(mv + "cold_junction_c = 0\n"), "no error");
}

// A camera name names its frame folder, so it is checked as one when the
// file is read: a 300-character name once passed and then failed with the
// system's "File name too long" after the run was created.
TEST(ExperimentConfig, ACameraNameTooLongForAFolderIsRefusedNamingTheKey) {
  const auto camera = [](const std::string& name) {
    return error_of("[[cameras]]\nname = \"" + name + "\"\nsource = \"video\"\ndevice = \"0\"\n");
  };
  EXPECT_EQ(camera(std::string(64, 'c')), "no error");
  EXPECT_EQ(camera(std::string(300, 'c')),
            "exp.toml:2: cameras[0].name: a camera name names its frame folder (frames/<name>/): it is 300 bytes "
            "long, more than the 64 a folder name may have");
  EXPECT_NE(camera(std::string(65, 'c')).find("exp.toml:2: cameras[0].name: "), std::string::npos);
}

// [run] min_free_mb: read, checked, and named with its line when the disk
// has less room (an impossible amount here, so any disk has less).
TEST(ExperimentConfig, TheLeastFreeSpaceIsReadAndARunDiskWithLessIsRefusedNamingTheKey) {
  const std::string device =
      "[[devices]]\nname = \"a\"\nprofile = \"adam-6018\"\nhost = \"127.0.0.1\"\n"
      "[[devices.channels]]\nname = \"t\"\ninput = 0\n";
  const auto config = [&](const std::string& run) { return parse_experiment(run + device, "exp.toml"); };
  EXPECT_EQ(config("").min_free_mb, 100);
  EXPECT_EQ(config("").min_free_key, "exp.toml: run.min_free_mb (default 100)");
  EXPECT_EQ(config("[run]\nname = \"x\"\n").min_free_key, "exp.toml:1: run.min_free_mb (default 100)");
  EXPECT_EQ(config("[run]\nmin_free_mb = 0\n").min_free_mb, 0);
  EXPECT_EQ(error_of("[run]\nname = \"x\"\nmin_free_mb = -1\n" + device),
            "exp.toml:3: run.min_free_mb: must be between 0 and 1099511627776");
  EXPECT_EQ(error_of("[run]\nmin_free_mb = 1.5\n" + device), "exp.toml:2: run.min_free_mb: expected an integer");

  const std::string run_dir = ::testing::TempDir() + "/not-made-yet";
  EXPECT_NO_THROW(check_free_space(config("[run]\nmin_free_mb = 0\n"), run_dir)) << "0 turns the check off";
  EXPECT_NO_THROW(check_free_space(config("[run]\nmin_free_mb = 1\n"), run_dir));
  try {
    check_free_space(config("[run]\nname = \"x\"\nmin_free_mb = 1099511627776\n"), run_dir);
    ADD_FAILURE() << "no disk has 2^40 MB free";
  } catch (const ConfigError& e) {
    const std::string said = e.what();
    EXPECT_EQ(said.rfind("exp.toml:3: run.min_free_mb: the disk of '" + run_dir + "' has ", 0), 0u) << said;
    EXPECT_NE(said.find("less than the 1099511627776 MB asked for"), std::string::npos) << said;
  }
}

TEST(ExperimentConfig, MissingFileIsReported) { EXPECT_THROW(load_experiment("/nonexistent/exp.toml"), ConfigError); }

}  // namespace
}  // namespace bosfuse::acquisition

namespace bosfuse::acquisition {
namespace {

std::string with_tc0_line(const std::string& line) {
  std::string text = kTwoDevices;
  const std::string anchor = "  name = \"tc0\"\n";
  return text.insert(text.find(anchor) + anchor.size(), "  " + line + "\n");
}

TEST(ExperimentConfig, AChannelStatesItsResponseTimeConstant) {
  const ExperimentConfig config = parse_experiment(with_tc0_line("time_constant_s = 0.5"), "exp.toml");
  EXPECT_EQ(config.modbus_devices[0].channels[0].time_constant_s, 0.5);
  EXPECT_FALSE(config.modbus_devices[0].channels[1].time_constant_s);
  const auto constants = channel_time_constants(config);
  ASSERT_EQ(constants.size(), 1u);
  EXPECT_DOUBLE_EQ(constants.at(channel_name_key("tc0")), 0.5);
}

TEST(ExperimentConfig, ABadTimeConstantNamesItsKeyAndLine) {
  // tc0's name is on line 13 of kTwoDevices, the inserted key on line 14.
  const std::string negative = error_of(with_tc0_line("time_constant_s = -1"));
  EXPECT_NE(negative.find("exp.toml:14"), std::string::npos) << negative;
  EXPECT_NE(negative.find("time_constant_s"), std::string::npos) << negative;
  EXPECT_NE(error_of(with_tc0_line("time_constant_s = \"fast\"")).find("time_constant_s"), std::string::npos);
  EXPECT_NE(error_of(with_tc0_line("time_constant_s = 7200")).find("time_constant_s"), std::string::npos);
}

TEST(ExperimentConfig, AgreementMarginsAreReadWithDefaults) {
  const ExperimentConfig defaults = parse_experiment(kTwoDevices, "exp.toml");
  EXPECT_DOUBLE_EQ(defaults.agreement.margin_c, 1.0);
  EXPECT_DOUBLE_EQ(defaults.agreement.margin_k_relative, 0.05);
  const ExperimentConfig set = parse_experiment(
      std::string(kTwoDevices) + "\n[agreement]\nmargin_c = 0.3\nmargin_k_relative = 0.1\n", "exp.toml");
  EXPECT_DOUBLE_EQ(set.agreement.margin_c, 0.3);
  EXPECT_DOUBLE_EQ(set.agreement.margin_k_relative, 0.1);
}

TEST(ExperimentConfig, ABadAgreementMarginNamesItsKeyAndLine) {
  const std::string text = std::string(kTwoDevices) + "\n[agreement]\nmargin_c = 0\n";
  const int line = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  const std::string zero = error_of(text);
  EXPECT_NE(zero.find("exp.toml:" + std::to_string(line) + ": agreement.margin_c"), std::string::npos) << zero;
  const std::string unknown = error_of(std::string(kTwoDevices) + "\n[agreement]\nmargin_k = 0.1\n");
  EXPECT_NE(unknown.find("margin_k"), std::string::npos) << unknown;
}

}  // namespace
}  // namespace bosfuse::acquisition
