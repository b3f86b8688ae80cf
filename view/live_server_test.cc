// The viewer as a browser meets it: a real server on a loopback port chosen
// at run time, over a run another connection is writing.

#include "view/live_server.h"
#include "view/live_stream.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"
#include "view/test_raw_connection.h"
#include "view/test_sse.h"

namespace bosfuse::view {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using testing::RawConnection;

class Viewer : public ::testing::Test {
 protected:
  void SetUp() override {
    writer_.emplace(storage::RunStore::create(dir_ / "run", {.name = "live", .started_ns = 1'000'000'000},
                                              storage::RunStore::CreateMode::kNew));
    device_ = writer_->add_device({.name = "adam", .kind = "modbus-tcp"});
    channel_ = writer_->add_channel({.device_id = device_, .name = "tc0", .kind = "thermocouple", .unit = "degC"});
  }
  void TearDown() override {
    if (server_) server_->stop();
    if (serving_.joinable()) serving_.join();
  }

  void start(ViewOptions options = {}) {
    options.port = 0;
    options.poll_period = 20ms;
    host_ = options.host;
    server_ = std::make_unique<LiveServer>(dir_ / "run", options);
    port_ = server_->listen();
    serving_ = std::thread([this] { server_->serve(); });
  }
  httplib::Client client() const {
    httplib::Client c(host_, port_);
    c.set_read_timeout(5, 0);
    return c;
  }
  // Samples numbered first..first+count-1, the value being the number, in batches.
  void write_samples(int first, int count, int per_batch = 7) {
    for (int i = first; i < first + count; i += per_batch) {
      std::vector<storage::Sample> batch;
      for (int k = i; k < std::min(i + per_batch, first + count); ++k) {
        batch.push_back({channel_, 2'000'000'000LL + k * 1'000'000LL, {}, static_cast<double>(k), {}, {}});
      }
      writer_->write_samples(batch);
    }
  }
  // Reads `path` (the stream) until `want` samples arrived (or 10 s); returns the messages.
  std::vector<testing::SseMessage> read_events(std::size_t want, const std::string& last_event_id = "",
                                               const std::string& path = "/events") {
    auto c = client();
    std::string text;
    httplib::Headers headers;
    if (!last_event_id.empty()) headers.emplace("Last-Event-ID", last_event_id);
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    c.Get(path, headers, [&](const char* data, std::size_t length) {
      text.append(data, length);
      std::size_t samples = 0;
      for (const auto& m : testing::parse_sse(text)) samples += m.type == "sample";
      return samples < want && std::chrono::steady_clock::now() < deadline;
    });
    return testing::parse_sse(text);
  }
  static std::vector<double> sample_values(const std::vector<testing::SseMessage>& messages) {
    std::vector<double> values;
    for (const auto& m : messages) {
      if (m.type == "sample") values.push_back(nlohmann::json::parse(m.data).at("value").get<double>());
    }
    return values;
  }

  bosfuse::testing::TempDir dir_;
  std::optional<storage::RunStore> writer_;
  std::int64_t device_ = 0;
  std::int64_t channel_ = 0;
  std::unique_ptr<LiveServer> server_;
  std::thread serving_;
  std::string host_;
  int port_ = 0;
};

TEST_F(Viewer, ServesThePageChartJsAndTheRunDescription) {
  start();
  auto c = client();
  const auto page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<script src=\"/chart.js\">"), std::string::npos);
  EXPECT_EQ(page->body.find("http"), std::string::npos) << "the page loads nothing from elsewhere";
  const auto chart = c.Get("/chart.js");
  ASSERT_TRUE(chart);
  EXPECT_EQ(chart->status, 200);
  EXPECT_NE(chart->body.find("Chart"), std::string::npos);
  const auto run = c.Get("/api/run");
  ASSERT_TRUE(run);
  const auto json = nlohmann::json::parse(run->body);
  EXPECT_EQ(json.at("name"), "live");
  EXPECT_EQ(json.at("status"), "running");
  EXPECT_NE(json.at("time_basis").get<std::string>().find("experiment seconds"), std::string::npos);
  ASSERT_EQ(json.at("channels").size(), 1u);
  EXPECT_EQ(json.at("channels")[0].at("unit"), "degC");
  EXPECT_EQ(json.at("channels")[0].at("device"), "adam");
}

TEST_F(Viewer, AnswersOtherPathsWith404) {
  start();
  auto c = client();
  for (const char* path : {"/run.sqlite", "/../run.sqlite", "/index.html", "/api", "/events/x", "/%2e%2e/run.sqlite",
                           "/usr/share/javascript/chart.js/chart.min.js"}) {
    const auto response = c.Get(path);
    ASSERT_TRUE(response) << path;
    EXPECT_EQ(response->status, 404) << path;
    EXPECT_EQ(response->body, "not found\n") << path;
  }
}

// Overwrites every byte of the run's database and its log with text.
void damage(const std::filesystem::path& run) {
  for (const char* name : {"run.sqlite", "run.sqlite-wal"}) {
    const auto path = run / name;
    if (!std::filesystem::exists(path)) continue;
    const std::string garbage(std::filesystem::file_size(path), 'x');
    std::fstream(path, std::ios::in | std::ios::out | std::ios::binary).write(garbage.data(), garbage.size());
  }
}

TEST_F(Viewer, ARunDamagedWhileServedIsSaidOnTheApiAndTheStreamAndTheServerGoesOn) {
  write_samples(0, 20);
  start();
  writer_.reset();
  damage(dir_ / "run");
  auto c = client();
  const auto run = c.Get("/api/run");
  ASSERT_TRUE(run);
  EXPECT_EQ(run->status, 500);
  const std::string error = nlohmann::json::parse(run->body).at("error");
  EXPECT_NE(error.find("the run cannot be read now"), std::string::npos) << error;
  EXPECT_NE(error.find("damaged"), std::string::npos) << error;
  const auto events = c.Get("/events");
  ASSERT_TRUE(events);
  EXPECT_EQ(events->status, 500);
  EXPECT_NE(events->body.find("the run cannot be read now"), std::string::npos) << events->body;
  const auto page = c.Get("/");  // the page still comes, and shows /api/run's error
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("showRunError(body.error)"), std::string::npos);
}

TEST_F(Viewer, StreamsEverySampleInCommitOrderWhileTheRunIsWritten) {
  write_samples(0, 50);
  start();
  std::thread writing([&] {
    std::this_thread::sleep_for(50ms);
    write_samples(50, 250);
  });
  const auto messages = read_events(300);
  writing.join();
  const auto values = sample_values(messages);
  ASSERT_EQ(values.size(), 300u);
  for (std::size_t i = 0; i < values.size(); ++i) ASSERT_EQ(values[i], static_cast<double>(i)) << "at " << i;
  ASSERT_FALSE(messages.empty());
  EXPECT_EQ(messages.front().type, "clock");
  const auto first = std::find_if(messages.begin(), messages.end(), [](auto& m) { return m.type == "sample"; });
  const auto data = nlohmann::json::parse(first->data);
  EXPECT_DOUBLE_EQ(data.at("t_s").get<double>(), 0.0) << "t = 0 is the first sample";
  EXPECT_EQ(data.at("channel"), channel_);
  EXPECT_EQ(data.at("status"), "ok");
}

TEST_F(Viewer, AReconnectWithLastEventIdContinuesWithoutLossOrRepeat) {
  write_samples(0, 120);
  start();
  const auto before = read_events(40);
  auto values = sample_values(before);
  ASSERT_GE(values.size(), 40u);
  const auto last = std::find_if(before.rbegin(), before.rend(), [](auto& m) { return !m.id.empty(); });
  ASSERT_NE(last, before.rend());
  write_samples(120, 80);
  const auto after = sample_values(read_events(200 - values.size(), last->id));
  values.insert(values.end(), after.begin(), after.end());
  ASSERT_EQ(values.size(), 200u);
  for (std::size_t i = 0; i < values.size(); ++i) ASSERT_EQ(values[i], static_cast<double>(i)) << "at " << i;
}

// The page's first paint: /snapshot.js holds the run's description and the
// stream's first turn with the cursor after it, and the stream named by that
// cursor (`/events?after=`) goes on with nothing lost or repeated.
TEST_F(Viewer, TheSnapshotHoldsTheRunSoFarAndTheStreamGoesOnAfterItsCursor) {
  write_samples(0, 50);
  start();
  auto c = client();
  const auto script = c.Get("/snapshot.js");
  ASSERT_TRUE(script);
  ASSERT_EQ(script->status, 200);
  EXPECT_EQ(script->get_header_value("Content-Type"), "text/javascript; charset=utf-8");
  const std::string prefix = "window.bosfuseSnapshot = ";
  ASSERT_TRUE(script->body.starts_with(prefix)) << script->body.substr(0, 100);
  ASSERT_TRUE(script->body.ends_with(";\n"));
  const auto snapshot =
      nlohmann::json::parse(script->body.substr(prefix.size(), script->body.size() - prefix.size() - 2));
  EXPECT_EQ(snapshot.at("run").at("name"), "live");
  auto values = sample_values(testing::parse_sse(snapshot.at("stream").get<std::string>()));
  ASSERT_EQ(values.size(), 50u);
  const std::string cursor = snapshot.at("cursor");
  EXPECT_EQ(parse_cursor(cursor)->sample_rowid, 50);
  write_samples(50, 30);
  const auto after = sample_values(read_events(30, "", "/events?after=" + cursor));
  values.insert(values.end(), after.begin(), after.end());
  ASSERT_EQ(values.size(), 80u);
  for (std::size_t i = 0; i < values.size(); ++i) ASSERT_EQ(values[i], static_cast<double>(i)) << "at " << i;
  const auto foreign = c.Get("/events?after=50-0");
  ASSERT_TRUE(foreign);
  EXPECT_EQ(foreign->status, 400);
}

TEST_F(Viewer, StreamsEventsAndFrameCounts) {
  const storage::Event lost{0, device_, 2'000'000'000, "disconnect", "no answer"};
  writer_->write_events({&lost, 1});
  writer_->add_frame({.t_ns = 2'500'000'000, .path = "frames/0.png", .width_px = 64, .height_px = 48});
  write_samples(0, 1);
  start();
  const auto messages = read_events(1);
  std::vector<std::string> kinds;
  for (const auto& m : messages) {
    if (m.type == "event") kinds.push_back(nlohmann::json::parse(m.data).at("kind"));
    if (m.type == "frames") {
      const auto data = nlohmann::json::parse(m.data);
      EXPECT_EQ(data.at("count"), 1);
      EXPECT_DOUBLE_EQ(data.at("last_t_s").get<double>(), 0.5);
      EXPECT_DOUBLE_EQ(data.at("first_t_s").get<double>(), 0.5);  // for the rate over the run
    }
  }
  EXPECT_NE(std::find(kinds.begin(), kinds.end(), "disconnect"), kinds.end());
  const auto disconnect = std::find_if(messages.begin(), messages.end(), [](auto& m) {
    return m.type == "event" && m.data.find("disconnect") != std::string::npos;
  });
  EXPECT_EQ(nlohmann::json::parse(disconnect->data).at("device"), "adam");
}

TEST_F(Viewer, RefusesAStreamBeyondItsClientLimitAndAForeignLastEventId) {
  start({.max_clients = 1});
  std::atomic<bool> open{false};
  std::atomic<bool> done{false};
  std::thread holder([&] {
    auto c = client();
    c.Get("/events", [&](const char*, std::size_t) {
      open = true;
      return !done;
    });
  });
  ASSERT_TRUE(bosfuse::testing::wait_for([&] { return open.load(); }, 5s));
  auto c = client();
  const auto refused = c.Get("/events");
  done = true;
  write_samples(0, 1);  // wakes the holder's stream so it sees `done`
  holder.join();
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 503);
  const auto foreign = c.Get("/events", {{"Last-Event-ID", "../../etc/passwd"}});
  ASSERT_TRUE(foreign);
  EXPECT_EQ(foreign->status, 400);
}

// The status of GET `path` with these headers (0: no answer); the body is
// not read, so a stream is left at once.
int status_of(httplib::Client& c, const std::string& path, const httplib::Headers& headers) {
  int status = 0;
  c.Get(
      path, headers,
      [&](const httplib::Response& response) {
        status = response.status;
        return false;
      },
      [](const char*, std::size_t) { return false; });
  return status;
}

// A page of another site whose name was made to resolve to 127.0.0.1 (DNS
// rebinding) sends its own name as Host: refused, on every route, before
// anything is read; the viewer's own names pass, with and without the port.
TEST_F(Viewer, RefusesARequestThatNamesAnotherHostOnEveryRoute) {
  start();
  auto c = client();
  const std::string port = std::to_string(port_);
  for (const char* path : {"/", "/chart.js", "/api/run", "/snapshot.js", "/frame.png", "/events", "/nothing"}) {
    for (const std::string& host : std::vector<std::string>{
             "evil.example", "evil.example:" + port, "127.0.0.1.evil.example", "localhost.evil.example:" + port,
             "127.0.0.1:" + std::to_string(port_ + 1), "[::2]:" + port, ""}) {
      const auto response = c.Get(path, {{"Host", host}});
      ASSERT_TRUE(response) << path << " " << host;
      EXPECT_EQ(response->status, 403) << path << " Host: " << host;
      EXPECT_NE(response->body.find("answers only to its own address"), std::string::npos) << response->body;
    }
  }
  for (const std::string& host : std::vector<std::string>{"localhost", "localhost:" + port, "LocalHost:" + port,
                                                          "127.0.0.1", "127.0.0.1:" + port, "[::1]", "[::1]:" + port}) {
    EXPECT_EQ(status_of(c, "/api/run", {{"Host", host}}), 200) << host;
    EXPECT_EQ(status_of(c, "/events", {{"Host", host}}), 200) << host;
  }
  RawConnection no_host("127.0.0.1", port_);  // HTTP/1.0 may leave Host out; this viewer wants it
  ASSERT_TRUE(no_host.send_text("GET /api/run HTTP/1.0\r\n\r\n"));
  ASSERT_TRUE(bosfuse::testing::wait_for([&] { return no_host.closed_by_server(); }, 5s));
  EXPECT_EQ(no_host.received().rfind("HTTP/1.1 403", 0), 0u) << no_host.received();
}

// Slowloris: 20 connections each send a request line, then a header byte a
// second (for at most 12 s). The page answers at once meanwhile, and each
// is cut off within the request timeout (5 s, docs/VIEW.md) plus a margin;
// so is a connection that sends nothing (the idle timeout, 5 s).
// The margin: this test looks once a second, and a loaded machine (tests
// side by side, sanitizers) is slow to answer. The 20 connections open at
// once, beyond httplib's own listen queue of 5 (GuardedServer widens it),
// and a byte that trickles in after the deadline must not start another
// request: both once made single connections last 10-12 s.
constexpr auto kCutOffMargin = 3s;

TEST_F(Viewer, ConnectionsThatTrickleTheirRequestsAreCutOffAndThePageStaysReachable) {
  start();
  std::vector<std::unique_ptr<RawConnection>> slow;
  for (int i = 0; i < 20; ++i) {
    slow.push_back(std::make_unique<RawConnection>("127.0.0.1", port_));
    ASSERT_TRUE(slow.back()->connected());
    ASSERT_TRUE(slow.back()->send_text("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "));
  }
  RawConnection silent("127.0.0.1", port_);
  const auto opened = Clock::now();
  std::vector<Clock::duration> cut_after(slow.size() + 1, Clock::duration::max());
  std::thread trickling([&] {
    for (int second = 0; second < 12; ++second) {  // bounded: 12 rounds of a byte each
      std::this_thread::sleep_for(1s);
      for (std::size_t i = 0; i < slow.size(); ++i) {
        if (cut_after[i] != Clock::duration::max()) continue;
        if (slow[i]->closed_by_server() || !slow[i]->send_text("x")) cut_after[i] = Clock::now() - opened;
      }
      if (cut_after.back() == Clock::duration::max() && silent.closed_by_server()) {
        cut_after.back() = Clock::now() - opened;
      }
      if (std::none_of(cut_after.begin(), cut_after.end(), [](auto d) { return d == Clock::duration::max(); })) break;
    }
  });
  std::this_thread::sleep_for(1500ms);  // every slow connection holds a thread now
  auto c = client();
  const auto asked = Clock::now();
  const auto page = c.Get("/");
  const auto run = c.Get("/api/run");
  const auto answered_in = Clock::now() - asked;
  trickling.join();
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  ASSERT_TRUE(run);
  EXPECT_EQ(run->status, 200);
  EXPECT_LT(answered_in, 2s) << "the page waited for the slow connections";
  for (std::size_t i = 0; i < cut_after.size(); ++i) {
    EXPECT_LT(cut_after[i], 5s + kCutOffMargin) << "connection " << i << " was not cut off within 5 s + margin";
  }
}

// 16 clients open /events and never read, while the run is written: their
// small receive buffers fill, and 5 s (docs/VIEW.md) after they stopped
// acknowledging, the viewer drops them; a new stream is then served.
TEST_F(Viewer, StreamsWhoseClientsStopReadingAreDroppedAndTheirSlotsServeANewClient) {
  start();
  std::atomic<bool> done{false};
  std::thread recording([&] {
    for (int i = 0; !done && i < 3000; ++i) {  // bounded: at most about 30 s
      write_samples(i * 10, 10, 10);
      std::this_thread::sleep_for(10ms);
    }
  });
  std::vector<std::unique_ptr<RawConnection>> idle_readers;
  for (int i = 0; i < 16; ++i) {
    idle_readers.push_back(std::make_unique<RawConnection>("127.0.0.1", port_, 4096));
    ASSERT_TRUE(idle_readers.back()->connected());
    ASSERT_TRUE(idle_readers.back()->send_text("GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
  }
  for (auto& reader : idle_readers) {
    ASSERT_TRUE(bosfuse::testing::wait_for([&] { return reader->peek_starts_with("HTTP/1.1 200"); }, 5s));
  }
  auto c = client();
  ASSERT_EQ(status_of(c, "/events", {}), 503) << "the 16 streams should take every slot";
  const auto full = Clock::now();
  const bool served = bosfuse::testing::wait_for([&] { return status_of(c, "/events", {}) == 200; }, 12s);
  const auto waited = Clock::now() - full;
  done = true;
  recording.join();
  EXPECT_TRUE(served) << "no slot was given back within 12 s";
  EXPECT_LT(waited, 5s + 3s) << "a slot came back only after "
                             << std::chrono::duration_cast<std::chrono::milliseconds>(waited).count() << " ms";
}

// The token of a viewer off loopback (asked for here on 127.0.0.1, so the
// test binds nothing else): in the URL, then a cookie the page's requests
// carry; any request without it, on any route, is 403.
TEST_F(Viewer, WantsTheTokenOfItsUrlOnEveryRouteAndHandsItToThePageAsACookie) {
  start({.require_token = true});
  const std::string url = server_->url();
  std::smatch match;
  ASSERT_TRUE(std::regex_match(url, match, std::regex(R"(http://127\.0\.0\.1:\d+/\?token=([0-9a-f]{32}))"))) << url;
  const std::string token = match[1];
  const std::string cookie = "bosfuse_token_" + std::to_string(port_);
  auto c = client();
  for (const char* path : {"/", "/chart.js", "/api/run", "/snapshot.js", "/frame.png", "/events", "/nothing"}) {
    EXPECT_EQ(status_of(c, path, {}), 403) << path;
    EXPECT_EQ(status_of(c, std::string(path) + "?token=" + std::string(32, '0'), {}), 403) << path;
    EXPECT_EQ(status_of(c, path, {{"Cookie", cookie + "=" + token.substr(1) + "0"}}), 403) << path;
    EXPECT_EQ(status_of(c, path, {{"Cookie", "bosfuse_token_1=" + token}}), 403) << path;
  }
  const auto page = c.Get("/?token=" + token);
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->get_header_value("Set-Cookie"), cookie + "=" + token + "; Path=/; HttpOnly; SameSite=Strict");
  EXPECT_EQ(status_of(c, "/api/run", {{"Cookie", cookie + "=" + token}}), 200);
  EXPECT_EQ(status_of(c, "/chart.js", {{"Cookie", "theme=dark; " + cookie + "=" + token}}), 200);
  EXPECT_EQ(status_of(c, "/events", {{"Cookie", cookie + "=" + token}}), 200);
  EXPECT_EQ(status_of(c, "/api/run", {{"Cookie", cookie + "=" + token}, {"Host", "evil.example"}}), 403)
      << "the token does not lift the Host check";
}

// Off loopback the Host may also name the address listened on; 127.0.0.2 is
// loopback too on Linux, so the test reaches no network.
TEST_F(Viewer, AcceptsTheAddressItListensOnAsHostAndDrawsANewTokenEachStart) {
  start({.host = "127.0.0.2", .require_token = true});
  const std::string url = server_->url();
  const std::string token = url.substr(url.find("token=") + 6);
  auto c = client();
  const std::string port = std::to_string(port_);
  EXPECT_EQ(status_of(c, "/api/run?token=" + token, {{"Host", "127.0.0.2:" + port}}), 200);
  EXPECT_EQ(status_of(c, "/api/run?token=" + token, {{"Host", "127.0.0.2"}}), 200);
  EXPECT_EQ(status_of(c, "/api/run?token=" + token, {{"Host", "127.0.0.3:" + port}}), 403);
  LiveServer other(dir_ / "run", {.host = "127.0.0.2", .port = 0, .require_token = true});
  other.listen();
  const std::string other_url = other.url();
  EXPECT_NE(other_url.substr(other_url.find("token=") + 6), token);
}

TEST(ListenAddress, SaysWhichAddressesAreLoopback) {
  for (const char* host :
       {"127.0.0.1", "127.0.0.2", "127.255.0.9", "::1", "::ffff:127.0.0.1", "localhost", "LOCALHOST"}) {
    EXPECT_TRUE(is_loopback_address(host)) << host;
  }
  for (const char* host : {"0.0.0.0", "::", "192.168.1.5", "10.0.0.1", "128.0.0.1", "::2", "lab-pc", ""}) {
    EXPECT_FALSE(is_loopback_address(host)) << host;
  }
}

// Constructed, never bound: off loopback the URL carries a token.
TEST(ViewerSetup, WantsATokenWheneverItListensOffLoopback) {
  bosfuse::testing::TempDir dir;
  storage::RunStore::create(dir / "run", {.name = "x"}, storage::RunStore::CreateMode::kNew);
  for (const char* host : {"0.0.0.0", "192.168.1.5", "::"}) {
    const LiveServer server(dir / "run", {.host = host});
    EXPECT_NE(server.url().find("/?token="), std::string::npos) << host;
  }
  const LiveServer local(dir / "run", {});
  EXPECT_EQ(local.url().find("token"), std::string::npos);
}

TEST(ViewerSetup, SaysWhenTheFolderHoldsNoRun) {
  bosfuse::testing::TempDir dir;
  try {
    LiveServer server(dir.path(), {});
    FAIL() << "a folder without a run must be refused";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("holds no bosfuse run"), std::string::npos) << e.what();
  }
}

TEST(ViewerSetup, SaysWhenChartJsIsMissing) {
  bosfuse::testing::TempDir dir;
  storage::RunStore::create(dir / "run", {.name = "x"}, storage::RunStore::CreateMode::kNew);
  ViewOptions options;
  options.chartjs_path = dir / "nothing.js";
  EXPECT_THROW(LiveServer(dir / "run", options), ViewError);
}

TEST(ViewerSetup, SaysWhenThePortIsInUse) {
  bosfuse::testing::TempDir dir;
  storage::RunStore::create(dir / "run", {.name = "x"}, storage::RunStore::CreateMode::kNew);
  LiveServer first(dir / "run", {.port = 0});
  const int port = first.listen();
  LiveServer second(dir / "run", {.port = port});
  try {
    second.listen();
    FAIL() << "the port is taken";
  } catch (const ViewError& e) {
    EXPECT_NE(std::string(e.what()).find("in use"), std::string::npos) << e.what();
  }
}

TEST(ListenAddress, ReadsHostAndPort) {
  ViewOptions options;
  parse_listen_address("127.0.0.1:9000", options);
  EXPECT_EQ(options.host, "127.0.0.1");
  EXPECT_EQ(options.port, 9000);
  parse_listen_address("[::1]:0", options);
  EXPECT_EQ(options.host, "::1");
  parse_listen_address(":8081", options);
  EXPECT_EQ(options.host, "127.0.0.1");
  EXPECT_THROW(parse_listen_address("8080", options), ViewError);
  EXPECT_THROW(parse_listen_address("localhost:http", options), ViewError);
  EXPECT_THROW(parse_listen_address("localhost:70000", options), ViewError);
}

}  // namespace
}  // namespace bosfuse::view
