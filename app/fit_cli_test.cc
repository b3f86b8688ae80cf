// `bosfuse fit` as a user runs it: CSV files in, a printed fit and JSON out.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "acquisition/clock.h"
#include "app/test_streams.h"
#include "storage/run_store.h"
#include "tests/support/cooling_curve.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using testing::kBosfuse;

class FitCli : public ::testing::Test {
 protected:
  testing::CommandResult bosfuse(const std::string& args) { return testing::run_command(kBosfuse + " " + args); }
  testing::StreamsResult streams(const std::string& args) {
    return testing::run_with_streams(kBosfuse + " " + args, dir_.path());
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
  nlohmann::json read_json(const std::string& name) const {
    std::ifstream in(path(name));
    return nlohmann::json::parse(in);
  }

  // t_s,T with the curve sampled every second plus noise.
  std::string seconds_csv(const testing::CoolingCurve& curve, std::size_t n, double sigma_c, unsigned seed) const {
    const auto r = testing::sample_cooling(curve, n, 1.0, sigma_c, seed);
    std::string text = "t_s,T\n";
    for (std::size_t i = 0; i < n; ++i) {
      text += std::to_string(r.time_s[i]) + "," + std::to_string(r.temperature_c[i]) + "\n";
    }
    return text;
  }

  testing::TempDir dir_;
};

TEST_F(FitCli, FitsASecondsCsvAndWritesJson) {
  const testing::CoolingCurve curve{22.0, 75.0, 0.012};
  write("run.csv", seconds_csv(curve, 400, 0.05, 1));
  const auto result = bosfuse("fit " + path("run.csv") + " --json " + path("fit.json"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("T_amb"), std::string::npos) << result.output;
  const auto j = read_json("fit.json");
  EXPECT_TRUE(j.at("ok").get<bool>());
  const auto& k = j.at("parameters").at("k_per_s");
  EXPECT_NEAR(k.at("value").get<double>(), curve.k_per_s, 4 * k.at("std_error").get<double>());
  EXPECT_LT(k.at("interval").at("low").get<double>(), k.at("value").get<double>());
  EXPECT_EQ(j.at("diagnostics").at("points_used").get<int>(), 400);
  EXPECT_EQ(j.at("input").at("time_column"), "t_s");
  EXPECT_EQ(j.at("input").at("temperature_column"), "T");
  EXPECT_NEAR(j.at("parameters").at("tau_s").at("value").get<double>() * k.at("value").get<double>(), 1.0, 1e-9);
}

// The layout `bosfuse export --csv` writes: ISO-8601 UTC and seconds since
// the run start, one column per channel, empty cells where a channel has no
// sample, quoted names when they need it.
TEST_F(FitCli, FitsAnExportedRunByIsoTimeOrBySeconds) {
  const testing::CoolingCurve curve{21.5, 64.0, 0.02};
  const auto r = testing::sample_cooling(curve, 300, 0.5, 0.03, 2);
  const std::int64_t start_ns = 1'795'000'000'123'456'000;  // 2026-11-18, epoch scale
  std::string text = "time_utc,t_s,tc0 [degC],\"tc1, top [degC]\"\n";
  for (std::size_t i = 0; i < r.time_s.size(); ++i) {
    const auto t_ns = start_ns + static_cast<std::int64_t>(std::llround(r.time_s[i] * 1e9));
    const std::string other = i % 50 == 3 ? "" : "20.0";  // a dropped poll of the other channel
    text += acquisition::format_iso8601_utc(t_ns, 6) + "," + std::to_string(r.time_s[i]) + "," + other + "," +
            std::to_string(r.temperature_c[i]) + "\n";
  }
  write("export.csv", text);
  const auto by_iso =
      bosfuse("fit " + path("export.csv") + " --time-column time_utc --temperature-column 'tc1, top [degC]' --json " +
              path("iso.json"));
  ASSERT_EQ(by_iso.exit_code, 0) << by_iso.output;
  const auto iso = read_json("iso.json");
  EXPECT_EQ(iso.at("origin_time_utc"), acquisition::format_iso8601_utc(start_ns, 6));
  const double k_iso = iso.at("parameters").at("k_per_s").at("value");
  EXPECT_NEAR(k_iso, curve.k_per_s, 4 * iso.at("parameters").at("k_per_s").at("std_error").get<double>());

  const auto by_seconds =
      bosfuse("fit " + path("export.csv") + " --temperature-column 'tc1, top [degC]' --json " + path("s.json"));
  ASSERT_EQ(by_seconds.exit_code, 0) << by_seconds.output;
  EXPECT_EQ(read_json("s.json").at("input").at("time_column"), "t_s") << "t_s is the default time column";
  EXPECT_NEAR(read_json("s.json").at("parameters").at("k_per_s").at("value").get<double>(), k_iso, 1e-6 * k_iso);

  const auto ambiguous = bosfuse("fit " + path("export.csv"));
  EXPECT_NE(ambiguous.exit_code, 0);
  EXPECT_NE(ambiguous.output.find("choose one with --temperature-column"), std::string::npos) << ambiguous.output;

  const auto other = bosfuse("fit " + path("export.csv") + " --temperature-column 'tc0 [degC]'");
  EXPECT_NE(other.exit_code, 0) << "a constant channel has no decay: " << other.output;
  EXPECT_NE(other.output.find("6 rows with an empty cell skipped"), std::string::npos) << other.output;
}

// A channel named like a formula went into the export as-is, so a
// spreadsheet opening it ran the command.
// Found by fuzzing: a year far from 1970 overflowed int64 nanoseconds.
TEST_F(FitCli, ATimeWithAnImplausibleYearIsAnErrorNamingIt) {
  write("far.csv", "time_utc,T\n2026-11-23T09:00:00Z,50\n7381-01-01T00:00:00Z,49\n");
  const auto result = bosfuse("fit " + path("far.csv") + " --temperature-column T");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.output.find("7381-01-01T00:00:00Z"), std::string::npos) << result.output;
}

TEST_F(FitCli, AFormulaNamedChannelIsExportedInertAndFitsByItsName) {
  const std::string name = "=cmd|' /C calc'!A0";
  const testing::CoolingCurve curve{21.5, 64.0, 0.02};
  const auto r = testing::sample_cooling(curve, 200, 1.0, 0.03, 5);
  const std::int64_t start_ns = 1'795'000'000'000'000'000;
  {
    auto store = storage::RunStore::create(dir_ / "run", {0, "csv", start_ns, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                           storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "generic", "127.0.0.1:502"});
    const auto formula = store.add_channel({0, device, name, "thermocouple", "degC", "K", {}, {}});
    const auto cold = store.add_channel({0, device, "cold", "thermocouple", "degC", "K", {}, {}});
    std::vector<storage::Sample> samples;
    for (std::size_t i = 0; i < r.time_s.size(); ++i) {
      const auto t_ns = start_ns + static_cast<std::int64_t>(std::llround(r.time_s[i] * 1e9));
      samples.push_back({formula, t_ns, {}, r.temperature_c[i], {}, storage::SampleStatus::kOk});
      samples.push_back({cold, t_ns, {}, -3.5, {}, storage::SampleStatus::kOk});
    }
    store.write_samples(samples);
    store.finish(storage::RunStatus::kComplete, start_ns + 300'000'000'000);
  }
  const auto exported = bosfuse("export " + path("run") + " --csv -o " + path("export.csv"));
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  std::ifstream in(path("export.csv"));
  std::string header, first;
  std::getline(in, header);
  std::getline(in, first);
  EXPECT_EQ(header, "time_utc,t_s,time_scale,\"'=cmd|' /C calc'!A0 [degC]\",cold [degC]");
  EXPECT_TRUE(first.ends_with(",-3.5")) << "a negative number is a number, not a formula: " << first;

  // Shell-quoted: the name holds single quotes, a pipe and an exclamation mark.
  const auto fitted = bosfuse("fit " + path("export.csv") +
                              " --temperature-column '=cmd|'\\'' /C calc'\\''!A0 [degC]' --json " + path("fit.json"));
  ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
  const auto j = read_json("fit.json");
  EXPECT_EQ(j.at("input").at("temperature_column"), name + " [degC]");
  EXPECT_NEAR(j.at("parameters").at("k_per_s").at("value").get<double>(), curve.k_per_s, 0.002);
}

// A run recorded 16× faster than the experiment (the demo): its UTC column
// is the recording's clock, so a fit by it must use the export's time_scale
// or k comes out 16× too large (issue 31: 0.0963 against 0.00604 1/s).
TEST_F(FitCli, AScaledRunsExportFitsInExperimentTimeByEitherTimeColumn) {
  constexpr double kScale = 16;
  const testing::CoolingCurve curve{21.5, 64.0, 0.006};
  const auto r = testing::sample_cooling(curve, 300, 1.0, 0.03, 7);
  const std::int64_t start_ns = 1'795'000'000'000'000'000;
  {
    auto store = storage::RunStore::create(
        dir_ / "run", {0, "demo", start_ns, {}, "", storage::RunStatus::kRunning, kScale, std::nullopt},
        storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "generic", "127.0.0.1:502"});
    const auto channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    std::vector<storage::Sample> samples;
    for (std::size_t i = 0; i < r.time_s.size(); ++i) {
      const auto t_ns = start_ns + static_cast<std::int64_t>(std::llround(r.time_s[i] / kScale * 1e9));
      samples.push_back({channel, t_ns, {}, r.temperature_c[i], {}, storage::SampleStatus::kOk});
    }
    store.write_samples(samples);
    store.finish(storage::RunStatus::kComplete, start_ns + 20'000'000'000);
  }
  ASSERT_EQ(bosfuse("export " + path("run") + " --csv -o " + path("export.csv")).exit_code, 0);
  for (const std::string column : {"t_s", "time_utc"}) {
    const auto fitted = bosfuse("fit " + path("export.csv") + " --time-column " + column + " --json " + path("f.json"));
    ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
    const auto k = read_json("f.json").at("parameters").at("k_per_s");
    EXPECT_NEAR(k.at("value").get<double>(), curve.k_per_s, 4 * k.at("std_error").get<double>()) << column;
    if (column == "time_utc") {
      EXPECT_NE(fitted.output.find("the recorded times × 16, the file's time_scale"), std::string::npos)
          << fitted.output;
      EXPECT_EQ(read_json("f.json").at("input").at("time_scale").get<double>(), kScale);
    }
  }
  write("mixed.csv", "time_utc,time_scale,T\n2026-11-23T09:00:00Z,16,50\n2026-11-23T09:00:01Z,1,49\n");
  const auto mixed = bosfuse("fit " + path("mixed.csv") + " --time-column time_utc");
  EXPECT_NE(mixed.exit_code, 0);
  EXPECT_NE(mixed.output.find("line 3: time_scale 1 differs from 16"), std::string::npos) << mixed.output;
}

TEST_F(FitCli, AmbientLossAndSigmaOptionsReachTheFit) {
  const testing::CoolingCurve curve{22.0, 75.0, 0.012};
  write("run.csv", seconds_csv(curve, 300, 0.05, 3));
  ASSERT_EQ(bosfuse("fit " + path("run.csv") + " --ambient fixed:22 --json " + path("fixed.json")).exit_code, 0);
  const auto fixed = read_json("fixed.json");
  EXPECT_TRUE(fixed.at("parameters").at("T_amb_c").at("fixed").get<bool>());
  EXPECT_EQ(fixed.at("diagnostics").at("parameters").get<int>(), 2);

  ASSERT_EQ(bosfuse("fit " + path("run.csv") + " --ambient prior:22,0.05 --json " + path("prior.json")).exit_code, 0);
  EXPECT_EQ(read_json("prior.json").at("diagnostics").at("dof").get<double>(), 298.0);

  ASSERT_EQ(bosfuse("fit " + path("run.csv") + " --sigma 0.05 --loss huber:0.1 --json " + path("s.json")).exit_code, 0);
  const auto sigma = read_json("s.json");
  EXPECT_NEAR(sigma.at("diagnostics").at("reduced_chi_square").get<double>(), 1.0, 0.3);
  EXPECT_NE(sigma.at("uncertainty").get<std::string>().find("absolute"), std::string::npos);

  for (const char* bad : {"--ambient fixed:", "--ambient prior:22", "--loss huber", "--loss tukey:1", "--sigma -1"}) {
    const auto refused = bosfuse("fit " + path("run.csv") + " " + bad);
    EXPECT_NE(refused.exit_code, 0) << bad;
    EXPECT_TRUE(refused.output.find("expected") != std::string::npos ||
                refused.output.find("must be positive") != std::string::npos)
        << bad << ": " << refused.output;
  }
}

TEST_F(FitCli, AnUntrustworthyFitIsAnErrorAndTheJsonSaysWhy) {
  const testing::CoolingCurve flat{22.0, 22.0, 0.01};
  write("flat.csv", seconds_csv(flat, 200, 0.05, 4));
  const auto result = bosfuse("fit " + path("flat.csv") + " --json " + path("flat.json"));
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.output.find("no fit"), std::string::npos) << result.output;
  const auto j = read_json("flat.json");
  EXPECT_FALSE(j.at("ok").get<bool>());
  EXPECT_FALSE(j.at("error").get<std::string>().empty());
  EXPECT_TRUE(j.at("parameters").at("k_per_s").is_null()) << "no numbers for a failed fit";
}

TEST_F(FitCli, NonFiniteValuesAreCountedAndBadCellsNamed) {
  write("nan.csv", seconds_csv(testing::CoolingCurve{}, 200, 0.05, 5) + "200,nan\n201,inf\n");
  const auto counted = bosfuse("fit " + path("nan.csv") + " --json " + path("nan.json"));
  ASSERT_EQ(counted.exit_code, 0) << counted.output;
  EXPECT_EQ(read_json("nan.json").at("diagnostics").at("rejected_non_finite").get<int>(), 2);

  write("bom.csv", "\xEF\xBB\xBF" + seconds_csv(testing::CoolingCurve{}, 100, 0.05, 6));
  const auto bom = bosfuse("fit " + path("bom.csv") + " --time-column t_s");
  EXPECT_EQ(bom.exit_code, 0) << "a byte order mark must not hide the t_s column: " << bom.output;

  write("month.csv", "time_utc,T\n2026-13-01T00:00:00Z,50\n");
  const auto month = bosfuse("fit " + path("month.csv"));
  EXPECT_NE(month.exit_code, 0);
  EXPECT_NE(month.output.find("line 2: time '2026-13-01T00:00:00Z' is neither"), std::string::npos) << month.output;

  write("bad.csv", "t_s,T\n0,50\n1,forty\n");
  const auto bad = bosfuse("fit " + path("bad.csv"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("line 3: temperature 'forty' is not a number"), std::string::npos) << bad.output;

  const auto missing = bosfuse("fit " + path("bad.csv") + " --time-column time");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("no time column 'time'; the columns are 't_s', 'T'"), std::string::npos)
      << missing.output;
}

// Command-line conventions (issue 11): `--json -` puts the JSON alone on
// standard output and the printed fit on standard error; with a file, the
// printed fit is the output and "wrote" a message; "-" as the data reads
// standard input.
TEST_F(FitCli, JsonDashIsStandardOutputAndDashReadsStandardInput) {
  const testing::CoolingCurve curve{22.0, 75.0, 0.012};
  write("run.csv", seconds_csv(curve, 300, 0.05, 7));
  const auto dash = streams("fit " + path("run.csv") + " --json -");
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  const auto j = nlohmann::json::parse(dash.out);  // throws on anything but one JSON document
  EXPECT_TRUE(j.at("ok").get<bool>());
  EXPECT_NE(dash.err.find("T_amb"), std::string::npos) << "the printed fit moves to stderr: " << dash.err;
  EXPECT_EQ(dash.err.find("wrote"), std::string::npos) << dash.err;

  const auto to_file = streams("fit " + path("run.csv") + " --json " + path("fit.json"));
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  EXPECT_NE(to_file.out.find("T_amb"), std::string::npos) << to_file.out;
  EXPECT_EQ(to_file.out.find("wrote"), std::string::npos) << "a message on stdout: " << to_file.out;
  EXPECT_NE(to_file.err.find("wrote " + path("fit.json")), std::string::npos) << to_file.err;
  EXPECT_EQ(read_json("fit.json"), j) << "the same JSON in the file as on stdout";

  const auto from_stdin = streams("fit - --json - < " + path("run.csv"));
  ASSERT_EQ(from_stdin.exit_code, 0) << from_stdin.err;
  const auto piped = nlohmann::json::parse(from_stdin.out);
  EXPECT_EQ(piped.at("input").at("file"), "-");
  EXPECT_EQ(piped.at("parameters"), j.at("parameters")) << "the same data, the same fit";
  EXPECT_NE(from_stdin.err.find("standard input: 'T' against 't_s'"), std::string::npos) << from_stdin.err;

  const auto quiet = streams("fit - --json - -q < " + path("run.csv"));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(nlohmann::json::parse(quiet.out).at("parameters"), j.at("parameters"));
  EXPECT_EQ(quiet.err, "") << "--quiet leaves only warnings and errors";
}

TEST_F(FitCli, AFailedFitWithJsonDashStillGivesTheJsonAndTheErrorOnStderr) {
  write("flat.csv", seconds_csv(testing::CoolingCurve{22.0, 22.0, 0.01}, 200, 0.05, 4));
  const auto result = streams("fit " + path("flat.csv") + " --json -");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_FALSE(nlohmann::json::parse(result.out).at("ok").get<bool>());
  EXPECT_NE(result.err.find("no fit"), std::string::npos) << result.err;
}

// Issue 28: the same clean curve (k = 0.005 1/s over 3 τ) with its times
// shifted — a file whose t = 0 lies elsewhere, an appended run's second
// session — failed with a Ceres parameter-block address at −300 s, was
// called flat at −1e4 s and rank-deficient at +1e4 s. Now it gives the same
// k, and says where T0 is when the origin lies too far for T0 there.
TEST_F(FitCli, AShiftedRecordGivesTheSameK) {
  const testing::CoolingCurve curve{22.0, 80.0, 0.005};
  const auto r = testing::sample_cooling(curve, 300, 2.0, 0.0, 1);
  const auto shifted_csv = [&](double shift_s) {
    std::string text = "t_s,T\n";
    for (std::size_t i = 0; i < r.time_s.size(); ++i) {
      text += std::to_string(r.time_s[i] + shift_s) + "," + std::to_string(r.temperature_c[i]) + "\n";
    }
    return text;
  };
  write("base.csv", shifted_csv(0.0));
  ASSERT_EQ(bosfuse("fit " + path("base.csv") + " --json " + path("base.json")).exit_code, 0);
  const double k = read_json("base.json").at("parameters").at("k_per_s").at("value");
  for (double shift_s : {-300.0, -1e4, 1e4, 1e6}) {
    const std::string name = "shift" + std::to_string(static_cast<long>(shift_s));
    write(name + ".csv", shifted_csv(shift_s));
    const auto result = bosfuse("fit " + path(name + ".csv") + " --json " + path(name + ".json"));
    ASSERT_EQ(result.exit_code, 0) << shift_s << ": " << result.output;
    EXPECT_EQ(result.output.find("ParameterBlock"), std::string::npos) << result.output;
    const auto j = read_json(name + ".json");
    EXPECT_NEAR(j.at("parameters").at("k_per_s").at("value").get<double>(), k, 1e-9 * k) << shift_s;
    EXPECT_EQ(j.at("origin_s").get<double>(), 0.0) << "the file's own t = 0";
    const bool far = std::abs(curve.k_per_s * shift_s) > std::log(1e6);
    EXPECT_EQ(j.at("t0_at_origin").get<bool>(), !far) << shift_s;
    if (!far) continue;
    EXPECT_EQ(j.at("t0_reference_s").get<double>(), shift_s);
    EXPECT_NE(
        result.output.find("T0 is at t₀ = " + std::to_string(static_cast<long>(shift_s)) + " s, the first sample"),
        std::string::npos)
        << result.output;
  }
}

// Issue 28: a row with a cell too many was read as if its cells were under
// the header's names.
TEST_F(FitCli, ARowWithMoreOrFewerCellsThanTheHeaderIsRefusedNamingTheLine) {
  write("extra.csv", "t_s,T\n0,50\n1,49,7\n2,48\n");
  const auto extra = bosfuse("fit " + path("extra.csv"));
  EXPECT_NE(extra.exit_code, 0);
  EXPECT_NE(extra.output.find("line 3: 3 cells, but the header has 2"), std::string::npos) << extra.output;

  write("short.csv", "t_s,T,other\n0,50,1\n1,49\n2,48,1\n");
  const auto short_row = bosfuse("fit " + path("short.csv") + " --temperature-column T");
  EXPECT_NE(short_row.exit_code, 0);
  EXPECT_NE(short_row.output.find("line 3: 2 cells, but the header has 3"), std::string::npos) << short_row.output;
}

TEST_F(FitCli, HasHelp) {
  const auto help = bosfuse("fit --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("--ambient"), std::string::npos) << help.output;
}

}  // namespace
}  // namespace bosfuse
