// A frame that does not show the reference's background, as `quality`,
// `evaluate` and `process` meet it (fusion/scene_match.h): said so, and
// nothing of it marked valid; a matching pair never is.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "app/process_test_run.h"
#include "app/run_control.h"
#include "app/test_streams.h"
#include "sim/synthetic_pair.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

const std::string kBinary = std::string(BOSFUSE_BINARY_DIR) + "/bosfuse";

sim::SyntheticPair pair_of(sim::DisplacementModel field, std::uint64_t seed = 3) {
  sim::PairOptions options;
  options.pattern.width_px = 256;
  options.pattern.height_px = 192;
  options.pattern.seed = seed;
  options.field = field;
  options.noise_std = 0.02;
  return sim::render_pair(options);
}

class SceneMatchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto matching = pair_of(sim::DisplacementModel::uniform(0, 0));
    cv::imwrite(path("ref.png"), matching.reference);
    cv::imwrite(path("same.png"), matching.measurement);
    cv::imwrite(path("foreign.png"), pair_of(sim::DisplacementModel::uniform(0, 0), 4).measurement);
    cv::imwrite(path("grey.png"), cv::Mat(192, 256, CV_8U, cv::Scalar(128)));
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  testing::StreamsResult streams(const std::string& args) {
    return testing::run_with_streams(kBinary + " " + args, dir_.path(), 120);
  }
  static std::string read(const std::string& file) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  // Rows of a field CSV whose `valid` column is 1.
  static int valid_rows(const std::string& csv) {
    std::istringstream lines(csv);
    std::string line;
    std::getline(lines, line);
    int valid = 0;
    while (std::getline(lines, line)) {
      std::stringstream cells(line);
      std::string cell;
      for (int column = 0; column < 5 && std::getline(cells, cell, ','); ++column) {
      }
      valid += cell == "1" ? 1 : 0;
    }
    return valid;
  }

  testing::TempDir dir_;
};

TEST_F(SceneMatchCli, QualityCallsAnUnrelatedBackgroundNotTheSameSceneInTextAndJson) {
  const auto run = streams("quality " + path("foreign.png") + " --reference " + path("ref.png") + " --json -");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_GT(json.at("q_mod").get<double>(), 0.9) << "the old key, kept: Q_mod alone calls this a good match";
  EXPECT_EQ(json.at("verdict"), "not the same scene");
  EXPECT_LT(json.at("scene_correlation").get<double>(),
            json.at("scene_thresholds").at("min_correlation").get<double>());
  EXPECT_NE(run.err.find("verdict: not the same scene (scene correlation "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("< 0.50"), std::string::npos) << "the threshold is printed: " << run.err;
}

TEST_F(SceneMatchCli, QualityCallsTwoFeaturelessImagesNoTextureAndAMatchingOneGood) {
  const auto flat = streams("quality " + path("grey.png") + " --reference " + path("grey.png") + " --json -");
  ASSERT_EQ(flat.exit_code, 0) << flat.err;
  EXPECT_EQ(nlohmann::json::parse(flat.out).at("verdict"), "no texture");
  EXPECT_NE(flat.err.find("verdict: no texture"), std::string::npos) << flat.err;

  const auto same = streams("quality " + path("same.png") + " --reference " + path("ref.png"));
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_NE(same.out.find("verdict: good (Q_mod "), std::string::npos) << same.out;
}

TEST_F(SceneMatchCli, EvaluateWarnsOfAnUnrelatedPairAndMarksNoVectorValid) {
  const auto foreign = streams("evaluate " + path("ref.png") + " " + path("foreign.png") + " -o " + path("f.csv"));
  ASSERT_EQ(foreign.exit_code, 0) << foreign.err;
  EXPECT_NE(foreign.err.find("not the same scene (scene correlation "), std::string::npos) << foreign.err;
  EXPECT_NE(foreign.err.find("no vector is marked valid"), std::string::npos) << foreign.err;
  EXPECT_EQ(valid_rows(read(path("f.csv"))), 0);
  EXPECT_NE(foreign.err.find("0 valid"), std::string::npos) << "the summary counts none: " << foreign.err;
}

// Shifts of 0, 2 and 6.5 px with noise, the last beyond the default search: never another scene.
TEST_F(SceneMatchCli, EvaluateNeverCallsAMatchingPairAnotherScene) {
  for (const auto& [u, v] : {std::pair{0.0, 0.0}, {2.0, 0.0}, {5.3, -3.7}}) {
    const auto pair = pair_of(sim::DisplacementModel::uniform(u, v));
    cv::imwrite(path("r.png"), pair.reference);
    cv::imwrite(path("m.png"), pair.measurement);
    const auto run = streams("evaluate " + path("r.png") + " " + path("m.png") + " -o " + path("m.csv"));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.err.find("not the same scene"), std::string::npos) << "u = " << u << ": " << run.err;
    EXPECT_GT(valid_rows(read(path("m.csv"))), 0) << "u = " << u;
  }
}

TEST_F(SceneMatchCli, AnEvaluatedSequenceGivesAForeignFrameItsReasonAsStatus) {
  std::filesystem::create_directories(dir_.path() / "seq");
  std::filesystem::copy_file(path("same.png"), path("seq/frame_1.png"));
  std::filesystem::copy_file(path("foreign.png"), path("seq/frame_2.png"));
  const auto run =
      streams("evaluate --reference " + path("ref.png") + " --sequence " + path("seq") + " -o " + path("seq.h5"));
  EXPECT_EQ(run.exit_code, app::kExitSomeFramesFailed) << run.err;
  EXPECT_NE(run.err.find("frame_2.png: not the same scene (scene correlation "), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("frame_1.png: not the same scene"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("1 of 2 frames could not be evaluated"), std::string::npos) << run.err;
}

using process_testing::ProcessCli;

// One frame of the run replaced by another background: refused, the others not.
void replace_frame_by_a_foreign_one(const std::filesystem::path& run, const std::string& frame_path) {
  const cv::Mat original = cv::imread((run / frame_path).string(), cv::IMREAD_UNCHANGED);
  sim::PairOptions other;
  other.pattern.width_px = original.cols;
  other.pattern.height_px = original.rows;
  other.pattern.seed = 99;
  ASSERT_TRUE(cv::imwrite((run / frame_path).string(), sim::render_pair(other).measurement));
}

TEST_F(ProcessCli, AForeignFrameIsRefusedNotStoredAsTemperatures) {
  std::int64_t foreign_id = 0;
  for (const auto& f : storage::RunStore::open(run_dir()).frames()) {
    if (f.path == "frames/f4.png") foreign_id = f.id;
  }
  ASSERT_NE(foreign_id, 0);
  replace_frame_by_a_foreign_one(run_dir(), "frames/f4.png");
  for (const std::string mode : {"full", "probes"}) {
    const auto run = bosfuse("process --mode " + mode + " " + grid_);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("1 frames refused as not showing the reference's background"), std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find(fmt::format("frame {}: not the same scene (scene correlation ", foreign_id)),
              std::string::npos)
        << run.output;
    const storage::ProcessingStore results(run_dir());
    std::size_t others = 0;
    for (const auto& p : results.probes()) {
      for (const auto& s : results.probe_samples(p.id)) {
        if (s.frame_id == foreign_id) {
          EXPECT_FALSE(s.valid) << mode;
          EXPECT_FALSE(s.temperature_c.has_value()) << mode;
        } else {
          EXPECT_TRUE(s.valid) << mode << ": a matching frame is never refused";
          ++others;
        }
      }
    }
    EXPECT_EQ(others, 2u * 7) << mode;
    const auto summary = nlohmann::json::parse(results.current_processing()->summary_json);
    ASSERT_EQ(summary.at("frames_refused").size(), 1u) << summary.dump();
    EXPECT_EQ(summary.at("frames_refused")[0].at("frame_id"), foreign_id);
    for (const auto& f : results.fields()) {
      EXPECT_FALSE(f.frame_id == foreign_id && f.kind == "temperature") << "no temperature field of a foreign frame";
    }
  }
}

}  // namespace
}  // namespace bosfuse
