// The [processing] table of a settings file and the run-less settings built from it.

#include "pipeline/processing_settings.h"

#include <gtest/gtest.h>

#include <fstream>

#include "acquisition/config/toml_reader.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;

std::string error_of(const std::string& toml) {
  try {
    parse_processing_table(toml, "s.toml");
  } catch (const acquisition::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ProcessingTable, TheStoredSettingsKeysAreRead) {
  const auto o = parse_processing_table(R"(
[geometry]
z_d_m = 0.5
[processing]
method = "xcorr"
window_px = 32
step_px = 16
passes = 2
max_shift_px = 6.5
roi_px = [8, 4, 200, 100]
mask = "holder.png"
)",
                                        "s.toml");
  ASSERT_TRUE(o.has_value());
  EXPECT_EQ(o->method, "xcorr");
  EXPECT_EQ(o->window_px, 32);
  EXPECT_EQ(o->step_px, 16);
  EXPECT_EQ(o->passes, 2);
  EXPECT_EQ(o->max_shift_px, 6.5);
  EXPECT_EQ(o->roi_px, cv::Rect(8, 4, 200, 100));
  EXPECT_EQ(o->mask, "holder.png");
  EXPECT_FALSE(o->flow_algorithm.has_value());
  EXPECT_FALSE(parse_processing_table("[geometry]\nz_d_m = 0.5\n", "s.toml").has_value());
}

TEST(ProcessingTable, ErrorsNameTheFileTheLineAndTheKey) {
  EXPECT_EQ(error_of("[processing]\nwindow_px = \"big\"\n"), "s.toml:2: processing.window_px: expected an integer");
  EXPECT_EQ(error_of("[processing]\n\nmethod = \"piv\"\n"),
            "s.toml:3: processing.method: expected one of \"xcorr\", \"flow\", not \"piv\"");
  EXPECT_EQ(error_of("[processing]\nwindow = 16\n"), "s.toml:2: processing.window: unknown key (a typo?)");
  EXPECT_EQ(error_of("[processing]\nroi_px = [1, 2, 3]\n"),
            "s.toml:2: processing.roi_px: expected [x, y, width, height] in whole pixels, width and height at least 1");
  // Values the evaluator refuses: said at the table.
  EXPECT_EQ(error_of("[processing]\nwindow_px = 4\n"), "s.toml:1: processing: window must be 8 to 128 px, not 4");
  EXPECT_NE(error_of("[processing\n").find("s.toml:1"), std::string::npos);
}

TEST(RunlessSettings, FlagsOverTheFileOverDefaults) {
  testing::TempDir dir;
  const fs::path file = dir.path() / "settings.toml";
  std::ofstream(file)
      << "[processing]\nwindow_px = 32\nstep_px = 16\nmask = \"holder.png\"\nflow_algorithm = \"farneback\"\n";
  SettingsOverrides flags;
  flags.step_px = 8;
  const auto s = resolve_runless_settings(file.string(), flags);
  EXPECT_EQ(s.evaluator.xcorr.window_px, 32);
  EXPECT_EQ(s.evaluator.xcorr.step_px, 8) << "the flag wins";
  EXPECT_EQ(s.evaluator.flow.step_px, 8);
  EXPECT_EQ(s.evaluator.flow.algorithm, fusion::FlowAlgorithm::kFarneback);
  EXPECT_EQ(s.evaluator.xcorr.passes, 3) << "a default";
  EXPECT_EQ(s.mask, (dir.path() / "holder.png").string()) << "relative to the settings file";
  EXPECT_EQ(describe(s).find("geometry"), std::string::npos) << describe(s);

  const auto defaults = resolve_runless_settings("", {});
  EXPECT_EQ(defaults.evaluator.xcorr.window_px, 16);
  EXPECT_EQ(defaults.evaluator.xcorr.step_px, 8);
  EXPECT_TRUE(defaults.mask.empty());

  EXPECT_THROW(resolve_runless_settings((dir.path() / "none.toml").string(), {}), std::runtime_error);
  std::ofstream(dir.path() / "other.toml") << "[geometry]\nz_d_m = 0.5\n";
  EXPECT_THROW(resolve_runless_settings((dir.path() / "other.toml").string(), {}), std::runtime_error);
}

TEST(PreprocessSetting, StoredReadBackAndAbsentFromOldSettingsReadsAsNone) {
  SettingsOverrides flags;
  flags.preprocess = "highpass";
  const auto s = resolve_runless_settings("", flags);
  EXPECT_EQ(s.evaluator.preprocess.method, fusion::Preprocessing::kHighpass);
  EXPECT_NE(describe(s).find("preprocessing highpass"), std::string::npos) << describe(s);
  auto j = nlohmann::json(to_json(s));
  EXPECT_EQ(j.at("preprocess"), "highpass");
  EXPECT_EQ(settings_from_json(j).evaluator.preprocess.method, fusion::Preprocessing::kHighpass);
  j.erase("preprocess");  // as a run processed before preprocessing existed stored it
  EXPECT_EQ(settings_from_json(j).evaluator.preprocess.method, fusion::Preprocessing::kNone);
  j["preprocess"] = "sharpen";
  EXPECT_THROW(settings_from_json(j), std::runtime_error);
  flags.preprocess = "sharpen";
  try {
    resolve_runless_settings("", flags);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("none, normalize, highpass, minmax"), std::string::npos) << e.what();
  }
}

TEST(FoundSearch, StoredWithTheSettingsAndReadBackAsFound) {
  auto s = resolve_runless_settings("", {});
  EXPECT_FALSE(nlohmann::json(to_json(s)).contains("found_search")) << "nothing found yet";
  fusion::SearchRange found;
  found.given_max_shift_px = 4;
  found.max_shift_px = 9;
  found.first_window_px = 40;
  found.widened = true;
  found.sampled = 60;
  found.on_bound = 51;
  found.largest_px = 7;
  s.evaluator.xcorr.known_search = found;
  const auto j = nlohmann::json(to_json(s));
  ASSERT_TRUE(j.contains("found_search"));
  const auto back = settings_from_json(j).evaluator.xcorr.known_search;
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->max_shift_px, 9);
  EXPECT_EQ(back->first_window_px, 40);
  EXPECT_TRUE(back->widened);
  EXPECT_EQ(back->on_bound, 51);
  EXPECT_EQ(back->largest_px, 7);
  s.evaluator.xcorr.find_search_range = false;  // an explicit bound: what a search found does not apply
  EXPECT_FALSE(nlohmann::json(to_json(s)).contains("found_search"));
}

TEST(PreprocessSetting, TheTableKeyIsReadAndABadNameIsNamedWithTheValidOnes) {
  const auto o = parse_processing_table("[processing]\npreprocess = \"normalize\"\n", "s.toml");
  ASSERT_TRUE(o.has_value());
  EXPECT_EQ(o->preprocess, "normalize");
  EXPECT_EQ(error_of("[processing]\n\npreprocess = \"clahe\"\n"),
            "s.toml:3: processing.preprocess: expected one of none, normalize, highpass, minmax, denoise, not \"clahe\"");
}

}  // namespace
}  // namespace bosfuse::pipeline
