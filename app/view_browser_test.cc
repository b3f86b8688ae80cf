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

#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "tests/support/browser.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace std::chrono_literals;

const std::string kBosfuse = std::string(BOSFUSE_BINARY_DIR) + "/bosfuse";
const std::string kCdpWait = std::string(BOSFUSE_SOURCE_DIR) + "/tests/support/cdp_wait.py";

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
// the token as a cookie, with which its own requests — /chart.js, /api/run,
// the event stream — are let in, and it shows the run.
TEST(ViewBrowser, APageOpenedAtItsTokenedUrlShowsTheRunThroughItsCookie) {
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  testing::TempDir dir;
  {
    auto store = storage::RunStore::create(dir / "run", {.name = "tokened", .started_ns = 1'000'000'000},
                                           storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({.name = "adam", .kind = "modbus-tcp"});
    const auto channel =
        store.add_channel({.device_id = device, .name = "tc0", .kind = "thermocouple", .unit = "degC"});
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
      " return document.getElementById('link').textContent === 'live' &&"
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
  ASSERT_TRUE(testing::wait_for([&] { return std::filesystem::exists(dir / "run/run.sqlite"); }, 10s));

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

}  // namespace
}  // namespace bosfuse
