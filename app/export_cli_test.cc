// `bosfuse export RUN --fields OUT.h5` end to end: a synthetic run (the
// report tests' run: a reference and two frames with a known hot-spot
// displacement, its experiment config giving the image scale) processed by
// the executable, exported by it, and read back by programs that share no
// code with bosfuse: h5py, h5dump, and xml.etree for the XDMF sidecar.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/test_streams.h"
#include "report/test_readers.h"
#include "tests/support/file_bytes.h"
#include "tests/support/synthetic_run.h"
#include "storage/database.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report::testreaders::sh_quoted;

using testing::kBosfuse;

class ExportCli : public ::testing::Test {
 protected:
  void SetUp() override {
    truth_.config_toml = "[geometry]\npx_per_mm_flow = 25\n";
    testrun::create_run(run(), true, truth_);
  }
  fs::path run() const { return dir_ / "run"; }
  testing::CommandResult bosfuse(const std::string& args) { return testing::run_command(kBosfuse + " " + args, 120); }
  testing::StreamsResult streams(const std::string& command) { return testing::run_with_streams(command, dir_.path()); }

  testing::TempDir dir_;
  testrun::Truth truth_;
};

TEST_F(ExportCli, FieldsOfAProcessedRunReadBackWithH5pyH5dumpAndTheXdmf) {
  const auto processed = bosfuse("process --window 16 --step 8 " + sh_quoted(run()));
  ASSERT_EQ(processed.exit_code, 0) << processed.output;
  const auto store = storage::RunStore::open(run());
  const auto frames = store.frames();
  const auto fields = storage::ProcessingStore(run()).fields();
  ASSERT_EQ(fields.size(), 4u) << "displacement and temperature of two measurement frames";

  const auto exported = bosfuse("export " + sh_quoted(run()) + " --fields " + sh_quoted(dir_ / "f.h5"));
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  EXPECT_NE(exported.output.find("2 displacement and 2 temperature frames, grid in mm at 25 px/mm"), std::string::npos)
      << "the scale from the run's stored config: " << exported.output;
  ASSERT_TRUE(fs::exists(dir_ / "f.xmf"));

  const json h5 = report::testreaders::h5py_listing(dir_ / "f.h5", dir_.path());
  EXPECT_EQ(h5.at("/").at("attrs").at("run_name"), "synthetic cooling");
  EXPECT_EQ(h5.at("/").at("attrs").at("px_per_mm"), 25.0);
  const json& x_px = h5.at("/grids/grid_000/x_px").at("data");
  const json& y_px = h5.at("/grids/grid_000/y_px").at("data");
  const json& x_mm = h5.at("/grids/grid_000/x_mm").at("data");
  ASSERT_GT(x_px.size(), 10u);
  ASSERT_GT(y_px.size(), 10u);
  EXPECT_DOUBLE_EQ(x_mm[3].get<double>(), x_px[3].get<double>() / 25.0);
  EXPECT_DOUBLE_EQ(x_px[1].get<double>() - x_px[0].get<double>(), 8.0) << "--step 8";
  const json shape = json::array({y_px.size(), x_px.size()});
  std::vector<double> peaks;
  for (int k = 0; k < 2; ++k) {
    const auto& frame = frames[1 + k];
    const std::string d = fmt::format("/displacement/frame_{:06d}", frame.id);
    const std::string t = fmt::format("/temperature/frame_{:06d}", frame.id);
    // Experiment time: seconds since the run started; the frames were taken 10.003 s and 60.003 s in.
    EXPECT_NEAR(h5.at(d).at("attrs").at("t_s").get<double>(), truth_.frame_times_s[k] + 0.003, 1e-9);
    EXPECT_EQ(h5.at(t).at("attrs").at("t_s"), h5.at(d).at("attrs").at("t_s"));
    EXPECT_EQ(h5.at(d).at("attrs").at("frame_path"), frame.path);
    for (const char* name : {"u_px", "v_px", "valid", "peak_ratio"}) {
      EXPECT_EQ(h5.at(d + "/" + name).at("shape"), shape) << name;
    }
    EXPECT_EQ(h5.at(d + "/u_px").at("attrs").at("units"), "px");
    EXPECT_EQ(h5.at(t + "/temperature_c").at("shape"), shape);
    EXPECT_EQ(h5.at(t + "/temperature_c").at("attrs").at("units"), "degC");
    // The rendered bump: its largest valid shift near the rendered peak.
    const json& u = h5.at(d + "/u_px").at("data");
    const json& v = h5.at(d + "/v_px").at("data");
    const json& valid = h5.at(d + "/valid").at("data");
    double peak = 0;
    for (std::size_t i = 0; i < u.size(); ++i) {
      if (valid[i] == 1) peak = std::max(peak, std::hypot(u[i].get<double>(), v[i].get<double>()));
    }
    peaks.push_back(peak);
    EXPECT_NEAR(peak, truth_.frame_peak_px[k], 0.2 * truth_.frame_peak_px[k]) << d;
  }
  EXPECT_GT(peaks[0], peaks[1]) << "the frames are not mixed up";

  // h5dump: the same shape and unit, from HDF5's own tool.
  const std::string first = fmt::format("/displacement/frame_{:06d}", frames[1].id);
  const auto dump = testing::run_command("h5dump -H -d " + first + "/v_px " + sh_quoted(dir_ / "f.h5"));
  ASSERT_EQ(dump.exit_code, 0) << dump.output;
  EXPECT_NE(dump.output.find(fmt::format("SIMPLE {{ ( {}, {} ) / ( {}, {} ) }}", y_px.size(), x_px.size(), y_px.size(),
                                         x_px.size())),
            std::string::npos)
      << dump.output;
  const auto units = testing::run_command("h5dump -a " + first + "/v_px/units " + sh_quoted(dir_ / "f.h5"));
  EXPECT_NE(units.output.find("\"px\""), std::string::npos) << units.output;

  // The sidecar: every reference resolves to a dataset of the declared shape, times match.
  const json xdmf = report::testreaders::xdmf_check(dir_ / "f.xmf", dir_.path());
  for (const char* kind : {"displacement", "temperature"}) {
    const json& grids = xdmf.at("collections").at(kind);
    ASSERT_EQ(grids.size(), 2u);
    for (const auto& g : grids) {
      const std::string group = fmt::format("/{}/{}", kind, g.at("name").get<std::string>());
      EXPECT_EQ(std::stod(g.at("time").get<std::string>()), h5.at(group).at("attrs").at("t_s").get<double>());
      EXPECT_EQ(g.at("geometry")[0].at("ref"), "f.h5:/grids/grid_000/x_mm");
      for (const auto& [name, item] : g.at("attributes").items()) EXPECT_EQ(item.at("shape"), shape) << name;
    }
  }
}

TEST_F(ExportCli, ARunWithoutStoredFieldsIsToldToProcessFirst) {
  const auto unprocessed = bosfuse("export " + sh_quoted(run()) + " --fields " + sh_quoted(dir_ / "f.h5"));
  EXPECT_NE(unprocessed.exit_code, 0);
  EXPECT_NE(unprocessed.output.find("has no stored fields: run `bosfuse process RUN --mode full` first"), std::string::npos)
      << unprocessed.output;
  ASSERT_EQ(bosfuse("process --mode probes " + sh_quoted(run())).exit_code, 0);
  const auto probes_only = bosfuse("export " + sh_quoted(run()) + " --fields " + sh_quoted(dir_ / "f.h5"));
  EXPECT_NE(probes_only.exit_code, 0);
  EXPECT_NE(probes_only.output.find("--mode full"), std::string::npos) << probes_only.output;
  EXPECT_FALSE(fs::exists(dir_ / "f.h5"));
  EXPECT_FALSE(fs::exists(dir_ / "f.xmf"));
}

TEST_F(ExportCli, CsvAndFieldsAreAlternatives) {
  const auto neither = bosfuse("export " + sh_quoted(run()));
  EXPECT_NE(neither.exit_code, 0);
  EXPECT_NE(neither.output.find("--csv,--probes,--fields"), std::string::npos) << neither.output;
  const auto both = bosfuse("export " + sh_quoted(run()) + " --csv --fields " + sh_quoted(dir_ / "f.h5"));
  EXPECT_NE(both.exit_code, 0);
  const auto output_with_fields =
      bosfuse("export " + sh_quoted(run()) + " --fields " + sh_quoted(dir_ / "f.h5") + " -o x.csv");
  EXPECT_NE(output_with_fields.exit_code, 0);
  EXPECT_NE(output_with_fields.output.find("--out excludes --fields"), std::string::npos) << output_with_fields.output;
  const auto csv = bosfuse("export " + sh_quoted(run()) + " --csv -o " + sh_quoted(dir_ / "s.csv"));
  ASSERT_EQ(csv.exit_code, 0) << csv.output;
  EXPECT_TRUE(fs::exists(dir_ / "s.csv"));
}

// --probes: the stored probe samples with their σ columns, read back with
// Python's csv module (no bosfuse code): every valid sample of a processed
// run has its σ, and a cell the store holds as NULL is empty.
TEST_F(ExportCli, ProbeSamplesCarryTheirUncertaintyColumns) {
  ASSERT_EQ(bosfuse("process " + sh_quoted(run())).exit_code, 0);
  const auto exported = bosfuse("export " + sh_quoted(run()) + " --probes -o " + sh_quoted(dir_ / "p.csv"));
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const std::string script =
      "import csv,sys\n"
      "rows=list(csv.DictReader(open(sys.argv[1])))\n"
      "cols=['sigma_u_px','sigma_v_px','sigma_shift_px','sigma_random_c','sigma_systematic_c']\n"
      "assert all(c in rows[0] for c in cols), rows[0].keys()\n"
      "valid=[r for r in rows if r['valid']=='1']\n"
      "assert valid and all(float(r[c])>0 for r in valid for c in cols), valid\n"
      "print(len(rows), len(valid))\n";
  std::ofstream(dir_ / "check.py") << script;
  const auto checked = testing::run_command("python3 " + sh_quoted(dir_ / "check.py") + " " + sh_quoted(dir_ / "p.csv"), 60);
  ASSERT_EQ(checked.exit_code, 0) << checked.output;
  EXPECT_EQ(checked.output, "4 4\n") << "two probes, two frames";
  {
    storage::Database db((run() / storage::RunStore::kDatabaseFileName).string(), storage::Database::Mode::kReadWrite);
    db.execute("UPDATE probe_samples SET sigma_random_c = NULL");
  }
  ASSERT_EQ(bosfuse("export " + sh_quoted(run()) + " --probes -o " + sh_quoted(dir_ / "q.csv")).exit_code, 0);
  std::ifstream q(dir_ / "q.csv");
  std::string header, row;
  std::getline(q, header);
  std::getline(q, row);
  EXPECT_NE(row.find(",,"), std::string::npos) << "NULL is an empty cell, never 0: " << row;
}

// Command-line conventions (issue 11): `-o -` is standard output, which
// then holds the CSV and nothing else; a file named by -o/--out gets the
// same bytes and standard output stays empty; messages are on stderr.
TEST_F(ExportCli, DashIsStandardOutputAndOutIsTheOneSpellingOfTheOutput) {
  const auto dash = streams(kBosfuse + " export " + sh_quoted(run()) + " --csv -o -");
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  EXPECT_TRUE(dash.out.starts_with("time_utc,t_s,time_scale,tc0 [degC],tc1 [degC]\n")) << dash.out.substr(0, 200);
  EXPECT_EQ(std::count(dash.out.begin(), dash.out.end(), '\n'), 1 + 2 * truth_.samples) << "one row per poll";
  EXPECT_EQ(dash.err, "") << "nothing but data was asked for";
  const auto plain = streams(kBosfuse + " export " + sh_quoted(run()) + " --csv");
  EXPECT_EQ(plain.out, dash.out) << "no -o is standard output too";

  const auto to_file = streams(kBosfuse + " export " + sh_quoted(run()) + " --csv --out " + sh_quoted(dir_ / "s.csv"));
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  EXPECT_EQ(to_file.out, "");
  EXPECT_NE(to_file.err.find("wrote " + (dir_ / "s.csv").string()), std::string::npos) << to_file.err;
  EXPECT_EQ(testing::file_bytes(dir_ / "s.csv"), dash.out);

  const auto old_spelling =
      streams(kBosfuse + " export " + sh_quoted(run()) + " --csv --output " + sh_quoted(dir_ / "t.csv"));
  EXPECT_NE(old_spelling.exit_code, 0);
  EXPECT_NE(old_spelling.err.find("--output"), std::string::npos) << old_spelling.err;
  EXPECT_FALSE(fs::exists(dir_ / "t.csv"));

  const auto fields = streams(kBosfuse + " export " + sh_quoted(run()) + " --fields -");
  EXPECT_NE(fields.exit_code, 0);
  EXPECT_EQ(fields.out, "");
  EXPECT_NE(fields.err.find("--fields cannot be standard output ('-'): HDF5 cannot be written to a pipe"),
            std::string::npos)
      << fields.err;
}

// The two conventions together: one command's standard output is the next
// one's input, and their messages stay out of the pipe.
TEST_F(ExportCli, AnExportPipedIntoFitGivesTheChannelsCoolingRate) {
  const auto piped = streams(kBosfuse + " export " + sh_quoted(run()) + " --csv -o - | " + kBosfuse +
                             " fit - --temperature-column 'tc1 [degC]' --json -");
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  const json fit = json::parse(piped.out);
  EXPECT_EQ(fit.at("input").at("file"), "-");
  EXPECT_EQ(fit.at("input").at("temperature_column"), "tc1 [degC]");
  const json& k = fit.at("parameters").at("k_per_s");
  EXPECT_NEAR(k.at("value").get<double>(), truth_.k_per_s[1], 4 * k.at("std_error").get<double>());
  EXPECT_NE(piped.err.find("standard input: 'tc1 [degC]' against 't_s'"), std::string::npos)
      << "the printed fit goes to stderr: " << piped.err;
}

// Issue 31: numbers at their precision. A channel of 0.1 °C resolution is
// exported with one decimal (run.sqlite keeps the doubles); a run from
// before schema 6, whose resolution is unknown, with 6 significant digits.
class ExportPrecisionCli : public ::testing::Test {
 protected:
  fs::path run() const { return dir_ / "run"; }
  testing::StreamsResult streams(const std::string& args) {
    return testing::run_with_streams(kBosfuse + " " + args, dir_.path());
  }
  // The channel cells of an export (columns 4 and 5), empty ones left out.
  std::vector<std::string> value_cells() {
    const auto exported = streams("export " + sh_quoted(run()) + " --csv -o -");
    EXPECT_EQ(exported.exit_code, 0) << exported.err;
    std::vector<std::string> cells;
    std::istringstream rows(exported.out);
    std::string row;
    std::getline(rows, row);  // the header
    while (std::getline(rows, row)) {
      std::istringstream fields(row);
      std::string cell;
      for (int column = 0; std::getline(fields, cell, ','); ++column) {
        if (column >= 3 && !cell.empty()) cells.push_back(cell);
      }
    }
    return cells;
  }

  testing::TempDir dir_;
  testrun::Truth truth_;
};

TEST_F(ExportPrecisionCli, ATenthOfADegreeChannelIsExportedWithOneDecimal) {
  truth_.resolution = 0.1;
  testrun::create_run(run(), false, truth_);
  const auto cells = value_cells();
  ASSERT_GT(cells.size(), 100u);
  for (const std::string& cell : cells) {
    ASSERT_TRUE(std::regex_match(cell, std::regex("-?[0-9]+\\.[0-9]"))) << "'" << cell << "'";
  }
  const auto store = storage::RunStore::open(run());
  EXPECT_EQ(store.channels().front().resolution, 0.1);
  const auto runs = streams("runs " + sh_quoted(run()));
  ASSERT_EQ(runs.exit_code, 0) << runs.err;
  EXPECT_TRUE(std::regex_search(runs.out, std::regex("tc0 +thermocouple +degC +0\\.1 +[0-9]+ +[0-9]+ +[0-9]+\\.[0-9] +"
                                                     "[0-9]+\\.[0-9] ")))
      << runs.out;
}

TEST_F(ExportPrecisionCli, ARunFromBeforeSchema6PrintsSixSignificantDigits) {
  testrun::create_run(run(), false, truth_);
  {
    // What a bosfuse before schema 6 left: no resolution column at all (and
    // the samples' index before version 7).
    storage::Database db((run() / storage::RunStore::kDatabaseFileName).string(), storage::Database::Mode::kReadWrite);
    db.execute(
        "DROP INDEX samples_by_channel_time_value; CREATE INDEX samples_by_channel_time ON samples (channel_id, t_ns); "
        "ALTER TABLE channels DROP COLUMN resolution; ALTER TABLE frames DROP COLUMN arrival_ns; "
        "DELETE FROM schema_version WHERE version >= 6;");
  }
  const auto cells = value_cells();
  ASSERT_GT(cells.size(), 100u);
  for (const std::string& cell : cells) {
    const std::string digits = std::regex_replace(cell, std::regex("[-.]|e.*"), "");
    EXPECT_LE(digits.size(), 6u) << "'" << cell << "'";
    EXPECT_EQ(cell, fmt::format("{:.6g}", std::stod(cell))) << "not the round trip of a 6-digit value";
  }
  const auto runs = streams("runs " + sh_quoted(run()));
  ASSERT_EQ(runs.exit_code, 0) << runs.err;
  EXPECT_TRUE(std::regex_search(runs.out, std::regex("tc0 +thermocouple +degC +- +[0-9]+"))) << runs.out;
}

}  // namespace
}  // namespace bosfuse
