// `bosfuse evaluate --reference REF --sequence GLOB --out FILE.h5` as a user
// runs it: synthetic frames with known shifts (sim/synthetic_pair.h) and
// known file times, evaluated by the executable, and the file read back by
// programs that share no code with bosfuse: h5py, h5dump, and xml.etree for
// the XDMF sidecar (report/test_readers.h).

#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "app/test_streams.h"
#include "report/test_readers.h"
#include "sim/synthetic_pair.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report::testreaders::sh_quoted;

using testing::kBosfuse;
constexpr int kWidth = 128, kHeight = 96;
// 2026-11-23T10:00:00Z, the first frame's modification time.
constexpr std::int64_t kFirstFrameS = 1'795'428'000;

struct Frame {
  std::string name;
  double u_px, v_px;
  double t_s;  // its modification time, after the first frame's
};

class SequenceCli : public ::testing::Test {
 protected:
  // Every pair shares the pattern and its noise seed, so the references are one image.
  cv::Mat render(double u_px, double v_px, bool reference = false) {
    sim::PairOptions options;
    options.pattern.width_px = kWidth;
    options.pattern.height_px = kHeight;
    options.field = sim::DisplacementModel::uniform(u_px, v_px);
    const auto pair = sim::render_pair(options);
    return reference ? pair.reference : pair.measurement;
  }
  fs::path write_frames(const std::vector<Frame>& frames) {
    cv::imwrite(path("ref.png"), render(0, 0, true));
    fs::create_directories(dir_.path() / "frames");
    for (const auto& f : frames) {
      const fs::path file = dir_.path() / "frames" / f.name;
      if (!fs::exists(file)) cv::imwrite(file.string(), render(f.u_px, f.v_px));
      set_mtime(file, f.t_s);
    }
    return dir_.path() / "frames";
  }
  static void set_mtime(const fs::path& file, double t_s) {
    const double whole = std::floor(t_s);
    const timespec at{static_cast<time_t>(kFirstFrameS + whole), static_cast<long>(std::lround((t_s - whole) * 1e9))};
    const timespec times[2] = {at, at};
    ASSERT_EQ(utimensat(AT_FDCWD, file.c_str(), times, 0), 0) << file;
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  testing::StreamsResult bosfuse(const std::string& args) {
    return testing::run_with_streams(kBosfuse + " " + args, dir_.path(), 120);
  }
  json h5(const std::string& name) { return report::testreaders::h5py_listing(path(name), dir_.path()); }
  // The mean u and v of frame `i`'s valid nodes.
  static cv::Point2d mean_shift(const json& file, std::size_t i) {
    const auto shape = file.at("/u_px").at("shape");
    const std::size_t nodes = shape[1].get<std::size_t>() * shape[2].get<std::size_t>();
    double u = 0, v = 0;
    std::size_t n = 0;
    for (std::size_t k = i * nodes; k < (i + 1) * nodes; ++k) {
      if (file.at("/valid").at("data")[k] != 1) continue;
      u += file.at("/u_px").at("data")[k].get<double>();
      v += file.at("/v_px").at("data")[k].get<double>();
      ++n;
    }
    EXPECT_GT(n, nodes * 9 / 10) << "frame " << i;
    return n ? cv::Point2d(u / n, v / n) : cv::Point2d(NAN, NAN);
  }

  testing::TempDir dir_;
};

TEST_F(SequenceCli, AGlobOfFramesGivesOneFileWithEveryFieldNameAndTime) {
  // Natural order: frame_10 is the last frame although it sorts first as text.
  const std::vector<Frame> frames = {
      {"frame_1.tif", 0.3, -0.2, 0}, {"frame_2.tif", 0.6, -0.4, 2.5}, {"frame_10.tif", 1.2, 0.5, 10.25}};
  write_frames(frames);
  const std::string pattern = path("frames") + "/frame_*.tif";
  const auto run = bosfuse("evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " + sh_quoted(pattern) +
                           " --out " + sh_quoted(path("fields.h5")) + " --window 16 --step 8");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "") << "the data is the file";
  EXPECT_NE(run.err.find("3/3"), std::string::npos) << "progress on stderr: " << run.err;
  EXPECT_NE(run.err.find("wrote " + path("fields.h5")), std::string::npos) << run.err;

  const json f = h5("fields.h5");
  const int nx = (kWidth - 16) / 8 + 1, ny = (kHeight - 16) / 8 + 1;
  for (const char* name : {"u_px", "v_px", "peak_ratio", "sigma_u_px", "sigma_v_px", "valid", "flag"}) {
    EXPECT_EQ(f.at(std::string("/") + name).at("shape"), json::array({3, ny, nx})) << name;
    EXPECT_EQ(f.at(std::string("/") + name).at("compression"), "gzip") << name;
  }
  EXPECT_EQ(f.at("/u_px").at("dtype"), "float64");
  EXPECT_EQ(f.at("/flag").at("dtype"), "uint8");
  EXPECT_EQ(f.at("/u_px").at("attrs").at("units"), "px");
  EXPECT_EQ(f.at("/x_px").at("shape"), json::array({nx}));
  EXPECT_EQ(f.at("/y_px").at("shape"), json::array({ny}));
  EXPECT_EQ(f.at("/x_px").at("data")[0], 7.5) << "the first window's centre";
  EXPECT_EQ(f.at("/x_px").at("data")[1], 15.5);

  std::vector<std::string> names;
  for (const auto& fr : frames) names.push_back(path("frames") + "/" + fr.name);
  EXPECT_EQ(f.at("/frame_name").at("data"), json(names)) << "paths as the pattern gave them, in natural order";
  EXPECT_EQ(f.at("/status").at("data"), json::array({"ok", "ok", "ok"}));
  EXPECT_EQ(f.at("/time_source").at("data"), json::array({"mtime", "mtime", "mtime"}));
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_NEAR(f.at("/t_s").at("data")[i].get<double>(), frames[i].t_s, 1e-6) << i;
    const cv::Point2d shift = mean_shift(f, i);
    EXPECT_NEAR(shift.x, frames[i].u_px, 0.03) << frames[i].name;
    EXPECT_NEAR(shift.y, frames[i].v_px, 0.03) << frames[i].name;
  }
  const json& root = f.at("/").at("attrs");
  EXPECT_EQ(root.at("time_origin_utc"), "2026-11-23T10:00:00.000000Z");
  EXPECT_EQ(root.at("frames"), 3);
  EXPECT_EQ(root.at("frames_ok"), 3);
  EXPECT_EQ(root.at("reference"), path("ref.png"));
  const json settings = json::parse(root.at("settings").get<std::string>());
  EXPECT_EQ(settings.at("window_px"), 16);
  EXPECT_EQ(settings.at("step_px"), 8);
  EXPECT_EQ(settings.at("method"), "xcorr");

  // h5dump: the shape and the names, from HDF5's own tool.
  const auto dump = testing::run_command("h5dump -H -d /v_px " + sh_quoted(path("fields.h5")));
  ASSERT_EQ(dump.exit_code, 0) << dump.output;
  EXPECT_NE(dump.output.find(fmt::format("SIMPLE {{ ( 3, {}, {} ) / ( 3, {}, {} ) }}", ny, nx, ny, nx)),
            std::string::npos)
      << dump.output;
  const auto names_dump = testing::run_command("h5dump -d /frame_name " + sh_quoted(path("fields.h5")));
  EXPECT_NE(names_dump.output.find("\"" + names[2] + "\""), std::string::npos) << names_dump.output;

  // The sidecar: one grid per frame, each array a slab of the stacked dataset, times equal t_s.
  const json xdmf = report::testreaders::xdmf_check(path("fields.xmf"), dir_.path());
  const json& grids = xdmf.at("collections").at("displacement");
  ASSERT_EQ(grids.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(std::stod(grids[i].at("time").get<std::string>()), f.at("/t_s").at("data")[i].get<double>());
    EXPECT_EQ(grids[i].at("geometry")[0].at("shape"), json::array({nx}));
    for (const char* name : {"u_px", "v_px", "peak_ratio", "sigma_u_px", "sigma_v_px", "valid", "flag"}) {
      const json& a = grids[i].at("attributes").at(name);
      EXPECT_EQ(a.at("shape"), json::array({1, ny, nx})) << name;
      EXPECT_EQ(a.at("start")[0], i) << name;
    }
  }
}

TEST_F(SequenceCli, AnUnreadableAndAMisfitFrameAreReportedAndTheRestEvaluated) {
  write_frames({{"b_1.png", 0.4, 0.1, 0}, {"b_4.png", -0.5, 0.2, 3}});
  std::ofstream(path("frames/b_2.png")) << "not an image";
  cv::imwrite(path("frames/b_3.png"), render(0.2, 0.2)(cv::Rect(0, 0, 64, 48)).clone());
  const auto run = bosfuse("evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " +
                           sh_quoted(path("frames")) + " -o " + sh_quoted(path("out.h5")));
  EXPECT_EQ(run.exit_code, 6) << "some frames failed: " << run.err;
  EXPECT_NE(run.err.find("frame " + path("frames/b_2.png") + ": unreadable image"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("frame " + path("frames/b_3.png") + ": image size 64x48 differs from the reference's 128x96"),
            std::string::npos)
      << run.err;
  EXPECT_NE(run.err.find("2 of 4 frames could not be evaluated"), std::string::npos) << run.err;

  const json f = h5("out.h5");
  EXPECT_EQ(f.at("/u_px").at("shape")[0], 4);
  const json& status = f.at("/status").at("data");
  EXPECT_EQ(status[0], "ok");
  EXPECT_NE(status[1].get<std::string>().find("unreadable image"), std::string::npos) << status;
  EXPECT_EQ(status[2], "image size 64x48 differs from the reference's 128x96");
  EXPECT_EQ(status[3], "ok");
  EXPECT_EQ(f.at("/").at("attrs").at("frames_ok"), 2);
  EXPECT_NEAR(mean_shift(f, 0).x, 0.4, 0.03);
  EXPECT_NEAR(mean_shift(f, 3).x, -0.5, 0.03);
  EXPECT_NEAR(f.at("/t_s").at("data")[3].get<double>(), 3.0, 1e-6);
  // A failed frame: no number that could be mistaken for a measurement.
  const std::size_t nodes =
      f.at("/u_px").at("shape")[1].get<std::size_t>() * f.at("/u_px").at("shape")[2].get<std::size_t>();
  for (const std::size_t frame : {1u, 2u}) {
    for (std::size_t k = frame * nodes; k < (frame + 1) * nodes; ++k) {
      ASSERT_TRUE(f.at("/u_px").at("data")[k].is_null()) << "NaN, frame " << frame;
      ASSERT_EQ(f.at("/flag").at("data")[k], 255) << frame;
      ASSERT_EQ(f.at("/valid").at("data")[k], 0) << frame;
    }
  }
  const json xdmf = report::testreaders::xdmf_check(path("out.xmf"), dir_.path());
  EXPECT_EQ(xdmf.at("collections").at("displacement").size(), 2u) << "only frames with a field";

  // --quiet silences the progress, not the frames that failed.
  const auto quiet = bosfuse("-q evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " +
                             sh_quoted(path("frames")) + " -o " + sh_quoted(path("quiet.h5")));
  EXPECT_EQ(quiet.exit_code, 6);
  EXPECT_NE(quiet.err.find("frame " + path("frames/b_2.png") + ": unreadable image"), std::string::npos) << quiet.err;
  EXPECT_EQ(quiet.err.find("4/4"), std::string::npos) << quiet.err;
}

#ifdef BOSFUSE_HAVE_MPI
// Under mpirun (cluster/frame_farm.h) the frames are spread over the ranks
// and rank 0 writes the file: the same file as one process writes, and a
// frame's own failure still only that frame's.
TEST_F(SequenceCli, UnderMpirunTheFileIsOneProcesssAndFailedFramesAreNamed) {
  std::vector<Frame> frames;
  for (int k = 1; k <= 9; ++k) frames.push_back({fmt::format("c_{}.png", k), 0.1 * k, -0.05 * k, 1.5 * k});
  write_frames(frames);
  std::ofstream(path("frames/c_10.png")) << "not an image";
  cv::imwrite(path("frames/c_11.png"), render(0.2, 0.2)(cv::Rect(0, 0, 64, 48)).clone());
  const std::string args = "evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " +
                           sh_quoted(path("frames")) + " --window 16 --step 4 -o ";
  const auto alone = bosfuse(args + sh_quoted(path("alone.h5")));
  ASSERT_EQ(alone.exit_code, 6) << alone.err;

  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);  // what Open MPI asks of root (CI runs as root)
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  const auto job = testing::run_with_streams(
      "mpirun --oversubscribe -n 3 " + kBosfuse + " " + args + sh_quoted(path("ranks.h5")), dir_.path(), 300);
  EXPECT_EQ(job.exit_code, 6) << "some frames failed: " << job.err;
  EXPECT_NE(job.err.find("frame " + path("frames/c_10.png") + ": unreadable image"), std::string::npos) << job.err;
  EXPECT_NE(job.err.find("2 of 11 frames could not be evaluated"), std::string::npos) << job.err;
  EXPECT_NE(job.err.find("distributed over 3 MPI ranks"), std::string::npos) << job.err;

  const json one = h5("alone.h5"), many = h5("ranks.h5");
  EXPECT_EQ(many.at("/u_px").at("shape")[0], 11);
  EXPECT_EQ(many.at("/status").at("data")[9].get<std::string>().substr(0, 16), "unreadable image");
  EXPECT_EQ(many, one) << "every dataset and attribute, bit for bit";
}
#endif

// Camera frames carry their capture time: it is taken over the file's time.
TEST_F(SequenceCli, ExifCaptureTimesAreTakenOverFileTimes) {
  write_frames({});
  fs::create_directories(path("jpeg"));
  const char* stamps[] = {"2026:11:23 10:15:30", "2026:11:23 10:15:31"};
  for (int k = 0; k < 2; ++k) {
    const std::string file = path("jpeg/e_" + std::to_string(k + 1) + ".jpg");
    cv::imwrite(file, render(0.5 * (k + 1), 0), {cv::IMWRITE_JPEG_QUALITY, 98});
    testing::write_exif(
        file, {std::string("-DateTimeOriginal=") + stamps[k], k ? "-SubSecTimeOriginal=250" : "-SubSecTimeOriginal=0"});
    set_mtime(file, 100.0 * (2 - k));  // file times in the opposite order
  }
  const auto run = bosfuse("evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " +
                           sh_quoted(path("jpeg") + "/*.jpg") + " -o " + sh_quoted(path("e.h5")));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const json f = h5("e.h5");
  EXPECT_EQ(f.at("/time_source").at("data"), json::array({"exif", "exif"}));
  EXPECT_EQ(f.at("/t_s").at("data"), json::array({0.0, 1.25}));
  EXPECT_EQ(f.at("/").at("attrs").at("time_origin_utc"), "2026-11-23T10:15:30.000000Z");
  EXPECT_NEAR(mean_shift(f, 1).x, 1.0, 0.05) << "a JPEG frame is evaluated too";
}

TEST_F(SequenceCli, ABadReferenceIsAnErrorBeforeAnythingIsWritten) {
  write_frames({{"c_1.png", 0.4, 0.1, 0}});
  std::ofstream(path("junk.png")) << "not an image";
  const auto run = bosfuse("evaluate --reference " + sh_quoted(path("junk.png")) + " --sequence " +
                           sh_quoted(path("frames") + "/*.png") + " -o " + sh_quoted(path("out.h5")));
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("reference " + path("junk.png") + ": unreadable image"), std::string::npos) << run.err;
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    EXPECT_EQ(entry.path().filename().string().find("out."), std::string::npos) << entry.path();
  }
  const auto to_stdout =
      bosfuse("evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " + sh_quoted(path("frames")));
  EXPECT_NE(to_stdout.exit_code, 0);
  EXPECT_NE(to_stdout.err.find("--sequence needs --out FILE.h5"), std::string::npos) << to_stdout.err;
}

TEST_F(SequenceCli, ASettingsFileSetsTheEvaluationAndOptionsOverrideIt) {
  write_frames({{"d_1.png", 0.4, 0.1, 0}, {"d_2.png", 0.8, 0.2, 1}});
  std::ofstream(path("settings.toml")) << "[processing]\nwindow_px = 32\nstep_px = 16\npasses = 2\n";
  const std::string common = "evaluate --reference " + sh_quoted(path("ref.png")) + " --sequence " +
                             sh_quoted(path("frames")) + " --settings " + sh_quoted(path("settings.toml"));
  const auto run = bosfuse(common + " -o " + sh_quoted(path("s.h5")) + " --step 8");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const json f = h5("s.h5");
  EXPECT_EQ(f.at("/u_px").at("shape"), json::array({2, (kHeight - 32) / 8 + 1, (kWidth - 32) / 8 + 1}))
      << "window 32 from the file, step 8 from the option";
  const json settings = json::parse(f.at("/").at("attrs").at("settings").get<std::string>());
  EXPECT_EQ(settings.at("window_px"), 32);
  EXPECT_EQ(settings.at("passes"), 2);
  EXPECT_EQ(settings.at("step_px"), 8);
  EXPECT_NEAR(mean_shift(f, 1).x, 0.8, 0.03);

  std::ofstream(path("settings.toml")) << "[processing]\nwindow_px = 32\nstep = 16\n";
  const auto typo = bosfuse(common + " -o " + sh_quoted(path("t.h5")));
  EXPECT_EQ(typo.exit_code, 1);
  EXPECT_NE(typo.err.find(path("settings.toml") + ":3: processing.step: unknown key"), std::string::npos) << typo.err;
  EXPECT_FALSE(fs::exists(path("t.h5")));
}

}  // namespace
}  // namespace bosfuse
