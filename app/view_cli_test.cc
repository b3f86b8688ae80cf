// `bosfuse view` as a user runs it, read by an independent HTTP client
// (curl) while the test records into the run.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"
#include "view/test_sse.h"

namespace bosfuse {
namespace {

using namespace std::chrono_literals;

using testing::kBosfuse;

// A loopback port free right now (the kernel's choice, released at once).
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    close(fd);
    throw std::runtime_error("no free loopback port");
  }
  close(fd);
  return ntohs(address.sin_port);
}

class ViewCli : public ::testing::Test {
 protected:
  void SetUp() override {
    writer_.emplace(storage::RunStore::create(run_dir(), {.name = "view-cli", .started_ns = 1'000'000'000},
                                              storage::RunStore::CreateMode::kNew));
    const auto device = writer_->add_device({.name = "adam", .kind = "modbus-tcp"});
    channel_ = writer_->add_channel({.device_id = device, .name = "tc0", .kind = "thermocouple", .unit = "degC"});
    port_ = free_port();
  }

  std::string run_dir() const { return (dir_ / "run").string(); }
  std::string url(const std::string& path) const { return "http://127.0.0.1:" + std::to_string(port_) + path; }
  std::unique_ptr<testing::BackgroundProcess> start_view() {
    auto view = std::make_unique<testing::BackgroundProcess>(std::vector<std::string>{
        kBosfuse, "view", run_dir(), "--listen", "127.0.0.1:" + std::to_string(port_)});
    const bool up = testing::wait_for(
        [&] { return testing::run_command("curl -sf -o /dev/null " + url("/api/run"), 5).exit_code == 0; }, 10s);
    if (!up) throw std::runtime_error("bosfuse view did not answer within 10 s");
    return view;
  }
  // Samples numbered first.., the value being the number, one batch every 10 ms.
  void write_samples(int first, int count) {
    for (int i = first; i < first + count; i += 5) {
      std::vector<storage::Sample> batch;
      for (int k = i; k < std::min(i + 5, first + count); ++k) {
        batch.push_back({channel_, 2'000'000'000LL + k * 10'000'000LL, {}, static_cast<double>(k), {}, {}});
      }
      writer_->write_samples(batch);
      std::this_thread::sleep_for(10ms);
    }
  }
  // /events for `seconds`, as curl received it.
  std::vector<view::testing::SseMessage> curl_events(double seconds, const std::string& last_event_id = "") {
    std::string command = "curl -sN --max-time " + std::to_string(seconds) + " ";
    if (!last_event_id.empty()) command += "-H 'Last-Event-ID: " + last_event_id + "' ";
    const auto result = testing::run_command(command + url("/events"), static_cast<int>(seconds) + 10);
    EXPECT_EQ(result.exit_code, 28) << "curl ends the stream at its time limit: " << result.output;
    return view::testing::parse_sse(result.output);
  }
  static std::vector<double> values(const std::vector<view::testing::SseMessage>& messages) {
    std::vector<double> out;
    for (const auto& m : messages) {
      if (m.type == "sample") out.push_back(nlohmann::json::parse(m.data).at("value").get<double>());
    }
    return out;
  }

  testing::TempDir dir_;
  std::optional<storage::RunStore> writer_;
  std::int64_t channel_ = 0;
  int port_ = 0;
};

TEST_F(ViewCli, CurlReadsEverySampleOnceAcrossAReconnectWhileTheRunIsRecorded) {
  write_samples(0, 50);
  const auto view = start_view();
  std::thread recording([&] { write_samples(50, 350); });  // about 0.7 s of batches
  const auto first = curl_events(0.4);
  const auto last = std::find_if(first.rbegin(), first.rend(), [](auto& m) { return !m.id.empty(); });
  ASSERT_NE(last, first.rend());
  const auto second = curl_events(2.5, last->id);
  recording.join();
  std::vector<double> seen = values(first);
  EXPECT_LT(seen.size(), 400u) << "the first connection should end while the run is still written";
  const std::vector<double> rest = values(second);
  seen.insert(seen.end(), rest.begin(), rest.end());
  const auto stored = writer_->read_samples(channel_);
  ASSERT_EQ(seen.size(), stored.size());
  for (std::size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], *stored[i].value) << "at " << i;
}

TEST_F(ViewCli, PrintsItsUrlAndStopsOnCtrlC) {
  const std::string out = (dir_ / "out.txt").string();
  testing::BackgroundProcess view({"/bin/sh", "-c",
                                   "exec " + kBosfuse + " view " + run_dir() + " --listen 127.0.0.1:" +
                                       std::to_string(port_) + " > " + out});
  ASSERT_TRUE(testing::wait_for(
      [&] {
        std::ifstream in(out);
        std::string line;
        return std::getline(in, line) && line == url("/");
      },
      10s));
  view.send_signal(SIGINT);
  EXPECT_EQ(view.wait_exit(5s), 0);
}

TEST_F(ViewCli, AnswersOnlyItsOwnRoutes) {
  const auto view = start_view();
  for (const char* path : {"/run.sqlite", "/..%2frun.sqlite", "/etc/passwd", "/api/run/x"}) {
    const auto result = testing::run_command("curl -s -o /dev/null -w '%{http_code}' '" + url(path) + "'");
    EXPECT_EQ(result.output, "404") << path;
  }
  EXPECT_EQ(testing::run_command("curl -s -o /dev/null -w '%{http_code}' " + url("/chart.js")).output, "200");
}

// The probe's request (`curl -H 'Host: evil.example' …/api/run`), as a
// DNS-rebinding page would send it: refused.
TEST_F(ViewCli, RefusesARequestNamingAnotherHost) {
  const auto view = start_view();
  const std::string status = "curl -s -o /dev/null --max-time 5 -w '%{http_code}' ";
  for (const char* path : {"/", "/api/run", "/events", "/chart.js"}) {
    EXPECT_EQ(testing::run_command(status + "-H 'Host: evil.example' " + url(path), 10).output, "403") << path;
  }
  EXPECT_EQ(testing::run_command(status + "-H 'Host: localhost:" + std::to_string(port_) + "' " + url("/api/run"), 10)
                .output,
            "200");
}

// `view --token` (what a listen address off loopback always gets): the
// printed URL carries the token; without it curl is refused, with it (or
// with the cookie the page got) served.
TEST_F(ViewCli, WithATokenPrintsItInTheUrlAndRefusesRequestsWithoutIt) {
  const std::string out = (dir_ / "out.txt").string();
  testing::BackgroundProcess view({"/bin/sh", "-c",
                                   "exec " + kBosfuse + " view " + run_dir() + " --token --listen 127.0.0.1:" +
                                       std::to_string(port_) + " > " + out});
  std::string printed;
  ASSERT_TRUE(testing::wait_for(
      [&] {
        std::ifstream in(out);
        return std::getline(in, printed) && printed.rfind(url("/?token="), 0) == 0;
      },
      10s))
      << printed;
  const std::string token = printed.substr(url("/?token=").size());
  EXPECT_EQ(token.size(), 32u) << printed;
  const std::string status = "curl -s -o /dev/null --max-time 5 -w '%{http_code}' ";
  EXPECT_EQ(testing::run_command(status + url("/api/run"), 10).output, "403");
  EXPECT_EQ(testing::run_command(status + "'" + url("/api/run?token=") + "x" + token.substr(1) + "'", 10).output,
            "403");
  const std::string jar = (dir_ / "cookies.txt").string();
  EXPECT_EQ(testing::run_command(status + "-c " + jar + " '" + printed + "'", 10).output, "200");
  EXPECT_EQ(testing::run_command(status + "-b " + jar + " " + url("/api/run"), 10).output, "200");
  view.send_signal(SIGINT);
  EXPECT_EQ(view.wait_exit(5s), 0);
}

TEST_F(ViewCli, SaysThePortIsInUse) {
  const auto view = start_view();
  const auto second = testing::run_command(kBosfuse + " view " + run_dir() + " --listen 127.0.0.1:" +
                                           std::to_string(port_));
  EXPECT_EQ(second.exit_code, 1);
  EXPECT_NE(second.output.find("cannot listen on 127.0.0.1:" + std::to_string(port_) +
                               ": the port is in use (choose another with --listen HOST:PORT)"),
            std::string::npos)
      << second.output;
}

TEST_F(ViewCli, RefusesAFolderThatIsNotARunOrIsDamaged) {
  std::filesystem::create_directories(dir_ / "nothing");
  const auto empty = testing::run_command(kBosfuse + " view " + (dir_ / "nothing").string());
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_NE(empty.output.find("holds no bosfuse run"), std::string::npos) << empty.output;
  std::filesystem::create_directories(dir_ / "damaged");
  std::ofstream(dir_ / "damaged" / "run.sqlite") << "not a database";
  const auto damaged = testing::run_command(kBosfuse + " view " + (dir_ / "damaged").string());
  EXPECT_EQ(damaged.exit_code, 1);
  EXPECT_NE(damaged.output.find("not a readable bosfuse run"), std::string::npos) << damaged.output;
}

// `acquire --live`: the viewer inside the logger, over the run it records.
class AcquireLive : public ViewCli {
 protected:
  void SetUp() override {
    ViewCli::SetUp();
    acquisition::ModbusEndpoint endpoint;
    endpoint.port = 0;
    module_.emplace(sim::module_server_options({}, endpoint));
    module_->start();
    std::ofstream(dir_ / "exp.toml") << "[run]\nname = \"live\"\n\n[[devices]]\nname = \"adam\"\nprofile = "
                                        "\"adam-6018\"\nhost = \"127.0.0.1\"\nport = "
                                     << module_->port()
                                     << "\npoll_period_s = 0.05\ntimeout_s = 0.2\n\n[[devices.channels]]\nname = "
                                        "\"tc0\"\ninput = 0\nalarm_high = 50\n";
  }
  std::string acquire_command(const std::string& duration) const {
    return kBosfuse + " acquire " + (dir_ / "exp.toml").string() + " --out " + (dir_ / "logged").string() +
           " --duration " + duration + " --live 127.0.0.1:" + std::to_string(port_);
  }
  std::optional<sim::ModbusSimServer> module_;
};

TEST_F(AcquireLive, PrintsTheUrlOfTheRunItRecordsAndServesItsSamplesLive) {
  const std::string err = (dir_ / "err.txt").string();
  testing::BackgroundProcess acquire({"/bin/sh", "-c", "exec " + acquire_command("4s") + " 2> " + err});
  ASSERT_TRUE(testing::wait_for(
      [&] {
        std::ifstream in(err);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        return text.find("live view: " + url("/")) != std::string::npos;
      },
      10s));
  const auto run = testing::run_command("curl -sf " + url("/api/run"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(nlohmann::json::parse(run.output).at("name"), "live");
  const auto events = curl_events(1.0);
  EXPECT_GE(values(events).size(), 5u) << "samples arrive while the logger records";
  const auto alarm = std::find_if(events.begin(), events.end(), [](const auto& m) {
    return m.type == "event" && nlohmann::json::parse(m.data).at("kind") == "alarm";
  });
  ASSERT_NE(alarm, events.end()) << "the module serves 80 °C, above the limit";
  EXPECT_EQ(nlohmann::json::parse(alarm->data).at("message").get<std::string>().rfind("tc0: high ", 0), 0u);
  EXPECT_EQ(acquire.wait_exit(15s), 0);
  std::ifstream in(err);
  const std::string stderr_text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(stderr_text.find("adam: tc0: high "), std::string::npos) << "acquire reports the alarm on stderr";
}

TEST_F(AcquireLive, APortInUseIsSaidAndTheRecordingGoesOnWithoutThePage) {
  const auto view = start_view();  // another viewer holds the port
  const auto result = testing::run_command(acquire_command("1s"), 20);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("live view not started, recording goes on without it"), std::string::npos)
      << result.output;
  // The option named is the one acquire has: --live, not view's --listen.
  EXPECT_NE(result.output.find("cannot listen on 127.0.0.1:" + std::to_string(port_) +
                               ": the port is in use (choose another with --live HOST:PORT)"),
            std::string::npos)
      << result.output;
  EXPECT_FALSE(storage::RunStore::open(dir_ / "logged").read_samples(1).empty());
}

}  // namespace
}  // namespace bosfuse
