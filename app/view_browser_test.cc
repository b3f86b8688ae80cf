// The live page in a real browser while a run is being recorded, seen by
// headless Chromium (Debian's chromium, driven over the DevTools protocol
// by tests/support/cdp_wait.py):
// - `bosfuse acquire` logs a simulated Modbus module and `bosfuse view`
//   serves the run: the thermocouple values appear and grow, each device's
//   polls are counted with the age of its last value, an alarm limit of the
//   experiment file is shown with its active alarm, and the device goes
//   "disconnected" (failed polls counted, a staleness alarm raised) when its
//   module is stopped;
// - `bosfuse demo --live` records the simulated experiment (Modbus module
//   and virtual camera) with the viewer inside the logger: the live BOS
//   temperature at each thermocouple appears and changes beside the
//   thermocouple's curve, with the latest frame and its quality index.
// And the DevTools handshake of cdp_wait.py as Chromium's Origin check sees
// it, so the tests run with every chromium Debian 12 ships (150 refuses an
// Origin it was not told to allow; 156, installed here, does not check).

#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <regex>
#include <thread>

#include "acquisition/clock.h"
#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "tests/support/browser.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace std::chrono_literals;

using testing::kBosfuse;
const std::string kCdpWait = std::string(BOSFUSE_SOURCE_DIR) + "/tests/support/cdp_wait.py";
const std::string kCdpScreenshot = std::string(BOSFUSE_SOURCE_DIR) + "/tests/support/cdp_screenshot.py";

// `text` as one /bin/sh word, whatever quotes it holds.
std::string sh_word(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Waits in the page until `expression` is truthy; its value as JSON, or a failure.
nlohmann::json wait_in_page(int devtools_port, const std::string& url, const std::string& expression, int seconds) {
  const auto result = testing::run_command("/usr/bin/python3 " + kCdpWait + " " + std::to_string(devtools_port) + " " +
                                               sh_word(url) + " " + std::to_string(seconds) + " " +
                                               sh_word(expression),
                                           seconds + 30);
  if (result.exit_code != 0) {
    ADD_FAILURE() << "the page never showed " << expression << ": " << result.output;
    return nullptr;
  }
  return nlohmann::json::parse(result.output);
}

// Opens `url` in a new tab and, at its load event (when `chromium --headless
// --screenshot` takes its picture), evaluates `expression` and captures the
// tab into `png`; the expression's value, or a failure.
nlohmann::json screenshot_at_load(int devtools_port, const std::string& url, const std::filesystem::path& png,
                                  const std::string& expression) {
  const auto result = testing::run_command("/usr/bin/python3 " + kCdpScreenshot + " " +
                                               std::to_string(devtools_port) + " " + sh_word(url) + " " +
                                               sh_word(png.string()) + " 30 " + sh_word(expression),
                                           60);
  if (result.exit_code != 0) {
    ADD_FAILURE() << "no screenshot of " << url << ": " << result.output;
    return nullptr;
  }
  return nlohmann::json::parse(result.output);
}

bool answers(const std::string& url) { return testing::run_command("curl -sf -o /dev/null " + url, 5).exit_code == 0; }

// Headless Chromium with its DevTools protocol on a free loopback port. The
// one Origin it allows is what websocket-client would send by default, in
// case a cdp_wait.py that sends none were changed.
struct Browser {
  explicit Browser(const std::filesystem::path& dir)
      : devtools_port(testing::unused_loopback_port()),
        process({"chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--no-first-run", "--user-data-dir=" + (dir / "chromium-profile").string(),
                 "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=" + std::to_string(devtools_port),
                 "--remote-allow-origins=http://127.0.0.1:" + std::to_string(devtools_port), "about:blank"}) {}
  bool ready() const {
    return testing::wait_for(
        [&] { return answers("http://127.0.0.1:" + std::to_string(devtools_port) + "/json/version"); }, 30s);
  }
  int devtools_port;
  testing::BackgroundProcess process;
};

// The number of points per thermocouple series once each has at least `at_least`.
std::string points_per_series(int at_least) {
  return "(() => { if (typeof series === 'undefined') return null;"
         " const n = [...series.values()].map(d => d.data.filter(p => p.y !== null).length);"
         " return n.length === 2 && n.every(x => x >= " +
         std::to_string(at_least) + ") ? n : null; })()";
}

// A stand-in for Chromium's DevTools endpoint on a loopback port: it hands
// out one target, records that target's WebSocket handshake and judges it
// as chromium 150 does (devtools_http_handler.cc: a request with an Origin
// header that --remote-allow-origins does not list is 403, "Rejected an
// incoming WebSocket connection from the … origin"). It speaks no
// WebSocket, so cdp_wait.py then stops with its error: the headers are what
// is looked at.
// The logger's store exists before its run row does: `view` started in
// between finds no run (seen under ASan), so the tests wait for the row.
bool holds_readable_run(const std::filesystem::path& run_dir) {
  try {
    return storage::RunStore::holds_run(run_dir);
  } catch (const std::exception&) {
    return false;  // the store is being created
  }
}

TEST(ViewBrowser, TheDevToolsHandshakeSendsNoOriginSoChromium150AcceptsIt) {
  httplib::Server devtools;
  const int port = devtools.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  const std::string target_path = "/devtools/page/T1";
  devtools.Put("/json/new", [&](const httplib::Request&, httplib::Response& response) {
    const nlohmann::json target{{"id", "T1"},
                                {"webSocketDebuggerUrl", "ws://127.0.0.1:" + std::to_string(port) + target_path}};
    response.set_content(target.dump(), "application/json");
  });
  devtools.Get("/json/close/T1", [](const httplib::Request&, httplib::Response& response) {
    response.set_content("Target is closing", "text/plain");
  });
  std::mutex mutex;
  std::optional<httplib::Headers> handshake;
  devtools.Get(target_path, [&](const httplib::Request& request, httplib::Response& response) {
    {
      const std::lock_guard lock(mutex);
      handshake = request.headers;
    }
    if (request.has_header("Origin")) {  // none is allowed: chromium's default
      response.status = 403;
      response.set_content("Rejected an incoming WebSocket connection from the " +
                               request.get_header_value("Origin") + " origin.",
                           "text/plain");
      return;
    }
    response.status = 400;  // past the check; this stand-in cannot go on
  });
  std::thread serving([&] { devtools.listen_after_bind(); });
  const auto result = testing::run_command(
      "/usr/bin/python3 " + kCdpWait + " " + std::to_string(port) + " http://127.0.0.1:1/ 1 true", 30);
  devtools.stop();
  serving.join();

  EXPECT_EQ(result.exit_code, 2) << "the stand-in ends every handshake: " << result.output;
  const std::lock_guard lock(mutex);
  ASSERT_TRUE(handshake) << "cdp_wait.py never opened the target's WebSocket: " << result.output;
  EXPECT_EQ(handshake->count("Upgrade"), 1u);
  EXPECT_EQ(handshake->find("Upgrade")->second, "websocket");
  const auto origin = handshake->find("Origin");
  EXPECT_TRUE(origin == handshake->end()) << "chromium 150 refuses the Origin " << origin->second;
  EXPECT_EQ(result.output.find("Rejected"), std::string::npos) << result.output;
}

// `view --token` (as off loopback): the page opened at the printed URL gets
// the token as a cookie, with which its own requests — /chart.js, the
// snapshot, the event stream — are let in, and it shows the run (whose
// writer went away without closing it: interrupted, so finished).
TEST(ViewBrowser, APageOpenedAtItsTokenedUrlShowsTheRunThroughItsCookie) {
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  testing::TempDir dir;
  {
    auto store = storage::RunStore::create(dir / "run",
                                           {.id = 0,
                                            .name = "tokened",
                                            .started_ns = 1'000'000'000,
                                            .ended_ns = std::nullopt,
                                            .config_toml = "",
                                            .status = storage::RunStatus::kRunning,
                                            .time_scale = 1,
                                            .origin_event = std::nullopt},
                                           storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({.id = 0, .name = "adam", .kind = "modbus-tcp", .profile = "", .address = ""});
    const auto channel = store.add_channel({.id = 0,
                                            .device_id = device,
                                            .name = "tc0",
                                            .kind = "thermocouple",
                                            .unit = "degC",
                                            .tc_type = std::nullopt,
                                            .image_x_px = std::nullopt,
                                            .image_y_px = std::nullopt});
    std::vector<storage::Sample> samples;
    for (int k = 0; k < 20; ++k)
      samples.push_back({channel, 2'000'000'000LL + k * 100'000'000LL, {}, 20.0 + k, {}, {}});
    store.write_samples(samples);
  }
  const int view_port = testing::unused_loopback_port();
  const std::string out = (dir / "out.txt").string();
  testing::BackgroundProcess view({"/bin/sh", "-c",
                                   "exec " + kBosfuse + " view " + (dir / "run").string() +
                                       " --token --listen 127.0.0.1:" + std::to_string(view_port) + " > " + out});
  std::string url;
  ASSERT_TRUE(testing::wait_for(
      [&] {
        std::ifstream in(out);
        return std::getline(in, url) && url.find("/?token=") != std::string::npos;
      },
      10s));
  ASSERT_FALSE(answers("http://127.0.0.1:" + std::to_string(view_port) + "/api/run")) << "no token, no run";
  const Browser browser(dir.path());
  ASSERT_TRUE(browser.ready());
  const auto shown = wait_in_page(
      browser.devtools_port, url,
      "(() => { if (typeof series === 'undefined') return null;"
      " const n = [...series.values()].map(d => d.data.length);"
      " return linkState === 'live' && document.getElementById('link').textContent === 'finished: the run is interrupted' &&"
      " document.getElementById('bos-state').textContent.startsWith('the run has no frames;') &&"
      " document.getElementById('name').textContent === 'tokened' && n.length === 1 && n[0] === 20 ? n : null; })()",
      30);
  ASSERT_TRUE(shown.is_array()) << shown;
}

TEST(ViewBrowser, ValuesAppearAndGrowWhileRecordingAndAStoppedModuleShowsDisconnected) {
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  testing::TempDir dir;
  acquisition::ModbusEndpoint endpoint;
  endpoint.port = 0;
  sim::ModbusSimServer module(sim::module_server_options({}, endpoint));
  module.start();
  std::ofstream(dir / "exp.toml") << "[run]\nname = \"live\"\n\n[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\n"
                                     "host = \"127.0.0.1\"\nport = "
                                  << module.port()
                                  << "\npoll_period_s = 0.1\ntimeout_s = 0.2\n\n[[devices.channels]]\nname = \"tc0\"\n"
                                     "input = 0\nalarm_high = 50  # the module starts at 80 °C\n\n[[devices.channels]]\n"
                                     "name = \"tc1\"\ninput = 1\nalarm_stale_s = 2\n";
  const std::string run = (dir / "run").string();
  testing::BackgroundProcess acquire({kBosfuse, "acquire", (dir / "exp.toml").string(), "--out", run, "-q"});
  ASSERT_TRUE(testing::wait_for([&] { return holds_readable_run(dir / "run"); }, 10s));

  const int view_port = testing::unused_loopback_port();
  const std::string url = "http://127.0.0.1:" + std::to_string(view_port) + "/";
  testing::BackgroundProcess view({kBosfuse, "view", run, "--listen", "127.0.0.1:" + std::to_string(view_port)});
  ASSERT_TRUE(testing::wait_for([&] { return answers(url + "api/run"); }, 10s));

  const Browser browser(dir.path());
  ASSERT_TRUE(browser.ready());
  const int devtools_port = browser.devtools_port;

  // Values appear on the page while the run goes on ...
  const auto first = wait_in_page(devtools_port, url, points_per_series(3), 30);
  ASSERT_TRUE(first.is_array()) << first;
  EXPECT_EQ(wait_in_page(devtools_port, url,
                         "(() => { const t = document.getElementById('link').textContent; "
                         "return t === 'live' ? t : null; })()",
                         10),
            "live");
  // Each thermocouple's current value in large type, as a number with its
  // unit and its age, near what the module serves, at the channel's digits:
  // a type-K adam-6018 input steps by 1370/65535 °C, two decimals.
  const auto readings = wait_in_page(
      devtools_port, url,
      "(() => { const r = [...document.querySelectorAll('#readings .reading')].map(e =>"
      " [e.dataset.channel, e.querySelector('.value').textContent, e.querySelector('.age').textContent]);"
      " return r.length === 2 && r.every(([, v, a]) => /^-?\\d+\\.\\d\\d °C$/.test(v) && /^\\d+ s ago$/.test(a)) ? r : null;"
      " })()",
      20);
  ASSERT_TRUE(readings.is_array()) << readings;
  const std::int64_t read_ns = acquisition::utc_now_ns();
  const auto served = module.served();
  for (const auto& reading : readings) {
    const std::string name = reading[0].get<std::string>();
    const double shown_c = std::stod(reading[1].get<std::string>());
    const int input = name == "tc0" ? 0 : 1;
    double low = 1e9, high = -1e9;
    for (const auto& value : served) {
      if (value.channel != input || !value.reading.value || value.t_ns < read_ns - 5'000'000'000LL) continue;
      low = std::min(low, *value.reading.value);
      high = std::max(high, *value.reading.value);
    }
    ASSERT_LE(low, high) << "the module served " << name << " nothing in the last 5 s";
    EXPECT_GE(shown_c, low - 0.005) << name << " " << reading;  // shown to 0.01 °C
    EXPECT_LE(shown_c, high + 0.005) << name << " " << reading;
    EXPECT_LE(std::stoi(reading[2].get<std::string>()), 3) << "a value of a run being recorded is fresh: " << reading;
  }
  // A marker made while recording is drawn on the chart with its label.
  const auto mark = testing::run_command(kBosfuse + " mark " + run + " 'heater off' 2>&1", 30);
  ASSERT_EQ(mark.exit_code, 0) << mark.output;
  const auto marker = wait_in_page(devtools_port, url,
                                   "(() => { const m = drawnMarkers.filter(m => m.label === 'heater off');"
                                   " const a = chart.chartArea;"
                                   " return m.length === 1 && m[0].x_px > a.left && m[0].x_px <= a.right ? m : null; })()",
                                   20);
  ASSERT_TRUE(marker.is_array()) << marker;
  // Each device counts its polls and says how old its last value is.
  const auto counted = wait_in_page(devtools_port, url,
                                    "(() => { const t = document.getElementById('devices').textContent;"
                                    " const m = t.match(/polls ok (\\d+), failed \\d+, skipped \\d+; last value \\d+ s ago/);"
                                    " return m && Number(m[1]) >= 6 ? t : null; })()",
                                    20);
  ASSERT_TRUE(counted.is_string()) << counted;
  // The alarm the experiment file asked for is active, with its limit shown.
  const auto alarm = wait_in_page(devtools_port, url,
                                  "(() => { const a = document.getElementById('alarms').textContent,"
                                  " l = document.getElementById('limits').textContent;"
                                  " return a.includes('tc0: high') && l.includes('tc0: high 50 °C') ? [a, l] : null; })()",
                                  20);
  ASSERT_TRUE(alarm.is_array()) << alarm;
  // ... and keep coming (a second tab: what it shows grows past the first one's count).
  const int seen = first[0].get<int>();
  const auto later = wait_in_page(devtools_port, url, points_per_series(seen + 10), 30);
  ASSERT_TRUE(later.is_array()) << later;

  // The module stops: the device is shown disconnected.
  module.stop();
  const auto devices = wait_in_page(
      devtools_port, url,
      "(() => { const t = document.getElementById('devices').textContent; "
      "return t.includes('disconnected') && /failed [1-9]/.test(t) ? t : null; })()",
      30);
  ASSERT_TRUE(devices.is_string()) << devices;
  EXPECT_NE(devices.get<std::string>().find("adam"), std::string::npos) << devices;
  // ... and the channel with a staleness limit raises its alarm.
  const auto stale = wait_in_page(
      devtools_port, url,
      "(() => { const a = document.getElementById('alarms').textContent; return a.includes('tc1: stale') ? a : null; })()",
      30);
  ASSERT_TRUE(stale.is_string()) << stale;
}

TEST(ViewBrowser, TheLiveBosTemperatureAppearsAndChangesBesideTheThermocouplesWhileTheDemoRecords) {
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  testing::TempDir dir;
  const int view_port = testing::unused_loopback_port();
  const std::string url = "http://127.0.0.1:" + std::to_string(view_port) + "/";
  // 4 min of cooling at 8x: 30 s of recording, a frame every 1.25 s.
  testing::BackgroundProcess demo({kBosfuse, "demo", "--out", (dir / "demo").string(), "--experiment-time", "4m",
                                   "--speed", "8", "--live", "127.0.0.1:" + std::to_string(view_port)});
  ASSERT_TRUE(testing::wait_for([&] { return answers(url + "api/run"); }, 20s));
  const Browser browser(dir.path());
  ASSERT_TRUE(browser.ready());

  // The BOS temperature at both thermocouples appears, each value within a
  // few degrees of the thermocouple's latest reading (the plume is at
  // 40-50 °C, the room at 22 °C) ...
  const auto first = wait_in_page(
      browser.devtools_port, url,
      "(() => { if (typeof bosSeries === 'undefined' || bosSeries.size !== 2) return null;"
      " const pairs = [...bosSeries.entries()].map(([c, d]) => {"
      "   const v = d.data.filter(p => p.y !== null); return [v.length, v.length ? v[v.length - 1].y : null, lastValue(c)]; });"
      " return pairs.every(([n, bos, tc]) => n >= 2 && tc !== null) ? pairs : null; })()",
      40);
  ASSERT_TRUE(first.is_array()) << first;
  for (const auto& pair : first) {
    const double bos_c = pair[1].get<double>(), tc_c = pair[2].get<double>();
    EXPECT_GT(bos_c, 30.0) << first;
    EXPECT_NEAR(bos_c, tc_c, 3.0) << first;  // measured: within 1 °C
  }
  // ... and changes while the run goes on, as the plume cools.
  const auto changing = wait_in_page(
      browser.devtools_port, url,
      "(() => { const v = [...bosSeries.values()].map(d => d.data.filter(p => p.y !== null).map(p => p.y));"
      " return v.every(a => a.length >= 5 && Math.max(...a) - Math.min(...a) > 0.5) ? v : null; })()",
      40);
  ASSERT_TRUE(changing.is_array()) << changing;
  // The latest frame is drawn with the probes, and its quality index shown.
  const auto frame = wait_in_page(
      browser.devtools_port, url,
      "(() => { const c = document.getElementById('frame-view'), q = document.getElementById('q-mod').textContent;"
      " const rows = document.getElementById('bos-rows').textContent;"
      " return c.width === 480 && q !== '–' && rows.includes('tc-35mm') ? [c.width, c.height, Number(q), rows] : null;"
      " })()",
      20);
  ASSERT_TRUE(frame.is_array()) << frame;
  EXPECT_EQ(frame[1], 440);
  EXPECT_GT(frame[2].get<double>(), 0.6) << "the virtual camera's frames are as good as the reference";
}

void expect_curves_drawn(const cv::Mat& image, const nlohmann::json& shown);

// What `chromium --headless --screenshot` sees: the picture taken at the
// page's load event, while its event stream is open, has the thermocouple
// curves drawn in the chart (pixels of each series' line colour), not an
// empty frame waiting for the stream.
TEST(ViewBrowser, AScreenshotAtLoadShowsTheCurvesWhileTheStreamIsOpen) {
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  testing::TempDir dir;
  acquisition::ModbusEndpoint endpoint;
  endpoint.port = 0;
  sim::ModbusSimServer module(sim::module_server_options({}, endpoint));
  module.start();
  std::ofstream(dir / "exp.toml") << "[run]\nname = \"shot\"\n\n[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\n"
                                     "host = \"127.0.0.1\"\nport = "
                                  << module.port()
                                  << "\npoll_period_s = 0.1\ntimeout_s = 0.2\n\n[[devices.channels]]\nname = \"tc0\"\n"
                                     "input = 0\n\n[[devices.channels]]\nname = \"tc1\"\ninput = 1\n";
  const std::string run = (dir / "run").string();
  testing::BackgroundProcess acquire({kBosfuse, "acquire", (dir / "exp.toml").string(), "--out", run, "-q"});
  ASSERT_TRUE(testing::wait_for([&] { return holds_readable_run(dir / "run"); }, 10s));
  const int view_port = testing::unused_loopback_port();
  const std::string url = "http://127.0.0.1:" + std::to_string(view_port) + "/";
  testing::BackgroundProcess view({kBosfuse, "view", run, "--listen", "127.0.0.1:" + std::to_string(view_port)});
  // Some seconds of curve (the module starts at 80 °C and cools).
  ASSERT_TRUE(testing::wait_for(
      [&] {
        const auto snapshot = testing::run_command("curl -sf " + url + "snapshot.js", 5).output;
        std::size_t samples = 0;
        for (auto at = snapshot.find("event: sample"); at != std::string::npos; at = snapshot.find("event: sample", at + 1))
          ++samples;
        return samples >= 60;
      },
      30s));
  const Browser browser(dir.path());
  ASSERT_TRUE(browser.ready());
  const auto png = dir / "shot.png";
  // The chart's canvas and each series' line colour as RGB.
  const auto shown = screenshot_at_load(
      browser.devtools_port, url, png,
      "(() => { const r = document.getElementById('chart').getBoundingClientRect(),"
      " g = document.createElement('canvas').getContext('2d');"
      " return {rect: [r.left, r.top, r.width, r.height], ratio: window.devicePixelRatio,"
      "  link: document.getElementById('link').textContent, size: [window.innerWidth, window.innerHeight],"
      "  colours: [...series.values()].map(d => { g.fillStyle = d.borderColor; const h = g.fillStyle;"
      "   return [1, 3, 5].map(i => parseInt(h.slice(i, i + 2), 16)); })}; })()");
  ASSERT_TRUE(shown.is_object()) << shown;
  // And `chromium --headless --screenshot` itself, at the same window size
  // (the DevTools tab's, so the chart is where the page said).
  const auto cli_png = dir / "cli-shot.png";
  std::filesystem::create_directories(dir / "cli");
  const auto cli = testing::chromium(dir / "cli",
                                     "--window-size=" + std::to_string(shown["size"][0].get<int>()) + "," +
                                         std::to_string(shown["size"][1].get<int>()) +
                                         " --screenshot=" + testing::shell_quote(cli_png) + " " + url,
                                     60);
  ASSERT_EQ(cli.exit_code, 0) << cli.output;
  for (const auto& [path, what] : {std::pair{png, "DevTools screenshot"}, std::pair{cli_png, "chromium --screenshot"}}) {
    SCOPED_TRACE(what);
    expect_curves_drawn(cv::imread(path.string(), cv::IMREAD_COLOR), shown);
  }
}

// The chart area of `image` (where `shown` says the page put it) holds each
// curve's colour `shown` names.
void expect_curves_drawn(const cv::Mat& image, const nlohmann::json& shown) {
  ASSERT_FALSE(image.empty()) << "the screenshot is not a PNG OpenCV decodes";
  const double ratio = shown["ratio"].get<double>();
  const cv::Rect chart_area = cv::Rect(static_cast<int>(shown["rect"][0].get<double>() * ratio),
                                       static_cast<int>(shown["rect"][1].get<double>() * ratio),
                                       static_cast<int>(shown["rect"][2].get<double>() * ratio),
                                       static_cast<int>(shown["rect"][3].get<double>() * ratio)) &
                              cv::Rect(0, 0, image.cols, image.rows);
  ASSERT_GT(chart_area.area(), 100 * 100) << shown;
  const cv::Mat chart = image(chart_area);
  ASSERT_EQ(shown["colours"].size(), 2u) << shown;
  for (const auto& colour : shown["colours"]) {
    const int r = colour[0], g = colour[1], b = colour[2];
    int matching = 0;
    for (int y = 0; y < chart.rows; ++y) {
      for (int x = 0; x < chart.cols; ++x) {
        const auto& bgr = chart.at<cv::Vec3b>(y, x);
        if (std::abs(bgr[2] - r) <= 40 && std::abs(bgr[1] - g) <= 40 && std::abs(bgr[0] - b) <= 40) ++matching;
      }
    }
    // A curve over a few seconds of the run spans many pixels; the legend's
    // swatch of that colour alone has under 50 (its border, 40x12 px).
    EXPECT_GT(matching, 150) << "no curve of colour " << colour << " in the chart at load: " << shown;
  }
}

// A finished run, opened after it ended: the page says "finished", not a
// green "live"; its camera row counts the frames with their rate and age;
// events carry their times at a precision without "−0.0 s" and colours by
// meaning (a cleared alarm is green); the marker that is its origin is drawn;
// and the default window ("last 30 min") starts at its first sample, before
// that origin, not at t = 0.
TEST(ViewBrowser, AFinishedRunShowsItsStateCameraEventsMarkerAndTheTimeBeforeItsOrigin) {
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  testing::TempDir dir;
  const std::int64_t t0 = acquisition::utc_now_ns() - 20'000'000'000LL;  // ages in seconds
  constexpr std::int64_t kSecond = 1'000'000'000LL;
  {
    auto store = storage::RunStore::create(dir / "run",
                                           {.id = 0,
                                            .name = "finished",
                                            .started_ns = t0,
                                            .ended_ns = std::nullopt,
                                            .config_toml = "",
                                            .status = storage::RunStatus::kRunning,
                                            .time_scale = 1,
                                            .origin_event = "heater off"},
                                           storage::RunStore::CreateMode::kNew);
    const auto adam = store.add_device({.id = 0, .name = "adam", .kind = "modbus-tcp", .profile = "", .address = ""});
    const auto camera = store.add_device({.id = 0, .name = "cam", .kind = "camera", .profile = "virtual", .address = ""});
    const auto channel = store.add_channel({.id = 0,
                                            .device_id = adam,
                                            .name = "tc0",
                                            .kind = "thermocouple",
                                            .unit = "degC",
                                            .tc_type = std::nullopt,
                                            .image_x_px = std::nullopt,
                                            .image_y_px = std::nullopt});
    std::vector<storage::Sample> samples;
    for (int k = 0; k < 100; ++k) samples.push_back({channel, t0 + k * kSecond / 10, {}, 40.0 + 0.1 * k, {}, {}});
    store.write_samples(samples);
    std::vector<storage::FrameRecord> frames;
    for (int k = 0; k < 25; ++k) {
      frames.push_back({.id = 0,
                        .device_id = camera,
                        .t_ns = t0 + kSecond / 5 + k * 4 * kSecond / 10,
                        .device_t_ns = std::nullopt,
                        .path = "frames/" + std::to_string(k) + ".png",
                        .width_px = 64,
                        .height_px = 64,
                        .bit_depth = 8,
                        .is_reference = false});
    }
    store.write_frames(frames);
    const std::int64_t origin = t0 + 6 * kSecond;  // t = 0: samples from −6 s
    const auto event = [](std::optional<std::int64_t> device, std::int64_t t_ns, std::string kind, std::string message) {
      return storage::Event{.id = 0, .device_id = device, .t_ns = t_ns, .kind = std::move(kind), .message = std::move(message)};
    };
    store.write_events(std::vector<storage::Event>{
        event(adam, origin - kSecond / 50, "connect", "connected"),
        event(adam, origin - kSecond / 250, "error", "a reply was late"),
        event(std::nullopt, origin, "marker", "heater off"),
        event(std::nullopt, origin + 2 * kSecond, "alarm", "tc0: high 46.0 degC above the limit 45 degC"),
        event(std::nullopt, origin + 3 * kSecond, "alarm-cleared", "tc0: high cleared at 44.9 degC")});
    store.finish(storage::RunStatus::kComplete, t0 + 10 * kSecond);
  }
  const int view_port = testing::unused_loopback_port();
  const std::string url = "http://127.0.0.1:" + std::to_string(view_port) + "/";
  testing::BackgroundProcess view({kBosfuse, "view", (dir / "run").string(), "--listen",
                                   "127.0.0.1:" + std::to_string(view_port)});
  ASSERT_TRUE(testing::wait_for([&] { return answers(url + "api/run"); }, 10s));
  const Browser browser(dir.path());
  ASSERT_TRUE(browser.ready());
  const auto page = wait_in_page(
      browser.devtools_port, url,
      "(() => { if (typeof chart === 'undefined' || !chart) return null;"
      " const text = id => document.getElementById(id).textContent;"
      " const events = [...document.querySelectorAll('#events li')].map(li => [li.textContent, li.className]);"
      " const rows = [...document.querySelectorAll('#devices tr')].map(tr => tr.textContent);"
      " const a = chart.chartArea, r = document.querySelector('#readings .reading');"
      " const page = {link: text('link'), link_class: document.getElementById('link').className, bos: text('bos-state'),"
      "  rows, events, x_min: chart.scales.x.min, window: document.getElementById('window').value,"
      "  markers: drawnMarkers.filter(m => m.x_px >= a.left && m.x_px <= a.right).map(m => m.label),"
      "  value: r.querySelector('.value').textContent, age: r.querySelector('.age').textContent};"
      " return events.length === 5 && frames.count === 25 ? page : null; })()",
      30);
  ASSERT_TRUE(page.is_object()) << page;
  EXPECT_EQ(page["link"], "finished: the run is complete") << page;
  EXPECT_NE(page["link_class"], "ok") << "a finished run is not shown in the green of a live one";
  EXPECT_EQ(page["bos"].get<std::string>().find("waiting for frames"), std::string::npos) << page;
  // The camera: frames, rate (24 intervals of 0.4 s) and the age of the last.
  const auto camera = std::find_if(page["rows"].begin(), page["rows"].end(),
                                   [](const auto& row) { return row.template get<std::string>().starts_with("cam"); });
  ASSERT_NE(camera, page["rows"].end()) << page;
  EXPECT_TRUE(std::regex_search(camera->get<std::string>(), std::regex("frames 25, 2\\.50 per s, last \\d+ s ago")))
      << *camera;
  // Events newest first, each at its time and in the colour of its meaning.
  const std::vector<std::pair<std::string, std::string>> expected{
      {"3.00 s alarm-cleared", "ok"}, {"2.00 s alarm", "bad"}, {"0.00 s marker", "marker"},
      {"0.00 s error", "bad"},  // 4 ms before t = 0: no signed zero
      {"−0.02 s connect", "ok"}};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const std::string text = page["events"][i][0];
    EXPECT_TRUE(text.starts_with(expected[i].first)) << i << ": " << text;
    EXPECT_EQ(page["events"][i][1], expected[i].second) << text;
  }
  EXPECT_EQ(page["markers"], nlohmann::json::array({"heater off"}));
  // The last 30 min of a 10 s run: all of it, from −6 s.
  EXPECT_EQ(page["window"], "1800");
  EXPECT_NEAR(page["x_min"].get<double>(), -6.0, 1e-6) << page;
  EXPECT_EQ(page["value"], "49.9 °C");
  EXPECT_TRUE(std::regex_match(page["age"].get<std::string>(), std::regex("\\d+ s ago"))) << page["age"];
}

}  // namespace
}  // namespace bosfuse
