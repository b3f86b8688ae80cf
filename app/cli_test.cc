// The command line as a user runs it: the bosfuse executable against a
// simulated module on loopback.

#include <gtest/gtest.h>

#include <fstream>

#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace std::chrono_literals;

// A name that fails to resolve on this machine without a query to any DNS
// server: the resolver refuses a label over 63 characters before sending.
constexpr const char* kUnresolvableHost =
    "unresolvable-because-this-first-label-is-longer-than-sixty-three-chars.invalid";

const std::string kBosfuse = std::string(BOSFUSE_BINARY_DIR) + "/bosfuse";

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    acquisition::ModbusEndpoint endpoint;
    endpoint.port = 0;
    server_ = std::make_unique<sim::ModbusSimServer>(sim::module_server_options({}, endpoint));
    server_->start();
    experiment_ = (dir_ / "exp.toml").string();
    write(experiment_, experiment_text(server_->port()));
  }

  static std::string experiment_text(int port) {
    return "[run]\nname = \"cli\"\n\n[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\nhost = \"127.0.0.1\"\n"
           "port = " +
           std::to_string(port) +
           "\npoll_period_s = 0.1\n\n"
           "[[devices.channels]]\nname = \"tc0\"\ninput = 0\n\n[[devices.channels]]\nname = \"tc1\"\ninput = 1\n";
  }
  static void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
  std::string run_dir() const { return (dir_ / "run").string(); }
  testing::CommandResult bosfuse(const std::string& args) { return testing::run_command(kBosfuse + " " + args); }

  testing::TempDir dir_;
  std::unique_ptr<sim::ModbusSimServer> server_;
  std::string experiment_;
};

TEST_F(Cli, AcquireThenSummariseAndExport) {
  const auto acquired = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 1s");
  ASSERT_EQ(acquired.exit_code, 0) << acquired.output;
  EXPECT_NE(acquired.output.find("run.sqlite"), std::string::npos) << "it must say where the data went";

  const auto summary = bosfuse("runs " + run_dir());
  ASSERT_EQ(summary.exit_code, 0) << summary.output;
  EXPECT_NE(summary.output.find("complete"), std::string::npos) << summary.output;
  EXPECT_NE(summary.output.find("tc1"), std::string::npos) << summary.output;

  const auto csv = bosfuse("export " + run_dir() + " --csv");
  ASSERT_EQ(csv.exit_code, 0) << csv.output;
  EXPECT_EQ(csv.output.substr(0, csv.output.find('\n')), "time_utc,t_s,tc0 [degC],tc1 [degC]");
  const auto rows = std::count(csv.output.begin(), csv.output.end(), '\n') - 1;
  const auto store = storage::RunStore::open(run_dir());
  EXPECT_EQ(rows, static_cast<long>(store.read_samples(store.channels()[0].id).size()));
  EXPECT_GE(rows, 8);
}

TEST_F(Cli, AFolderHoldingARunIsRefusedUnlessAppending) {
  ASSERT_EQ(bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 300ms").exit_code, 0);
  const std::size_t first = storage::RunStore::open(run_dir()).channel_summaries()[0].sample_count;
  const auto refused = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 300ms");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("already holds a run"), std::string::npos) << refused.output;
  EXPECT_EQ(storage::RunStore::open(run_dir()).channel_summaries()[0].sample_count, first) << "refusal touched the run";
  const auto appended = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 300ms --append");
  ASSERT_EQ(appended.exit_code, 0) << appended.output;
  EXPECT_GT(storage::RunStore::open(run_dir()).channel_summaries()[0].sample_count, first);
}

TEST_F(Cli, CtrlCEndsTheRunCleanlyWithEverythingCommitted) {
  testing::BackgroundProcess acquire({kBosfuse, "acquire", experiment_, "--out", run_dir()});
  ASSERT_TRUE(testing::wait_for([&] { return server_->requests_answered() >= 5; }, 10s));
  acquire.send_signal(SIGINT);
  ASSERT_EQ(acquire.wait_exit(10s), 0);
  const auto store = storage::RunStore::open(run_dir());
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
  // Every poll the module answered before the stop is in the store.
  const auto samples = store.read_samples(store.channels()[0].id);
  EXPECT_EQ(static_cast<std::int64_t>(samples.size()), server_->requests_answered());
}

TEST_F(Cli, MalformedExperimentNamesTheKeyAndLine) {
  write(experiment_,
        "[run]\nname = \"x\"\n\n[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\nhost = \"h\"\n"
        "port = \"502\"\n");
  const auto result = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 1s");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.output.find("exp.toml:8: devices[0].port: expected an integer"), std::string::npos) << result.output;
  EXPECT_FALSE(storage::RunStore::holds_run(run_dir())) << "a bad configuration must not start a run";
}

// libmodbus's plain TCP context takes an IPv4 address only: a host name
// used to pass validation, was retried for the whole run and the run ended
// "complete" with no samples and exit 0.
TEST_F(Cli, HostNamesAreResolvedAndAnUnresolvableOneStopsTheStart) {
  std::string text = experiment_text(server_->port());
  const auto host = text.find("127.0.0.1");
  write(experiment_, std::string(text).replace(host, 9, kUnresolvableHost));
  const auto refused = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 1s");
  EXPECT_NE(refused.exit_code, 0) << refused.output;
  EXPECT_NE(refused.output.find("exp.toml:7: devices[0].host: device \"adam\": cannot resolve host \"" +
                                std::string(kUnresolvableHost) + "\""),
            std::string::npos)
      << refused.output;
  EXPECT_FALSE(storage::RunStore::holds_run(run_dir())) << "an unreachable name must not start a run";

  write(experiment_, text.replace(host, 9, "localhost"));
  const auto acquired = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 1s");
  ASSERT_EQ(acquired.exit_code, 0) << acquired.output;
  const auto store = storage::RunStore::open(run_dir());
  const auto samples = store.read_samples(store.channels()[0].id);
  ASSERT_GE(samples.size(), 5u) << acquired.output;
  for (const auto& s : samples) EXPECT_EQ(s.status, storage::SampleStatus::kOk);
}

TEST_F(Cli, EverySubcommandHasHelp) {
  for (const char* sub : {"acquire", "runs", "export", "demo", "sim modbus", "replay", "evaluate", "quality",
                          "background", "bench", "fit", "process", "calibrate", "report"}) {
    const auto help = bosfuse(std::string(sub) + " --help");
    EXPECT_EQ(help.exit_code, 0) << sub;
    EXPECT_NE(help.output.find("Usage"), std::string::npos) << sub;
  }
}

}  // namespace
}  // namespace bosfuse
