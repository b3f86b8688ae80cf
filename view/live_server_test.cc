// The viewer as a browser meets it: a real server on a loopback port chosen
// at run time, over a run another connection is writing.

#include "view/live_server.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"
#include "view/test_sse.h"

namespace bosfuse::view {
namespace {

using namespace std::chrono_literals;

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
    server_ = std::make_unique<LiveServer>(dir_ / "run", options);
    port_ = server_->listen();
    serving_ = std::thread([this] { server_->serve(); });
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port_);
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
  // Reads /events until `want` samples arrived (or 10 s); returns the messages.
  std::vector<testing::SseMessage> read_events(std::size_t want, const std::string& last_event_id = "") {
    auto c = client();
    std::string text;
    httplib::Headers headers;
    if (!last_event_id.empty()) headers.emplace("Last-Event-ID", last_event_id);
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    c.Get("/events", headers, [&](const char* data, std::size_t length) {
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
