// The demo through a real camera protocol: `bosfuse demo --camera genicam`
// records its frames from the simulated GigE Vision camera on 127.0.0.1
// through Aravis and the GenICam source, and must give the same fits as the
// default demo of the same seed within their uncertainties, its frames
// keeping the camera's time and their arrival. And `bosfuse cameras
// --address 127.0.0.1` lists a running `bosfuse sim camera --genicam`.
// GigE Vision's control port is fixed (3956): these tests hold the ctest
// lock genicam_gvcp (app/CMakeLists.txt).

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "fitting/fit_json.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::app {
namespace {

namespace fs = std::filesystem;
using testing::kBosfuse;

// Each stored fit's k by series name (a channel's, or a probe's + " (BOS)").
std::map<std::string, fitting::Estimate> genicam_demo_rates(const fs::path& run) {
  const storage::RunStore store = storage::RunStore::open(run);
  const storage::ProcessingStore results(run);
  std::map<std::int64_t, std::string> channel_names, probe_names;
  for (const auto& c : store.channels()) channel_names[c.id] = c.name;
  for (const auto& p : results.probes()) probe_names[p.id] = p.name + " (BOS)";
  std::map<std::string, fitting::Estimate> k;
  for (const auto& fit : results.fits()) {
    EXPECT_TRUE(fit.ok) << fit.json;
    const auto f = fitting::fit_from_json(nlohmann::json::parse(fit.json));
    k[fit.subject == storage::FitSubject::kChannel ? channel_names[fit.subject_id] : probe_names[fit.subject_id]] =
        f.k_per_s;
  }
  return k;
}

fs::path genicam_demo_run(const fs::path& out, const std::string& camera) {
  const auto demo =
      testing::run_command(kBosfuse + " demo --out '" + out.string() +
                               "' --experiment-time 80s --frame-interval 5s --speed 16 --seed 3 --camera " + camera,
                           180);
  EXPECT_EQ(demo.exit_code, 0) << demo.output;
  if (!fs::is_directory(out) || fs::directory_iterator(out) == fs::directory_iterator()) return {};
  return fs::directory_iterator(out)->path();
}

TEST(DemoGenicamCli, RecordsThroughTheGenicamSourceWithTheDefaultDemosFits) {
  testing::TempDir dir;
  const fs::path virtual_run = genicam_demo_run(dir / "virtual", "virtual");
  const fs::path genicam_run = genicam_demo_run(dir / "genicam", "genicam");
  ASSERT_FALSE(virtual_run.empty());
  ASSERT_FALSE(genicam_run.empty());
  const auto by_virtual = genicam_demo_rates(virtual_run);
  const auto by_genicam = genicam_demo_rates(genicam_run);
  ASSERT_EQ(by_virtual.size(), 4u) << "two thermocouples, two BOS probes";
  ASSERT_EQ(by_genicam.size(), by_virtual.size());
  for (const auto& [name, k] : by_virtual) {
    ASSERT_TRUE(by_genicam.count(name)) << name;
    const fitting::Estimate& g = by_genicam.at(name);
    // The two fits' 95 % intervals, combined in quadrature.
    const double half_width = std::hypot((k.high - k.low) / 2, (g.high - g.low) / 2);
    EXPECT_LE(std::abs(g.value - k.value), half_width)
        << name << ": k virtual " << k.value << ", genicam " << g.value << ", combined 95 % half-width " << half_width;
    std::cout << name << ": k virtual " << k.value << " [" << k.low << ", " << k.high << "], genicam " << g.value
              << " [" << g.low << ", " << g.high << "] 1/s\n";
  }
  // Every frame keeps the camera's time and the host's arrival beside the mapped t_ns.
  const auto kept = testing::run_command("sqlite3 '" + (genicam_run / storage::RunStore::kDatabaseFileName).string() +
                                         "' 'SELECT COUNT(*) > 4 AND COUNT(*) = SUM(device_t_ns IS NOT NULL AND "
                                         "arrival_ns IS NOT NULL) FROM frames'");
  EXPECT_EQ(kept.output, "1\n");
  const auto profile =
      testing::run_command("sqlite3 '" + (genicam_run / storage::RunStore::kDatabaseFileName).string() +
                           "' \"SELECT COUNT(*) FROM devices WHERE profile = 'genicam'\"");
  EXPECT_EQ(profile.output, "1\n");
}

TEST(CamerasCli, ListsARunningSimulatedGenicamCamera) {
  testing::BackgroundProcess camera(
      {kBosfuse, "sim", "camera", "--genicam", "--serial", "BOSLIST", "--frame-rate", "2", "--duration", "60s"});
  std::string listed;
  for (int i = 0; i < 30 && listed.find("BOSLIST") == std::string::npos; ++i) {  // up to ~15 s
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    listed = testing::run_command(kBosfuse + " cameras --no-discovery --address 127.0.0.1", 30).output;
  }
  EXPECT_NE(listed.find("BOSLIST"), std::string::npos) << listed;
  EXPECT_NE(listed.find("Mono8"), std::string::npos) << listed;
  EXPECT_NE(listed.find("127.0.0.1"), std::string::npos) << listed;
}

}  // namespace
}  // namespace bosfuse::app
