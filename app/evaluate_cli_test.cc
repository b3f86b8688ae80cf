// bosfuse evaluate / quality / background as a user runs them.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "app/test_streams.h"
#include "sim/background_pattern.h"
#include "sim/synthetic_pair.h"
#include "tests/support/forged_image.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using testing::kBosfuse;

class EvaluateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    sim::PairOptions options;
    options.pattern.width_px = 128;
    options.pattern.height_px = 96;
    options.field = sim::DisplacementModel::uniform(0.4, -0.3);
    const auto pair = sim::render_pair(options);
    cv::imwrite(path("ref.png"), pair.reference);
    cv::imwrite(path("meas.png"), pair.measurement);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  testing::CommandResult bosfuse(const std::string& args) { return testing::run_command(kBosfuse + " " + args); }
  testing::StreamsResult streams(const std::string& args) {
    return testing::run_with_streams(kBosfuse + " " + args, dir_.path());
  }
  static std::string read(const std::string& file) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

  testing::TempDir dir_;
};

TEST_F(EvaluateCli, AGoodPairGivesACsvWithTheHeader) {
  const auto run = bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " -o " + path("field.csv") +
                           " --map " + path("map.png") + " --contour 0.05");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string csv = read(path("field.csv"));
  std::istringstream lines(csv);
  std::string header;
  std::getline(lines, header);
  EXPECT_EQ(header, "x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v");
  int rows = 0, valid = 0;
  double sum_u = 0;
  for (std::string line; std::getline(lines, line) && rows < 10000; ++rows) {
    double x, y, u, v, peak;
    int ok;
    char flag[32] = {};
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%d,%31[^,],%lf", &x, &y, &u, &v, &ok, flag, &peak), 7) << line;
    EXPECT_EQ(ok == 1, std::string(flag) == "ok") << line;
    valid += ok;
    sum_u += ok ? u : 0;
  }
  EXPECT_EQ(rows, ((128 - 16) / 8 + 1) * ((96 - 16) / 8 + 1));
  ASSERT_GT(valid, rows * 9 / 10);
  EXPECT_NEAR(sum_u / valid, 0.4, 0.02);
  EXPECT_FALSE(cv::imread(path("map.png")).empty());
  EXPECT_NE(run.output.find("valid"), std::string::npos) << "a summary goes to stderr";
}

// The 6.5 px pair: with --max-shift 4 the bound is kept, every
// window peaks on it, and the user is told so and how to fix it; unset, the
// scene widens the search and says nothing alarming.
TEST_F(EvaluateCli, PeaksOnAnExplicitSearchBoundAreFlaggedAndWarnedAbout) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = 256;
  options.pattern.dot_diameter_px = 3;
  options.pattern.coverage = 0.5;
  options.field = sim::DisplacementModel::uniform(5.3, -3.7);
  const auto pair = sim::render_pair(options);
  cv::imwrite(path("far_ref.png"), pair.reference);
  cv::imwrite(path("far_meas.png"), pair.measurement);
  const std::string images = "evaluate " + path("far_ref.png") + " " + path("far_meas.png");
  const auto bounded = streams(images + " --max-shift 4 -o " + path("bounded.csv"));
  ASSERT_EQ(bounded.exit_code, 0) << bounded.err;
  EXPECT_NE(bounded.err.find("peaked on the ±4 px search bound"), std::string::npos) << bounded.err;
  EXPECT_NE(bounded.err.find("raise --max-shift or leave it unset"), std::string::npos) << bounded.err;
  const std::string csv = read(path("bounded.csv"));
  EXPECT_TRUE(csv.starts_with("x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v\n")) << csv.substr(0, 80);
  EXPECT_NE(csv.find(",0,beyond-search,"), std::string::npos);
  EXPECT_EQ(csv.find(",1,ok,"), std::string::npos) << "no vector of the wrong shift is valid";

  const auto found = streams(images + " -o " + path("found.csv"));
  ASSERT_EQ(found.exit_code, 0) << found.err;
  EXPECT_EQ(found.err.find("search bound"), std::string::npos) << found.err;
  EXPECT_NE(found.err.find("widened from the scene"), std::string::npos) << found.err;
  EXPECT_NE(read(path("found.csv")).find(",1,ok,"), std::string::npos);
}

TEST_F(EvaluateCli, AdaptiveRefinementOfAShiftEverywhereRefinesEverything) {
  const std::string pair = "evaluate " + path("ref.png") + " " + path("meas.png");
  const auto plain = bosfuse(pair + " -o " + path("plain.csv"));
  const auto adaptive = bosfuse(pair + " --adaptive-refinement on -o " + path("adaptive.csv"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  ASSERT_EQ(adaptive.exit_code, 0) << adaptive.output;
  EXPECT_EQ(read(path("adaptive.csv")), read(path("plain.csv")));
  EXPECT_EQ(adaptive.output.find("refined"), std::string::npos) << "all of it: nothing to say";
  const auto bad = bosfuse(pair + " --adaptive-refinement on --adaptive-threshold 0");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("adaptive refinement threshold"), std::string::npos) << bad.output;
}

TEST_F(EvaluateCli, ProbesGiveOneRowEach) {
  const auto run = bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " --probe 40,40 --probe 80.5,50");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v\n"), std::string::npos);
  // (40, 40) lies halfway between window centres 39.5 and 40.5: it snaps up.
  EXPECT_NE(run.output.find("\n40.5,40.5,0.4"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("\n80.5,50.5,0.3"), std::string::npos) << run.output;
}

TEST_F(EvaluateCli, UnreadableAndMissingFilesAreNamed) {
  std::ofstream(path("junk.png")) << "not an image";
  const auto junk = bosfuse("evaluate " + path("junk.png") + " " + path("meas.png") + " -o " + path("f.csv"));
  EXPECT_NE(junk.exit_code, 0);
  EXPECT_NE(junk.output.find("junk.png: unreadable image"), std::string::npos) << junk.output;
  const auto missing = bosfuse("evaluate " + path("ref.png") + " " + path("nope.png"));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("nope.png: no such file"), std::string::npos) << missing.output;
}

TEST_F(EvaluateCli, MismatchedSizesAreNamed) {
  const cv::Mat small = cv::imread(path("meas.png"), cv::IMREAD_UNCHANGED)(cv::Rect(0, 0, 64, 64)).clone();
  cv::imwrite(path("small.png"), small);
  const auto run = bosfuse("evaluate " + path("ref.png") + " " + path("small.png"));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("image sizes differ: reference 128x96 but measurement 64x64"), std::string::npos)
      << run.output;
}

TEST_F(EvaluateCli, WindowLargerThanTheImageIsNamed) {
  const auto run = bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " --window 128");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("interrogation window 128 px is larger than the image (128x96)"), std::string::npos)
      << run.output;
}

// Both once reached int pixel arithmetic that overflowed (seen under UBSan);
// the probe ran and printed an out-of-ROI row with exit code 0.
TEST_F(EvaluateCli, ProbeOutsideTheImageIsAnError) {
  for (const char* probe : {"-2147483648,0", "0,2147483647", "128,10", "nan,3"}) {
    const auto run = bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " --probe " + probe);
    EXPECT_NE(run.exit_code, 0) << probe;
    EXPECT_NE(run.output.find("probe '" + std::string(probe) + "' lies outside the 128x96 image"), std::string::npos)
        << run.output;
  }
}

TEST_F(EvaluateCli, RoiOutsideTheImageIsAnError) {
  for (const char* roi : {"2147483647,0,10,10", "2147483647,2147483647,2147483647,2147483647"}) {
    const auto run = bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " --roi " + roi);
    EXPECT_NE(run.exit_code, 0) << roi;
    EXPECT_NE(run.output.find("region of interest " + std::string(roi) + " lies outside the 128x96 image"),
              std::string::npos)
        << run.output;
  }
}

// A few hundred bytes declaring 20000x20000 px: once decoded in full (a
// 388 KB one took 7.5 GB and 134 s evaluated against itself).
TEST_F(EvaluateCli, AnImageDeclaringTooManyPixelsIsRefusedUnread) {
  const auto bomb = testing::png_declaring(20000, 20000);
  std::ofstream(path("bomb.png"), std::ios::binary)
      .write(reinterpret_cast<const char*>(bomb.data()), static_cast<std::streamsize>(bomb.size()));
  const auto run = bosfuse("evaluate " + path("bomb.png") + " " + path("bomb.png"));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("bomb.png: the image declares 20000x20000 px (400.0 megapixels), over the limit"),
            std::string::npos)
      << run.output;
  // The limit is the user's to set.
  const auto limited = testing::run_command("env BOSFUSE_MAX_IMAGE_PIXELS=10000 " + kBosfuse + " evaluate " +
                                            path("ref.png") + " " + path("meas.png"));
  EXPECT_NE(limited.exit_code, 0);
  EXPECT_NE(limited.output.find("declares 128x96 px"), std::string::npos) << limited.output;
}

// The probe's file: a real 256x256 PNG padded to 1.9 GB (68 KB on disk,
// sparse), once read whole in 8.9 s and 2.03 GB. Refused from its header and
// its size, naming the file; the process never holds a tenth of the padding.
TEST_F(EvaluateCli, APaddedImageIsRefusedBeforeItIsReadWhole) {
  cv::Mat image(256, 256, CV_8U);
  cv::randu(image, 0, 255);
  std::vector<std::uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", image, png));
  testing::write_padded(path("padded.png"), png, 1'900'000'000);
  for (const std::string& command : {"evaluate " + path("padded.png") + " " + path("meas.png"),
                                     "quality " + path("padded.png") + " --reference " + path("ref.png")}) {
    const auto run = streams(command);
    EXPECT_EQ(run.exit_code, 1) << command << "\n" << run.err;
    EXPECT_NE(run.err.find(path("padded.png") + ": the file is 1900000000 bytes (1900.0 MB), more than a 256x256 px "
                                                "PNG can need"),
              std::string::npos)
        << run.err;
    EXPECT_GT(run.peak_memory_bytes, 0);
    EXPECT_LT(run.peak_memory_bytes, 300'000'000) << command;
  }
}

// Under `ulimit -v 1.5G` the probe's padded PNG ended in a bare
// std::bad_alloc. A file within every limit (a header declaring 10000x10000
// px may come with 1.2 GB) can still need more memory than there is:
// the error names the file and its size.
TEST_F(EvaluateCli, RunningOutOfMemoryForAnImageIsAnErrorNamingTheFile) {
#ifdef BOSFUSE_SANITIZED
  GTEST_SKIP() << "sanitizers reserve terabytes of address space: no ulimit -v fits them "
                  "(ImageFile.RunningOutOfMemoryWhileDecodingIsAnErrorNamingTheFile runs under them)";
#endif
  testing::write_padded(path("big.png"), testing::png_declaring(10000, 10000), 1'200'000'000);
  const auto run = testing::run_with_streams(
      "ulimit -v 1000000; exec " + kBosfuse + " evaluate " + path("big.png") + " " + path("meas.png"), dir_.path());
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find(path("big.png") + ": out of memory for its 1200000000 bytes (1200.0 MB)"), std::string::npos)
      << run.err;
}

// Half a JPEG: OpenCV decodes it with a warning and grey for the missing
// half. bosfuse refuses it, naming the file, in libjpeg's own words.
TEST_F(EvaluateCli, HalfAJpegIsRefusedNamingTheFile) {
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::imread(path("meas.png"), cv::IMREAD_UNCHANGED), jpeg));
  jpeg.resize(jpeg.size() / 2);
  std::ofstream(path("half.jpg"), std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  const auto run = streams("evaluate " + path("ref.png") + " " + path("half.jpg"));
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find(path("half.jpg") +
                         ": the JPEG's image data is incomplete or damaged (libjpeg: Premature end of JPEG file)"),
            std::string::npos)
      << run.err;
}

// A 4000×3000 pair passes the pixel limit but needs about 190 MB to
// evaluate. Under a 450 MB address-space limit (ulimit -v) bosfuse has about
// 95 MB left once it is loaded and has decoded both images: the field is
// refused before anything of image size is allocated, with what it needs and
// what is available, instead of ending in std::bad_alloc (what it did without
// the check, or OpenCV's "Insufficient memory", or a failed pthread_create).
// Probes need only their crops and still run; with a 4 GB limit the same
// pair is evaluated.
TEST_F(EvaluateCli, APairTooLargeForTheMemoryLimitIsRefusedBeforeItAllocates) {
#ifdef BOSFUSE_SANITIZED
  GTEST_SKIP() << "sanitizers reserve terabytes of address space: no ulimit -v fits them";
#endif
  cv::Mat noise(3000, 4000, CV_32F), shifted;
  cv::randu(noise, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, {0, 0}, 1.0);
  cv::warpAffine(noise, shifted, cv::Matx23d(1, 0, 0.4, 0, 1, -0.3), noise.size(), cv::INTER_LINEAR,
                 cv::BORDER_REFLECT);
  const std::vector<int> fast_png{cv::IMWRITE_PNG_COMPRESSION, 1};
  for (const auto& [name, image] : {std::pair{"big_ref.png", noise}, std::pair{"big_meas.png", shifted}}) {
    cv::Mat grey;
    image.convertTo(grey, CV_8U, 255.0);
    ASSERT_TRUE(cv::imwrite(path(name), grey, fast_png));
  }
  const std::string pair = path("big_ref.png") + " " + path("big_meas.png");
  auto limited = [&](int megabytes, const std::string& args) {
    return testing::run_command(
        "sh -c 'ulimit -v " + std::to_string(megabytes * 1024) + " && exec " + kBosfuse + " evaluate " + args + "'",
        120);
  };
  const auto refused = limited(450, pair + " -o " + path("big.csv"));
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("a 4000×3000 pair needs "), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("to evaluate with these settings (window 16 px, step 8 px, 3 passes); "),
            std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("are available to this process (the least of MemAvailable "), std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("ulimit -v "), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("use probe mode (--probe), or a machine with more memory"), std::string::npos)
      << refused.output;
  for (const char* failure : {"bad_alloc", "Insufficient memory", "pthread_create"}) {
    EXPECT_EQ(refused.output.find(failure), std::string::npos) << refused.output;
  }
  EXPECT_FALSE(std::filesystem::exists(path("big.csv"))) << "refused before any output";
  // A sequence is refused before its file is laid out, not frame by frame.
  const auto sequence =
      limited(450, "--reference " + path("big_ref.png") + " --sequence " + path("big_meas.png") + " -o " + path("big.h5"));
  EXPECT_EQ(sequence.exit_code, 1) << sequence.output;
  EXPECT_NE(sequence.output.find("a 4000×3000 pair needs "), std::string::npos) << sequence.output;
  EXPECT_FALSE(std::filesystem::exists(path("big.h5"))) << "refused before any output";

  const auto probes = limited(450, pair + " --probe 1000,1000 --probe 3000,2000");
  ASSERT_EQ(probes.exit_code, 0) << probes.output;
  EXPECT_NE(probes.output.find("2 vectors, 2 valid"), std::string::npos) << probes.output;

  const auto evaluated = limited(4000, pair + " -o " + path("big.csv"));
  ASSERT_EQ(evaluated.exit_code, 0) << evaluated.output;
  const std::string csv = read(path("big.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + ((4000 - 16) / 8 + 1) * ((3000 - 16) / 8 + 1));
}

TEST_F(EvaluateCli, ColourImagesAreConvertedWithAWarning) {
  for (const char* name : {"ref", "meas"}) {
    cv::Mat colour;
    cv::cvtColor(cv::imread(path(std::string(name) + ".png"), cv::IMREAD_GRAYSCALE), colour, cv::COLOR_GRAY2BGR);
    cv::imwrite(path(std::string(name) + "_rgb.png"), colour);
  }
  const auto run = bosfuse("evaluate " + path("ref_rgb.png") + " " + path("meas_rgb.png") + " -o " + path("c.csv"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("colour image (3 channels) converted to grey"), std::string::npos) << run.output;
}

TEST_F(EvaluateCli, FlowMethodWritesTheSameGrid) {
  const auto run =
      bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " --method flow -o " + path("flow.csv"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string csv = read(path("flow.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 15 * 11);
}

TEST_F(EvaluateCli, DisPresetIsChosenAndAnUnknownOneIsNamed) {
  const std::string pair = path("ref.png") + " " + path("meas.png") + " --method flow -o ";
  const auto medium = bosfuse("evaluate " + pair + path("medium.csv"));
  ASSERT_EQ(medium.exit_code, 0) << medium.output;
  const auto ultrafast = bosfuse("evaluate " + pair + path("ultrafast.csv") + " --dis-preset ultrafast");
  ASSERT_EQ(ultrafast.exit_code, 0) << ultrafast.output;
  const auto again = bosfuse("evaluate " + pair + path("medium_again.csv") + " --dis-preset medium");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(read(path("medium_again.csv")), read(path("medium.csv"))) << "medium is the default";
  EXPECT_NE(read(path("ultrafast.csv")), read(path("medium.csv"))) << "another preset, another field";
  const auto unknown = bosfuse("evaluate " + path("ref.png") + " " + path("meas.png") + " --dis-preset slow");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("--dis-preset"), std::string::npos) << unknown.output;
}

TEST_F(EvaluateCli, BackgroundAndQuality) {
  const auto made = bosfuse("background --out " + path("bg.png") +
                            " --width 200 --height 120 --dot-mm 0.3 --dpi 600 --coverage 0.3 --seed 4");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_NEAR(sim::read_png_dpi(path("bg.png")), 600, 0.05);
  cv::Mat captured;
  cv::imread(path("bg.png"), cv::IMREAD_GRAYSCALE).convertTo(captured, CV_8U, 0.5, 30);
  cv::imwrite(path("captured.png"), captured);
  const auto q = streams("quality " + path("captured.png") + " --reference " + path("bg.png") + " --json - --map " +
                         path("q.png"));
  ASSERT_EQ(q.exit_code, 0) << q.err;
  const auto json = nlohmann::json::parse(q.out);
  EXPECT_GT(json.at("q_mod").get<double>(), 0.2);
  EXPECT_LT(json.at("q_mod").get<double>(), 0.9);
  EXPECT_NEAR(json.at("q_mod").get<double>(), json.at("q_l").get<double>() * json.at("q_c").get<double>(), 1e-9);
  EXPECT_FALSE(cv::imread(path("q.png")).empty());
}

// Command-line conventions (issue 11): `-o -` is standard output, which then
// holds the CSV and nothing else; the summary is a message on stderr.
TEST_F(EvaluateCli, DashIsStandardOutputWithOnlyTheCsvOnIt) {
  const auto dash = streams("evaluate " + path("ref.png") + " " + path("meas.png") + " -o -");
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  EXPECT_TRUE(dash.out.starts_with("x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v\n")) << dash.out.substr(0, 200);
  EXPECT_EQ(std::count(dash.out.begin(), dash.out.end(), '\n'), 1 + 15 * 11);
  EXPECT_NE(dash.err.find("vectors"), std::string::npos) << "the summary goes to stderr: " << dash.err;
  EXPECT_EQ(dash.err.find("x,y,u,v"), std::string::npos) << dash.err;
  const auto plain = streams("evaluate " + path("ref.png") + " " + path("meas.png"));
  EXPECT_EQ(plain.out, dash.out) << "no -o is standard output too";

  const auto to_file = streams("evaluate " + path("ref.png") + " " + path("meas.png") + " --out " + path("f.csv"));
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  EXPECT_EQ(to_file.out, "");
  EXPECT_EQ(read(path("f.csv")), dash.out);
  EXPECT_NE(to_file.err.find("wrote " + path("f.csv")), std::string::npos) << to_file.err;
}

// One spelling per option: the map image is --map here as in `quality`.
TEST_F(EvaluateCli, TheMapIsWrittenWithMapAndNeedsAFileName) {
  const auto old_spelling = streams("evaluate " + path("ref.png") + " " + path("meas.png") + " --png " + path("m.png"));
  EXPECT_NE(old_spelling.exit_code, 0);
  EXPECT_NE(old_spelling.err.find("--png"), std::string::npos) << old_spelling.err;
  const auto dash = streams("evaluate " + path("ref.png") + " " + path("meas.png") + " --map -");
  EXPECT_NE(dash.exit_code, 0);
  EXPECT_EQ(dash.out, "") << "refused before any work";
  EXPECT_NE(dash.err.find("--map cannot be standard output ('-'): the image format comes from the file name"),
            std::string::npos)
      << dash.err;
}

// Usage mistakes exit with CLI11's code for a refused value, as the
// parser's own refusals do (README, "Exit statuses").
TEST_F(EvaluateCli, UsageMistakesExitWithCli11sValidationCode) {
  constexpr int kValidationError = 105;
  const std::string pair = "evaluate " + path("ref.png") + " " + path("meas.png");
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {" --window 7", "window must be 8 to 128 px, not 7"},
           {" --probe 12", "probe '12' must be x,y in pixels"},
           {" --probe 5000,10", "probe '5000,10' lies outside the"},
           {" --roi 1,2,3", "--roi '1,2,3' needs 4 numbers"},
           {" --sequence 'x*.png'", "--sequence takes the reference as --reference REF"}}) {
    SCOPED_TRACE(args);
    const auto run = streams(pair + args);
    EXPECT_EQ(run.exit_code, kValidationError) << run.err;
    EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
  }
}

// One ROI parser serves evaluate and process: a ROI of no width or height
// is a usage mistake that names the option, before any image is read.
TEST_F(EvaluateCli, ARoiOfNoWidthIsRefusedAsAUsageMistake) {
  constexpr int kValidationError = 105;
  for (const char* roi : {"0,0,0,10", "0,0,10,0", "-1,0,10,10", "0,0,10,10x"}) {
    const auto run = streams("evaluate " + path("ref.png") + " " + path("meas.png") + " --roi " + roi);
    EXPECT_EQ(run.exit_code, kValidationError) << roi << ": " << run.err;
    EXPECT_NE(run.err.find("--roi '" + std::string(roi) + "'"), std::string::npos) << run.err;
    EXPECT_EQ(run.out, "") << roi;
  }
  const auto sequence = streams("evaluate --reference " + path("ref.png") + " --sequence " + path("meas.png") +
                                " -o " + path("s.h5") + " --roi 0,0,0,10");
  EXPECT_EQ(sequence.exit_code, kValidationError) << sequence.err;
  EXPECT_NE(sequence.err.find("width and height at least 1"), std::string::npos) << sequence.err;
}

// An output's format is checked before anything is written (issue 31).
TEST_F(EvaluateCli, AMapThatIsNotAPngIsRefusedBeforeTheCsvIsWritten) {
  const auto jpeg = streams("evaluate " + path("ref.png") + " " + path("meas.png") + " -o " + path("f.csv") +
                            " --map " + path("m.jpg"));
  EXPECT_NE(jpeg.exit_code, 0);
  EXPECT_NE(jpeg.err.find("a figure is named by its PNG file (name.png)"), std::string::npos) << jpeg.err;
  EXPECT_FALSE(std::filesystem::exists(path("f.csv"))) << "the CSV was written before the map was refused";
  EXPECT_FALSE(std::filesystem::exists(path("m.jpg")));
}

TEST_F(EvaluateCli, QualityTextIsTheOutputUnlessJsonTakesStandardOutput) {
  const auto made = bosfuse("background --out " + path("bg.png") + " --width 160 --height 120 --seed 2");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const std::string quality = "quality " + path("bg.png") + " --reference " + path("bg.png");

  const auto text = streams(quality);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_TRUE(text.out.starts_with("Q_L   1.000")) << text.out;
  EXPECT_EQ(text.err, "");

  const auto dash = streams(quality + " --json -");
  ASSERT_EQ(dash.exit_code, 0) << dash.err;
  const auto json = nlohmann::json::parse(dash.out);  // throws on anything but one JSON document
  EXPECT_DOUBLE_EQ(json.at("q_mod").get<double>(), 1.0);
  EXPECT_EQ(dash.err, text.out) << "the text moves to stderr";

  const auto to_file = streams(quality + " --json " + path("q.json"));
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  EXPECT_EQ(to_file.out, text.out);
  EXPECT_EQ(nlohmann::json::parse(read(path("q.json"))), json);
  EXPECT_NE(to_file.err.find("wrote " + path("q.json")), std::string::npos) << to_file.err;

  const auto quiet = streams(quality + " --json - -q");
  EXPECT_EQ(nlohmann::json::parse(quiet.out), json);
  EXPECT_EQ(quiet.err, "") << "--quiet leaves only warnings and errors";

  const auto bare = streams(quality + " --json");
  EXPECT_NE(bare.exit_code, 0) << "--json takes FILE or -";
}

TEST_F(EvaluateCli, ABackgroundPatternIsAFileNotStandardOutput) {
  const auto refused = streams("background --out - --width 160 --height 120");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_EQ(refused.out, "");
  EXPECT_NE(refused.err.find("--out cannot be standard output ('-')"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "-"));
}

// A pair lit through a glow that does not move with the pattern: highpass
// takes it out, so the field is nearer the truth than without, and the
// summary says which preprocessing was used.
TEST_F(EvaluateCli, PreprocessHighpassIsChosenReportedAndHelpsUnderAGlow) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = 128;
  options.noise_std = 0.003;
  options.bit_depth = 16;
  options.field = sim::DisplacementModel::uniform(0.6, 0.35);
  const auto pair = sim::render_pair(options);
  cv::Mat glow(pair.reference.size(), CV_32F);
  for (int y = 0; y < glow.rows; ++y) {
    for (int x = 0; x < glow.cols; ++x) {
      glow.at<float>(y, x) = 0.35f * (1 + static_cast<float>(std::sin(x / 5.0) * std::cos(y / 6.0)));
    }
  }
  for (const auto& [image, name] : {std::pair{pair.reference, "glow_ref.png"}, {pair.measurement, "glow_meas.png"}}) {
    cv::Mat lit;
    image.convertTo(lit, CV_32F, 0.5 / 65535.0);
    lit += glow;
    lit.convertTo(lit, CV_16U, 65535.0);
    cv::imwrite(path(name), lit);
  }
  const std::string glow_pair = "evaluate " + path("glow_ref.png") + " " + path("glow_meas.png");
  struct Measured {
    int valid = 0;
    double mean_error_px = 0;
  };
  const auto measured = [&](const std::string& csv) {
    std::istringstream lines(read(csv));
    std::string line;
    std::getline(lines, line);
    Measured m;
    double sum = 0;
    for (int rows = 0; std::getline(lines, line) && rows < 10000; ++rows) {
      double x, y, u, v;
      int ok;
      if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%d", &x, &y, &u, &v, &ok) != 5 || !ok) continue;
      sum += std::hypot(u - 0.6, v - 0.35);
      ++m.valid;
    }
    m.mean_error_px = m.valid ? sum / m.valid : 0;
    return m;
  };
  const auto plain = bosfuse(glow_pair + " -o " + path("plain.csv"));
  const auto filtered = bosfuse(glow_pair + " --preprocess highpass -o " + path("highpass.csv"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  ASSERT_EQ(filtered.exit_code, 0) << filtered.output;
  EXPECT_NE(plain.output.find("preprocessing: none"), std::string::npos) << plain.output;
  EXPECT_NE(filtered.output.find("preprocessing: highpass"), std::string::npos) << filtered.output;
  // The glow dominates the unfiltered correlation: its windows show no clear
  // peak and are flagged, never valid and wrong, and the warning names the fix.
  const Measured none = measured(path("plain.csv")), highpass = measured(path("highpass.csv"));
  EXPECT_GT(highpass.valid, 200) << filtered.output;
  EXPECT_LT(highpass.mean_error_px, 0.05);
  EXPECT_LT(none.valid, highpass.valid / 2) << plain.output;
  if (none.valid > 0) {
    EXPECT_LT(highpass.mean_error_px, 0.8 * none.mean_error_px);
  }
  EXPECT_NE(plain.output.find("try --preprocess highpass"), std::string::npos) << plain.output;
  // An unknown name is a usage error that lists the valid ones.
  const auto unknown = streams(glow_pair + " --preprocess clahe");
  EXPECT_EQ(unknown.exit_code, 105) << unknown.err;
  EXPECT_NE(unknown.err.find("none, normalize, highpass, minmax"), std::string::npos) << unknown.err;
}

}  // namespace
}  // namespace bosfuse
