// The command line as a user runs it: the bosfuse executable against a
// simulated module on loopback.

#include <gtest/gtest.h>

#include <fstream>
#include <regex>

#include "app/test_streams.h"
#include "sim/modbus_server.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace std::chrono_literals;

// A name that fails to resolve on this machine without a query to any DNS
// server: the resolver refuses a label over 63 characters before sending.
constexpr const char* kUnresolvableHost =
    "unresolvable-because-this-first-label-is-longer-than-sixty-three-chars.invalid";

using testing::kBosfuse;

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
  testing::StreamsResult streams(const std::string& args) {
    return testing::run_with_streams(kBosfuse + " " + args, dir_.path());
  }

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
  EXPECT_EQ(csv.output.substr(0, csv.output.find('\n')), "time_utc,t_s,time_scale,tc0 [degC],tc1 [degC]");
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
  EXPECT_NE(refused.output.find("already holds a run (" + run_dir() +
                                "), which a new run never overwrites; choose another folder, or append to that run "
                                "where the command can (acquire --append)"),
            std::string::npos)
      << refused.output;
  // The experiment file given where --live expects HOST:PORT is named, not served on.
  const auto live = bosfuse("acquire --live " + experiment_ + " --out " + (dir_ / "live-run").string());
  EXPECT_EQ(live.exit_code, 105) << live.output;
  EXPECT_NE(live.output.find("--live takes HOST:PORT (e.g. 127.0.0.1:"), std::string::npos) << live.output;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "live-run"));
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
  std::string text = experiment_text(server_->port());
  text.replace(text.find("input = 0\n"), 10, "input = 0\nresolution = 0\n");
  write(experiment_, text);
  const auto zero = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 1s");
  EXPECT_NE(zero.exit_code, 0);
  EXPECT_NE(zero.output.find("exp.toml:14: devices[0].channels[0].resolution: expected a step in the channel's unit"),
            std::string::npos)
      << zero.output;
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

// Issue 31: a logger user without a camera goes acquire → process →
// report, through a simulated module cooling fast enough (k = 0.5 1/s) for
// a fit within the 3 s of the record; the report has the fits and no BOS.
TEST_F(Cli, AThermocoupleOnlyRunGoesFromAcquireThroughProcessToReport) {
  sim::SimulatedModule module;
  module.signal.k_per_s = 0.5;
  module.signal.noise_c = 0.05;
  acquisition::ModbusEndpoint endpoint;
  endpoint.port = 0;
  sim::ModbusSimServer fast(sim::module_server_options(module, endpoint));
  fast.start();
  // tc0 states its resolution (the file's wins over the driver's step).
  std::string text = experiment_text(fast.port());
  text.replace(text.find("input = 0\n"), 10, "input = 0\nresolution = 0.1\n");
  write(experiment_, text);
  const auto acquired = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 3s");
  ASSERT_EQ(acquired.exit_code, 0) << acquired.output;
  const auto channels = storage::RunStore::open(run_dir()).channels();
  ASSERT_EQ(channels.size(), 2u);
  EXPECT_EQ(channels[0].resolution, 0.1);
  EXPECT_NEAR(channels[1].resolution.value_or(0), 1370.0 / 65535, 1e-12) << "the adam-6018's register step";
  const auto exported = streams("export " + run_dir() + " --csv");
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const std::string row = exported.out.substr(exported.out.find('\n') + 1, 200);
  EXPECT_TRUE(std::regex_search(row, std::regex("^[^,]+,[^,]+,[^,]+,[0-9]+\\.[0-9],[0-9]+\\.[0-9][0-9]\n")))
      << "tc0 at 0.1 °C, tc1 at 0.02 °C: " << row;
  const auto processed = streams("process " + run_dir());
  ASSERT_EQ(processed.exit_code, 0) << processed.err;
  EXPECT_EQ(processed.out, "");
  const auto reported = streams("report " + run_dir() + " -o " + (dir_ / "report").string());
  ASSERT_EQ(reported.exit_code, 0) << reported.err;
  std::ifstream html_file(dir_ / "report" / "report.html");
  const std::string html((std::istreambuf_iterator<char>(html_file)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("Thermocouples only: the run has no frames"), std::string::npos);
  EXPECT_NE(html.find("Cooling curves"), std::string::npos);
  const auto fits = storage::ProcessingStore(run_dir()).fits();
  EXPECT_EQ(fits.size(), 2u) << "one fit per thermocouple";
}

// Command-line conventions (issue 11): data on stdout, every message on
// stderr; a typo of a subcommand is named; --quiet silences the chatter;
// a run that lacks a device's data says so and exits with its own status.
TEST_F(Cli, DataGoesToStdoutAndMessagesToStderr) {
  // acquire and replay make a run folder the user named: their summaries
  // are for the person watching, on stderr (issue 31).
  const auto acquired = streams("acquire " + experiment_ + " --out " + run_dir() + " --duration 300ms");
  ASSERT_EQ(acquired.exit_code, 0) << acquired.err;
  EXPECT_EQ(acquired.out, "");
  EXPECT_NE(acquired.err.find("run store: " + run_dir() + "/run.sqlite"), std::string::npos) << acquired.err;
  const auto replayed = streams("replay " + run_dir() + " --out " + (dir_ / "replayed").string() + " --speed 10");
  ASSERT_EQ(replayed.exit_code, 0) << replayed.err;
  EXPECT_EQ(replayed.out, "");
  EXPECT_NE(replayed.err.find("replayed run: " + (dir_ / "replayed").string()), std::string::npos) << replayed.err;
  // The module's register step is stored as the channels' resolution (a
  // type-K adam-6018 input: 1370 °C over 65535 counts), and a replay keeps it.
  for (const std::filesystem::path& run : {std::filesystem::path(run_dir()), dir_ / "replayed"}) {
    for (const auto& channel : storage::RunStore::open(run).channels()) {
      ASSERT_TRUE(channel.resolution) << run << " " << channel.name;
      EXPECT_NEAR(*channel.resolution, 1370.0 / 65535, 1e-12) << run << " " << channel.name;
    }
  }
  // Standard output into a file, standard error into the captured output.
  const auto stdout_to = [&](const std::string& args, const std::string& file) {
    return testing::run_command("sh -c '" + kBosfuse + " " + args + " > " + (dir_ / file).string() + "'");
  };
  const auto first_line = [&](const std::string& file) {
    std::ifstream in(dir_ / file);
    std::string line;
    std::getline(in, line);
    return line;
  };
  const auto exported = stdout_to("export " + run_dir() + " --csv", "out.csv");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  EXPECT_EQ(first_line("out.csv"), "time_utc,t_s,time_scale,tc0 [degC],tc1 [degC]") << "something other than data on stdout";
  const auto failed = stdout_to("runs " + (dir_ / "nothing-here").string(), "none.txt");
  EXPECT_NE(failed.exit_code, 0);
  EXPECT_NE(failed.output.find("no such folder"), std::string::npos) << "the error is not on stderr";
  EXPECT_EQ(first_line("none.txt"), "") << "the error went to stdout";
}

// Every command that reads a run tells a missing folder from a folder
// that holds no run, and reads `RUN/run.sqlite` as RUN.
TEST_F(Cli, AMissingFolderIsNamedAndAFileInsideARunIsItsRun) {
  ASSERT_EQ(bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 300ms").exit_code, 0);
  const std::string missing = (dir_ / "no-such-run").string();
  for (const char* command : {"runs", "export", "process", "report", "calibrate", "view", "replay", "mark"}) {
    const std::string extra = std::string(command) == "mark" ? " 'heater off' --at +0.1s" : "";
    const auto result = bosfuse(std::string(command) + " " + missing + extra);
    EXPECT_EQ(result.exit_code, 105) << command << ": " << result.output;
    EXPECT_NE(result.output.find("no such folder: '" + missing + "'"), std::string::npos) << command << ": " << result.output;
  }
  const auto listed = bosfuse("runs " + run_dir() + "/run.sqlite");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_NE(listed.output.find("tc1"), std::string::npos) << "the run of its file is described: " << listed.output;
  const auto exported = bosfuse("export " + run_dir() + "/run.sqlite --csv");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  EXPECT_EQ(exported.output.substr(0, exported.output.find('\n')), "time_utc,t_s,time_scale,tc0 [degC],tc1 [degC]");
  write((dir_ / "notes.txt").string(), "x");
  const auto file = bosfuse("runs " + (dir_ / "notes.txt").string());
  EXPECT_EQ(file.exit_code, 105) << file.output;
  EXPECT_NE(file.output.find("is a file, not a run folder"), std::string::npos) << file.output;
}

TEST_F(Cli, AnUnknownSubcommandIsNamed) {
  const auto result = bosfuse("acquier " + experiment_);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.output.find("unknown subcommand 'acquier' (one of: "), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("acquire"), std::string::npos) << result.output;
}

// A typo is named at the level it is made, with the nearest name (issue 31,
// item 7), before anything runs; CLI11's code for arguments it cannot place.
TEST_F(Cli, ATypoOfANestedSubcommandOrAnOptionIsNamedWithTheNearestName) {
  constexpr int kExtrasError = 109;
  const auto nested = bosfuse("sim modbsu --port 0");
  EXPECT_EQ(nested.exit_code, kExtrasError) << nested.output;
  EXPECT_NE(nested.output.find(
                "unknown subcommand 'modbsu' of 'bosfuse sim' (one of: modbus, camera); did you mean 'modbus'?"),
            std::string::npos)
      << nested.output;
  const auto option = bosfuse("process " + run_dir() + " --windw 32");
  EXPECT_EQ(option.exit_code, kExtrasError) << option.output;
  EXPECT_NE(option.output.find("unknown option '--windw' of 'bosfuse process'; did you mean '--window'?"),
            std::string::npos)
      << option.output;
  const auto root = bosfuse("--qiet runs " + run_dir());
  EXPECT_EQ(root.exit_code, kExtrasError) << root.output;
  EXPECT_NE(root.output.find("unknown option '--qiet' of 'bosfuse'; did you mean '--quiet'?"), std::string::npos)
      << root.output;
  // Far from every name: named, nothing suggested.
  const auto far = bosfuse("process " + run_dir() + " --colour-of-the-sky blue");
  EXPECT_NE(far.output.find("unknown option '--colour-of-the-sky' of 'bosfuse process'"), std::string::npos)
      << far.output;
  EXPECT_EQ(far.output.find("did you mean"), std::string::npos) << far.output;
  // Values and root options before the subcommand are not taken for names.
  const auto values = bosfuse("-q sim modbus --port 0 --duration 100ms");
  EXPECT_EQ(values.exit_code, 0) << values.output;
}

TEST_F(Cli, QuietLeavesOnlyWarningsAndADurationWithoutUnitSaysWhatItAssumed) {
  const auto chatty = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 0.3");
  ASSERT_EQ(chatty.exit_code, 0) << chatty.output;
  EXPECT_NE(chatty.output.find("[info] logging 1 devices"), std::string::npos) << chatty.output;
  EXPECT_NE(chatty.output.find("duration '0.3' has no unit: taken as 0.3 s"), std::string::npos) << chatty.output;
  const auto quiet = bosfuse("acquire " + experiment_ + " --out " + (dir_ / "run2").string() + " --duration 300ms -q");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("[info]"), std::string::npos) << quiet.output;
}

TEST_F(Cli, ARunWhoseDeviceDeliveredNothingEndsWithAWarningAndItsOwnStatus) {
  write(experiment_, experiment_text(testing::unused_loopback_port()));
  const auto result = bosfuse("acquire " + experiment_ + " --out " + run_dir() + " --duration 500ms");
  EXPECT_EQ(result.exit_code, 4) << result.output;
  EXPECT_NE(result.output.find("the run is recorded, but device adam delivered no readings"), std::string::npos)
      << result.output;
  EXPECT_EQ(storage::RunStore::open(run_dir()).run().status, storage::RunStatus::kComplete);
}

TEST_F(Cli, RunsOfAFolderListsTheRunsBelowIt) {
  ASSERT_EQ(bosfuse("acquire " + experiment_ + " --out " + (dir_ / "day1/a").string() + " --duration 300ms").exit_code,
            0);
  ASSERT_EQ(bosfuse("acquire " + experiment_ + " --out " + (dir_ / "day2/b").string() + " --duration 300ms").exit_code,
            0);
  const auto listed = bosfuse("runs " + dir_.path().string());
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_NE(listed.output.find("day1/a "), std::string::npos) << listed.output;
  EXPECT_NE(listed.output.find("day2/b "), std::string::npos) << listed.output;
  EXPECT_LT(listed.output.find("day1/a "), listed.output.find("day2/b ")) << listed.output;
  EXPECT_NE(listed.output.find("complete"), std::string::npos) << listed.output;
}

TEST_F(Cli, EverySubcommandHasHelp) {
  for (const char* sub : {"acquire", "runs", "export", "demo", "sim modbus", "replay", "evaluate", "quality",
                          "background", "bench", "fit", "process", "calibrate", "report"}) {
    const auto help = bosfuse(std::string(sub) + " --help");
    EXPECT_EQ(help.exit_code, 0) << sub;
    EXPECT_NE(help.output.find("Usage"), std::string::npos) << sub;
  }
}

// A usage mistake exits with CLI11's code in every subcommand, as the README
// says: 109 for an unknown option (named with its command), 106 for a missing
// argument, 105 for evaluate's missing pair (a check of its own).
TEST_F(Cli, UsageMistakesExitWithCli11sCodesInEverySubcommand) {
  for (const char* sub : {"acquire", "runs", "export", "demo", "sim", "sim modbus", "replay", "evaluate", "quality",
                          "background", "bench", "fit", "process", "calibrate", "report", "mark", "view"}) {
    const auto unknown = streams(std::string(sub) + " --no-such-option");
    EXPECT_EQ(unknown.exit_code, 109) << sub << ": " << unknown.err;
    EXPECT_NE(unknown.err.find("unknown option '--no-such-option' of 'bosfuse " + std::string(sub) + "'"),
              std::string::npos)
        << unknown.err;
    EXPECT_EQ(unknown.out, "") << sub;
  }
  for (const auto& [sub, message] : std::vector<std::pair<std::string, std::string>>{
           {"acquire", "experiment is required"}, {"runs", "run is required"}, {"export", "run is required"},
           {"process", "run is required"}, {"mark", "run is required"}, {"fit", "data is required"},
           {"quality", "image is required"}, {"background", "--out is required"}, {"sim", "A subcommand is required"}}) {
    const auto missing = streams(sub);
    EXPECT_EQ(missing.exit_code, 106) << sub << ": " << missing.err;
    EXPECT_EQ(missing.err.rfind(message, 0), 0u) << sub << ": " << missing.err;
  }
  const auto evaluate = streams("evaluate");
  EXPECT_EQ(evaluate.exit_code, 105) << evaluate.err;
  EXPECT_EQ(evaluate.err.rfind("evaluate needs REF MEAS (an image pair)", 0), 0u) << evaluate.err;
}

// Every subcommand spells an option the same way: the output is -o/--out
// (export's --output and evaluate's --png are gone), a JSON output is
// --json FILE|- (quality's --json was a flag), an image of a map is --map.
TEST_F(Cli, OneSpellingPerOptionAcrossSubcommands) {
  const std::vector<std::string> subcommands{"acquire", "runs",     "export",    "demo",       "sim modbus",
                                             "replay",  "evaluate", "quality",   "background", "bench",
                                             "fit",     "process",  "calibrate", "report"};
  for (const auto& sub : subcommands) {
    const auto help = streams(sub + " --help");
    ASSERT_EQ(help.exit_code, 0) << sub;
    for (const char* gone : {"--output", "--png"}) {
      EXPECT_EQ(help.out.find(gone), std::string::npos) << sub << " has " << gone << ":\n" << help.out;
    }
    if (const auto out = help.out.find("--out "); out != std::string::npos) {
      EXPECT_EQ(help.out.substr(out - 3, 9), "-o,--out ") << sub;
    }
    if (const auto json = help.out.find("--json"); json != std::string::npos) {
      EXPECT_EQ(help.out.substr(json, 11), "--json TEXT") << sub << ": --json takes FILE or -";
    }
  }
}

TEST_F(Cli, ARunFolderCannotBeStandardOutput) {
  const auto refused = streams("acquire " + experiment_ + " -o - --duration 300ms");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("--out cannot be standard output ('-'): a run is a folder"), std::string::npos)
      << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "-"));
  EXPECT_EQ(server_->requests_answered(), 0) << "refused before any device was polled";
}

// Piped or logged, progress is plain lines on stderr flushed as they
// happen; the table is the only thing on stdout.
TEST_F(Cli, BenchShowsProgressOnStderrAndTheTableOnStdout) {
  const auto bench = streams("bench --size 64");
  ASSERT_EQ(bench.exit_code, 0) << bench.err;
  EXPECT_TRUE(bench.out.starts_with("synthetic 64x64 pairs")) << bench.out;
  EXPECT_NE(bench.out.find("\nflow-farneback "), std::string::npos) << bench.out;
  EXPECT_NE(bench.out.find("  IW  8: "), std::string::npos) << bench.out;
  EXPECT_EQ(bench.out.find("ETA"), std::string::npos) << "progress on stdout: " << bench.out;
  EXPECT_EQ(std::count(bench.err.begin(), bench.err.end(), '\n'), 12) << bench.err;
  EXPECT_TRUE(bench.err.starts_with("0/11   0%  0:00 elapsed  ETA —  xcorr, IW 32, 1 pass\n")) << bench.err;
  EXPECT_NE(bench.err.find("\n11/11 100%  "), std::string::npos) << bench.err;
  EXPECT_EQ(bench.err.find('\r'), std::string::npos) << "no carriage returns in a log";
  EXPECT_EQ(bench.err.find('\x1b'), std::string::npos) << "no escape codes in a log";

  const auto quiet = streams("bench --size 64 -q");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "") << "--quiet: no progress";
  EXPECT_TRUE(quiet.out.starts_with("synthetic 64x64 pairs")) << quiet.out;
}

// On a terminal (a pseudo-terminal from util-linux's script) the progress
// is one line rewritten in place.
TEST_F(Cli, BenchProgressIsOneLineInPlaceOnATerminal) {
  if (testing::run_command("sh -c 'command -v script'").exit_code != 0) GTEST_SKIP() << "no script(1)";
  const auto tty = testing::run_with_streams(
      "script -qec '" + kBosfuse + " bench --size 64 > " + (dir_ / "table.txt").string() + "' /dev/null", dir_.path());
  ASSERT_EQ(tty.exit_code, 0) << tty.out << tty.err;
  EXPECT_NE(tty.out.find("\r0/11   0%"), std::string::npos) << tty.out;
  EXPECT_NE(tty.out.find("\x1b[K\r1/11   9%"), std::string::npos) << tty.out;
  EXPECT_NE(tty.out.find("\r11/11 100%"), std::string::npos) << tty.out;
  EXPECT_EQ(std::count(tty.out.begin(), tty.out.end(), '\n'), 1) << "one line, ended once: " << tty.out;
  std::ifstream table(dir_ / "table.txt");
  std::string first;
  std::getline(table, first);
  EXPECT_EQ(first.rfind("synthetic 64x64 pairs", 0), 0u) << first;
}

// A server has no data: where it serves and what it answered are messages.
TEST_F(Cli, SimModbusSpeaksOnStderr) {
  const auto served = streams("sim modbus --port 0 --duration 200ms --update-period 100ms");
  ASSERT_EQ(served.exit_code, 0) << served.err;
  EXPECT_EQ(served.out, "");
  EXPECT_NE(served.err.find("inputs serving on 127.0.0.1:"), std::string::npos) << served.err;
  EXPECT_NE(served.err.find("answered 0 requests"), std::string::npos) << served.err;
  const auto bad = streams("sim modbus --port 0 --duration 200ms --update-period soon");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("cannot read duration 'soon'"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace bosfuse
