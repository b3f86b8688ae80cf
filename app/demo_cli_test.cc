// The main job end to end, small and short: `bosfuse demo` simulates the
// experiment, records it through the real paths, processes it and writes the
// report; the cooling rates it recovers from thermocouples and from BOS must
// match the scene's true one.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/browser.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::app {
namespace {

namespace fs = std::filesystem;

// Every quantity of the demo's report can be computed, so none may show as
// nan, inf or null (a reader once missed the stored limits of agreement).
void expect_every_number_present(const std::string& page, const fs::path& json_file) {
  std::string text = page;
  for (auto at = text.find("base64,"); at != std::string::npos; at = text.find("base64,", at + 7)) {
    text.erase(at + 7, text.find('"', at) - at - 7);  // images are not text
  }
  for (const char* bad : {">nan", "nan<", "[nan", "nan]", " nan ", ">inf", "inf<", "null"}) {
    EXPECT_EQ(text.find(bad), std::string::npos)
        << "report.html shows '" << bad
        << "' near: " << text.substr(text.find(bad) > 80 ? text.find(bad) - 80 : 0, 160);
  }
  nlohmann::json report;
  std::ifstream(json_file) >> report;
  std::vector<std::string> nulls;
  const std::function<void(const nlohmann::json&, const std::string&)> walk = [&](const nlohmann::json& j,
                                                                                  const std::string& path) {
    if (j.is_null()) nulls.push_back(path);
    if (j.is_number_float() && !std::isfinite(j.get<double>())) nulls.push_back(path);
    if (j.is_object()) {
      for (const auto& [key, value] : j.items()) walk(value, path + "/" + key);
    }
    if (j.is_array()) {
      for (std::size_t i = 0; i < j.size(); ++i) walk(j[i], path + "/" + std::to_string(i));
    }
  };
  walk(report, "");
  EXPECT_TRUE(nulls.empty()) << "report.json has no number at " << ::testing::PrintToString(nulls);
}

TEST(DemoCli, RecoversTheTrueCoolingRateFromThermocouplesAndBos) {
  testing::TempDir dir;
  const auto result = testing::run_command(std::string(BOSFUSE_BINARY_DIR) + "/bosfuse demo --out " +
                                               (dir / "demo").string() + " --experiment-time 150 --speed 30",
                                           120);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  ASSERT_EQ(std::distance(fs::directory_iterator(dir / "demo"), fs::directory_iterator()), 1);
  const fs::path run = fs::directory_iterator(dir / "demo")->path();
  EXPECT_NE(result.output.find((run / "report/report.html").string()), std::string::npos) << result.output;

  nlohmann::json truth;
  std::ifstream(run / "demo-truth.json") >> truth;
  const double speed = truth["speed"], true_k = truth["plume_k_per_s"];
  const storage::ProcessingStore results(run);
  int thermocouple_fits = 0, bos_fits = 0;
  for (const auto& fit : results.fits()) {
    ASSERT_TRUE(fit.ok) << fit.json;
    const double k = nlohmann::json::parse(fit.json)["parameters"]["k_per_s"]["value"].get<double>() / speed;
    // Stated tolerance: 5% of the true rate, for both kinds of measurement.
    EXPECT_NEAR(k, true_k, 0.05 * true_k) << fit.json;
    (fit.subject == storage::FitSubject::kChannel ? thermocouple_fits : bos_fits) += 1;
  }
  EXPECT_EQ(thermocouple_fits, 2);
  EXPECT_EQ(bos_fits, 2);
  EXPECT_EQ(results.agreements().size(), 2u);

  std::ifstream html(run / "report/report.html");
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  std::size_t figures = 0;
  for (auto at = page.find("src=\"data:image/png;base64,"); at != std::string::npos;
       at = page.find("src=\"data:image/png;base64,", at + 1)) {
    ++figures;
  }
  EXPECT_GE(figures, 4u);
  // And a real browser draws every one of them.
  ASSERT_TRUE(testing::have_chromium()) << "chromium is not installed (scripts/debian-packages.txt lists it)";
  const auto images = testing::render_check(page, run / "report/render-check.html", dir.path());
  EXPECT_EQ(images.size(), figures);
  for (const auto& image : images) {
    EXPECT_TRUE(image.complete);
    EXPECT_NE(image.size, "0x0");
    EXPECT_GT(image.spread, 100);
  }
  EXPECT_EQ(storage::RunStore::open(run).run().status, storage::RunStatus::kComplete);
  expect_every_number_present(page, run / "report/report.json");
}

}  // namespace
}  // namespace bosfuse::app
