// SequenceFieldWriter on its own: results arriving in any order land at their
// index, a mistaken gather is refused, and nothing reaches the destination
// until every frame is written. Read back by h5py (report/test_readers.h).

#include "report/sequence_export.h"

#include <gtest/gtest.h>

#include <fstream>

#include "fusion/evaluation.h"
#include "report/test_readers.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

const fusion::GridGeometry kGrid{7.5, 7.5, 8, 2, 3};

pipeline::SequenceFrameResult frame(const std::string& name, double u_px, std::int64_t t_ns) {
  pipeline::SequenceFrameResult r;
  r.name = name;
  r.time = {t_ns, pipeline::TimeSource::kFileModification};
  r.field = fusion::field_on_grid(kGrid);
  for (auto& v : r.field.vectors) v.u_px = u_px;
  r.field.at(1, 2).flag = fusion::VectorFlag::kMasked;
  return r;
}

SequenceExportInfo info() { return {"ref.png", R"({"window_px":16})", {"a_1.png", "a_2.png", "a_10.png"}, kGrid}; }

TEST(SequenceExport, ResultsInAnyOrderLandAtTheirIndex) {
  testing::TempDir dir;
  const fs::path out = dir.path() / "s.h5";
  SequenceFieldWriter writer(out, info());
  writer.write(2, frame("a_10.png", 3.0, 12'000'000'000));
  auto failed = frame("a_2.png", 0, 11'500'000'000);
  failed.status = "unreadable image";
  failed.field = {};
  writer.write(1, failed);
  writer.write(0, frame("a_1.png", 1.0, 10'000'000'000));
  EXPECT_FALSE(fs::exists(out)) << "only commit() puts the file in place";
  const auto result = writer.commit();
  EXPECT_EQ(result.frames_ok, 2u);
  EXPECT_EQ(result.time_origin_ns, 10'000'000'000);

  const auto f = testreaders::h5py_listing(out, dir.path());
  EXPECT_EQ(f.at("/u_px").at("shape"), nlohmann::json::array({3, 2, 3}));
  const auto& u = f.at("/u_px").at("data");
  EXPECT_EQ(u[0], 1.0);
  EXPECT_TRUE(u[6].is_null()) << "the failed frame is NaN";
  EXPECT_EQ(u[12], 3.0);
  EXPECT_EQ(f.at("/flag").at("data")[5], 3) << "masked";
  EXPECT_EQ(f.at("/valid").at("data")[5], 0);
  for (const char* quantity : {"/u_px", "/v_px", "/peak_ratio", "/sigma_u_px", "/sigma_v_px"}) {
    EXPECT_TRUE(f.at(quantity).at("data")[5].is_null()) << quantity << ": the masked node has no number";
  }
  EXPECT_EQ(f.at("/flag").at("data")[6], 255);
  EXPECT_EQ(f.at("/t_s").at("data"), nlohmann::json::array({0.0, 1.5, 2.0}));
  EXPECT_EQ(f.at("/status").at("data"), nlohmann::json::array({"ok", "unreadable image", "ok"}));
  EXPECT_EQ(f.at("/x_px").at("data"), nlohmann::json::array({7.5, 15.5, 23.5}));
  EXPECT_EQ(f.at("/").at("attrs").at("time_origin_utc"), "1970-01-01T00:00:10.000000Z");
}

TEST(SequenceExport, AMistakenGatherIsRefusedAndLeavesNoFile) {
  testing::TempDir dir;
  const fs::path out = dir.path() / "s.h5";
  std::ofstream(out) << "the previous file";
  {
    SequenceFieldWriter writer(out, info());
    EXPECT_THROW(writer.write(1, frame("a_10.png", 1, 0)), std::logic_error) << "another frame's result";
    writer.write(0, frame("a_1.png", 1, 0));
    EXPECT_THROW(writer.write(0, frame("a_1.png", 1, 0)), std::logic_error) << "twice";
    EXPECT_THROW(writer.write(3, frame("a_4.png", 1, 0)), std::out_of_range);
    auto wrong_grid = frame("a_2.png", 1, 0);
    wrong_grid.field.cols = 2;
    EXPECT_THROW(writer.write(1, wrong_grid), std::invalid_argument);
    EXPECT_THROW(writer.commit(), std::logic_error) << "frames 1 and 2 never written";
  }
  std::ifstream in(out);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "the previous file");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1) << "no temporary left";
  EXPECT_THROW(SequenceFieldWriter(dir.path() / "no" / "s.h5", info()), std::invalid_argument);
  EXPECT_THROW(SequenceFieldWriter(dir.path() / "s.xmf", info()), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::report
