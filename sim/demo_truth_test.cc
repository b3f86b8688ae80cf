#include "sim/demo_truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "tests/support/temp_dir.h"

namespace bosfuse::sim {
namespace {

TEST(DemoTruth, TheLogLinearRateOfAnExponentialIsItsRate) {
  std::vector<double> t_s, excess_c;
  for (double t = 0; t <= 240; t += 10) t_s.push_back(t), excess_c.push_back(80 * std::exp(-0.004 * t));
  EXPECT_NEAR(log_linear_rate(t_s, excess_c), 0.004, 1e-12);
}

// The truth file holds, per thermocouple, the point's rate and the window
// mean's, whose excess lies below the point's on the curved centreline.
TEST(DemoTruth, TheTruthFileHasTheRatesAndEachThermocouplesProbe) {
  testing::TempDir dir;
  const DemoOptions options;
  const DemoSetup setup = demo_setup(options.experiment_s);
  write_truth(dir.path(), options, setup);
  nlohmann::json truth;
  std::ifstream(dir / "demo-truth.json") >> truth;
  EXPECT_DOUBLE_EQ(truth.at("speed").get<double>(), options.speed);
  EXPECT_DOUBLE_EQ(truth.at("plume_k_per_s").get<double>(), true_plume_cooling_rate(setup));
  EXPECT_DOUBLE_EQ(true_plume_cooling_rate(setup), 0.8 * truth.at("cylinder_k_per_s").get<double>());
  ASSERT_EQ(truth.at("probes").size(), setup.thermocouples.size());
  for (std::size_t i = 0; i < setup.thermocouples.size(); ++i) {
    const auto& probe = truth["probes"][i];
    EXPECT_EQ(probe.at("name"), setup.thermocouples[i].name);
    EXPECT_EQ(probe.at("window_px"), kDemoWindowPx);
    EXPECT_LT(probe.at("window_excess_at_0_c").get<double>(), probe.at("point_excess_at_0_c").get<double>());
    EXPECT_NEAR(probe.at("point_k_per_s").get<double>(), true_plume_cooling_rate(setup),
                0.05 * true_plume_cooling_rate(setup));
  }
}

}  // namespace
}  // namespace bosfuse::sim
