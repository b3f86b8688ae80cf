// The GenICam source: pixel unpacking and the camera-clock mapping on their
// own, then against Aravis' fake GigE Vision camera (arv-fake-gv-camera-0.8)
// on 127.0.0.1: frames at the requested rate, depth and size; timestamps
// increasing and mapped; settings outside the camera's limits refused with
// the feature's name and range; a killed and restarted camera; injected
// packet loss counted. The fake camera's control port is fixed (GVCP,
// 3956): the GenicamFakeCamera tests hold the ctest resource lock
// genicam_gvcp (acquisition/CMakeLists.txt) so none run side by side.

#include "acquisition/cameras/genicam_source.h"

#include <arpa/inet.h>
#include <arv.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <optional>
#include <random>
#include <thread>

#include "acquisition/cameras/frame_recorder.h"
#include "acquisition/cameras/genicam_cameras.h"
#include "acquisition/cameras/genicam_link_budget.h"
#include "acquisition/cameras/genicam_pixels.h"
#include "acquisition/clock.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;

TEST(GenicamPixels, UnpacksGigEVisionMono12Packed) {
  // p0 = 0xABC, p1 = 0x123: B0 = 0xAB, B1 = (0x3 << 4) | 0xC, B2 = 0x12.
  const std::uint8_t data[] = {0xAB, 0x3C, 0x12};
  const cv::Mat image = genicam_pixels_to_image("Mono12Packed", data, sizeof data, 2, 1);
  ASSERT_EQ(image.type(), CV_16UC1);
  EXPECT_EQ(image.at<std::uint16_t>(0, 0), 0xABC);
  EXPECT_EQ(image.at<std::uint16_t>(0, 1), 0x123);
}

TEST(GenicamPixels, UnpacksPfncMono12pAndMono10p) {
  // Mono12p: p0 = 0xABC, p1 = 0x123 from the least significant bit: 0xBC, 0x3A, 0x12.
  const std::uint8_t twelve[] = {0xBC, 0x3A, 0x12};
  const cv::Mat a = genicam_pixels_to_image("Mono12p", twelve, sizeof twelve, 2, 1);
  EXPECT_EQ(a.at<std::uint16_t>(0, 0), 0xABC);
  EXPECT_EQ(a.at<std::uint16_t>(0, 1), 0x123);
  // Mono10p: four pixels 1023, 0, 512, 1 in five bytes.
  const std::uint64_t bits = 1023ull | (0ull << 10) | (512ull << 20) | (1ull << 30);
  std::uint8_t ten[5];
  for (int i = 0; i < 5; ++i) ten[i] = static_cast<std::uint8_t>(bits >> (8 * i));
  const cv::Mat b = genicam_pixels_to_image("Mono10p", ten, sizeof ten, 4, 1);
  EXPECT_EQ(b.at<std::uint16_t>(0, 0), 1023);
  EXPECT_EQ(b.at<std::uint16_t>(0, 1), 0);
  EXPECT_EQ(b.at<std::uint16_t>(0, 2), 512);
  EXPECT_EQ(b.at<std::uint16_t>(0, 3), 1);
}

TEST(GenicamPixels, KeepsMono16AndMono8ValuesAndRefusesShortBuffers) {
  const std::uint8_t data[] = {0xFF, 0x0F, 0x01, 0x00};  // little-endian 4095, 1
  const cv::Mat deep = genicam_pixels_to_image("Mono12", data, sizeof data, 2, 1);
  EXPECT_EQ(deep.at<std::uint16_t>(0, 0), 4095);
  EXPECT_EQ(deep.at<std::uint16_t>(0, 1), 1);
  EXPECT_EQ(genicam_pixels_to_image("Mono8", data, sizeof data, 4, 1).type(), CV_8UC1);
  EXPECT_THROW(genicam_pixels_to_image("Mono16", data, sizeof data, 3, 1), std::invalid_argument);
  EXPECT_THROW(genicam_pixels_to_image("BayerRG8", data, sizeof data, 2, 1), std::invalid_argument);
}

TEST(GenicamClockMapping, RecoversAKnownOffsetAndDriftWithItsResidual) {
  // A camera clock 1234.5 s behind the host, running 50 ppm slow, read
  // with 200 µs of uniform latency jitter every 50 ms for 10 minutes.
  const double offset_ns = 1234.5e9, drift = -50e-6;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter_ns(0, 200e3);
  GenicamClockMapping mapping(GenicamClockMapping::Pairs::kLatched, 2048);
  const std::int64_t host0 = 1'700'000'000'000'000'000;
  for (int i = 0; i < 12'000; ++i) {
    const std::int64_t host = host0 + std::int64_t{i} * 50'000'000;
    const auto camera = static_cast<std::int64_t>((static_cast<double>(host - host0) + 1e9) * (1 + drift));
    mapping.add(camera, host + static_cast<std::int64_t>(jitter_ns(random)));
  }
  const auto fit = mapping.fit();
  ASSERT_TRUE(fit);
  EXPECT_LE(fit->pairs, 2048u);
  EXPECT_NEAR(fit->drift, 1 / (1 + drift) - 1, 1e-7);
  // The mapping is within the jitter's spread of the true host time, and says so.
  const std::int64_t camera_at_5min = static_cast<std::int64_t>((300e9 + 1e9) * (1 + drift));
  EXPECT_NEAR(static_cast<double>(*mapping.map(camera_at_5min) - (host0 + 300'000'000'000)), 100e3, 20e3);
  EXPECT_NEAR(fit->residual_rms_ns, 200e3 / std::sqrt(12.0), 10e3);
  EXPECT_LE(fit->residual_max_ns, 1e6);  // the issue's target: ≤ 1 ms over 10 minutes
  (void)offset_ns;
  EXPECT_NE(GenicamClockMapping::describe(*fit).find("ppm"), std::string::npos);
}

// Arrivals: the true host time of each camera stamp plus a latency that is
// never negative: a 40 µs floor, exponential jitter (200 µs mean), 3 % of
// heavy-tailed spikes (Pareto, up to seconds) and an 80 s stretch of load
// where every frame is 20 ms later. 20 frames/s for 10 minutes, the camera
// 3.5 s ahead and 40 ppm fast.
struct GenicamArrivalTrial {
  static constexpr double kOffsetNs = 3.5e9, kDrift = 40e-6, kFloorNs = 40e3;
  static constexpr std::int64_t kHost0Ns = 1'700'000'000'000'000'000;
  std::int64_t camera_at(std::int64_t host_ns) const {
    const double since = static_cast<double>(host_ns - kHost0Ns);
    return kHost0Ns + static_cast<std::int64_t>(std::llround(kOffsetNs + since * (1 + kDrift)));
  }
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;  // (camera, arrival)
  std::vector<std::int64_t> true_host;                       // each pair's stamp on the host clock

  explicit GenicamArrivalTrial(unsigned seed) {
    std::mt19937 random(seed);
    std::exponential_distribution<double> jitter(1 / 200e3);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int i = 0; i < 12'000; ++i) {
      const std::int64_t host = kHost0Ns + std::int64_t{i} * 50'000'000;
      double latency = kFloorNs + jitter(random);
      if (unit(random) < 0.03) latency += 1e6 * std::min(1e3, std::pow(1 - unit(random), -1 / 1.2) - 1);
      if (i >= 4000 && i < 5600) latency += 20e6;
      pairs.emplace_back(camera_at(host), host + static_cast<std::int64_t>(latency));
      true_host.push_back(host);
    }
  }
  // The largest |mapped − true host − floor| over every pair.
  double worst_error_ns(const GenicamClockMapping& mapping) const {
    double worst = 0;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const double error = static_cast<double>(*mapping.map(pairs[i].first) - true_host[i]) - kFloorNs;
      worst = std::max(worst, std::abs(error));
    }
    return worst;
  }
};

TEST(GenicamClockMapping, FitsTheLowerEnvelopeOfArrivalsWithHeavyTailedLatency) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const GenicamArrivalTrial trial(seed);
    GenicamClockMapping envelope(GenicamClockMapping::Pairs::kArrivals, 4096);
    GenicamClockMapping least_squares(GenicamClockMapping::Pairs::kLatched, 4096);
    for (const auto& [camera, arrival] : trial.pairs) {
      envelope.add(camera, arrival);
      least_squares.add(camera, arrival);
    }
    const auto fit = envelope.fit();
    ASSERT_TRUE(fit);
    EXPECT_EQ(fit->kind, GenicamClockMapping::Pairs::kArrivals);
    EXPECT_LE(fit->pairs, 4096u);
    EXPECT_GE(fit->envelope_pairs, 8u);  // of 16 stretches of 37.5 s ...
    EXPECT_LT(fit->envelope_pairs, 16u) << seed;  // ... one of them loaded throughout, left out
    EXPECT_NEAR(fit->drift, 1 / (1 + GenicamArrivalTrial::kDrift) - 1, 0.2e-6) << seed;
    // Every stamp mapped within 100 µs of its true host time plus the floor
    // the envelope cannot see, and so within the issue's 1 ms.
    EXPECT_LE(trial.worst_error_ns(envelope), 100e3) << seed;
    EXPECT_LE(trial.worst_error_ns(envelope) + GenicamArrivalTrial::kFloorNs, 1e6) << seed;
    // The stated residual is the envelope's spread, small beside the
    // latency it removed; the latency above it is stated apart.
    EXPECT_LT(fit->residual_rms_ns, 50e3) << seed;
    EXPECT_NEAR(fit->latency_median_ns, 200e3 * std::log(2.0), 60e3) << seed;
    EXPECT_GT(fit->latency_max_ns, 5e6) << seed;
    EXPECT_GE(fit->latency_pairs, 2048u);
    EXPECT_NE(GenicamClockMapping::describe(*fit).find("lower envelope"), std::string::npos);
    // A least-squares line through the same arrivals carries their mean
    // latency: milliseconds off, which is why arrivals are not fitted so.
    EXPECT_GT(trial.worst_error_ns(least_squares), 1e6) << seed;
  }
}

TEST(GenicamLinkBudget, RefusesARateTheLinkCannotCarryNamingTheFigures) {
  GenicamLinkBudget budget;
  budget.frame_rate_hz = 20;
  budget.payload_bytes = 2048 * 2048 * 2;  // 8.4 MB: 168 MB/s at 20 frames/s
  budget.link_bytes_per_s = genicam_link_bytes_per_s("GevLinkSpeed", 1000);  // 1 Gbit/s: 125 MB/s
  budget.link_feature = "GevLinkSpeed";
  EXPECT_DOUBLE_EQ(budget.link_bytes_per_s, 125e6);
  const std::string problem = budget.problem();
  EXPECT_NE(problem.find("20 frames/s"), std::string::npos) << problem;
  EXPECT_NE(problem.find("8388608 bytes"), std::string::npos) << problem;
  EXPECT_NE(problem.find("167.8 MB/s"), std::string::npos) << problem;
  EXPECT_NE(problem.find("GevLinkSpeed = 125.0 MB/s"), std::string::npos) << problem;
  EXPECT_NE(problem.find("at most 14.9 frames/s"), std::string::npos) << problem;
  budget.frame_rate_hz = 14.9;
  EXPECT_EQ(budget.problem(), "");
  // Nothing to check: no rate asked, or no link figure reported.
  budget.frame_rate_hz = 0;
  EXPECT_EQ(budget.problem(), "");
  budget.frame_rate_hz = 100;
  budget.link_bytes_per_s = 0;
  EXPECT_EQ(budget.problem(), "");
  EXPECT_DOUBLE_EQ(genicam_link_bytes_per_s("DeviceLinkThroughputLimit", 3e8), 3e8);
  EXPECT_DOUBLE_EQ(genicam_link_bytes_per_s("DeviceLinkSpeed", 4e8), 4e8);
  EXPECT_DOUBLE_EQ(genicam_link_bytes_per_s("SomethingElse", 1), 0);
}

TEST(GenicamOptions, RefusesWhatNeedsNoCamera) {
  GenicamOptions o;
  EXPECT_NE(o.Validate().find("device"), std::string::npos);
  o.device = "127.0.0.1";
  EXPECT_EQ(o.Validate(), "");
  o.pixel_format = "RGB8";
  EXPECT_NE(o.Validate().find("pixel_format"), std::string::npos);
  o.pixel_format = "Mono12p";
  o.exposure_us = -1;
  EXPECT_NE(o.Validate().find("exposure_us"), std::string::npos);
}

// Whether nothing holds the GigE Vision control port on loopback: a bind,
// at once, where asking a camera that is not there waits out its timeouts.
bool genicam_gvcp_port_free() {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(3956);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool free = bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  close(fd);
  return free;
}

// arv-fake-gv-camera-0.8 on 127.0.0.1, started for one test and waited for
// (bounded) until it answers.
class GenicamFakeGvCamera {
 public:
  explicit GenicamFakeGvCamera(int lost_packets_per_thousand = 0) { start(lost_packets_per_thousand); }

  void start(int lost_packets_per_thousand = 0) {
    // A camera left answering (a crashed test's) would be read instead of ours.
    ASSERT_TRUE(genicam_gvcp_port_free()) << "127.0.0.1:3956 (GVCP) is taken: a fake camera left running?";
    // setpriv: the fake camera dies with this process, even when it crashes.
    std::vector<std::string> argv = {"setpriv", "--pdeathsig", "KILL", "arv-fake-gv-camera-0.8",
                                     "-i",      "127.0.0.1",   "-s",   "BOS01"};
    if (lost_packets_per_thousand > 0) {
      argv.insert(argv.end(), {"-r", std::to_string(lost_packets_per_thousand)});
    }
    process_.emplace(argv);
    for (int i = 0; i < 50; ++i) {  // up to 5 s
      if (list_genicam_cameras({"127.0.0.1"}, false).front().problem.empty()) return;
      std::this_thread::sleep_for(100ms);
    }
    FAIL() << "arv-fake-gv-camera-0.8 did not answer on 127.0.0.1 within 5 s";
  }
  void kill_now() {
    process_->send_signal(SIGKILL);
    process_.reset();
  }

 private:
  std::optional<testing::BackgroundProcess> process_;
};

GenicamOptions genicam_fake_options() {
  GenicamOptions o;
  o.device = "127.0.0.1";
  o.pixel_format = "Mono16";
  o.roi = GenicamRoi{0, 0, 320, 240};
  o.frame_rate_hz = 20;
  o.frame_timeout = 300ms;
  o.clock_report_period = 500ms;
  return o;
}

TEST(GenicamFakeCamera, RecordsFramesAtTheRequestedRateDepthAndSizeWithMappedTimestamps) {
  GenicamFakeGvCamera fake;
  GenicamSource source(genicam_fake_options());
  source.connect();
  EXPECT_EQ(source.streaming().pixel_format, "Mono16");
  std::vector<CapturedFrame> frames;
  std::vector<FrameSource::Note> notes;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < 1500ms) {
    if (auto frame = source.next(100ms)) frames.push_back(std::move(*frame));
    for (auto& note : source.take_notes()) notes.push_back(note);
  }
  source.disconnect();
  // 20 frames/s for 1.5 s, give or take the start.
  ASSERT_GE(frames.size(), 24u);
  EXPECT_LE(frames.size(), 32u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const CapturedFrame& f = frames[i];
    EXPECT_EQ(f.image.type(), CV_16UC1);
    EXPECT_EQ(f.image.cols, 320);
    EXPECT_EQ(f.image.rows, 240);
    ASSERT_TRUE(f.device_t_ns && f.arrival_ns);
    // Mapped to the host clock: within a frame period of the arrival.
    EXPECT_LT(std::abs(f.t_ns - *f.arrival_ns), 50'000'000) << i;
    if (i > 0) {
      EXPECT_GT(*f.device_t_ns, *frames[i - 1].device_t_ns);
      EXPECT_GT(f.t_ns, frames[i - 1].t_ns);
    }
  }
  // The camera's own frame period, median of its timestamps' steps.
  std::vector<double> periods_s;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    periods_s.push_back(static_cast<double>(*frames[i].device_t_ns - *frames[i - 1].device_t_ns) * 1e-9);
  }
  std::nth_element(periods_s.begin(), periods_s.begin() + periods_s.size() / 2, periods_s.end());
  EXPECT_NEAR(periods_s[periods_s.size() / 2], 0.05, 0.005);
  const auto clock = std::find_if(notes.begin(), notes.end(), [](const auto& n) { return n.kind == "clock"; });
  ASSERT_NE(clock, notes.end());
  EXPECT_NE(clock->message.find("residual"), std::string::npos) << clock->message;
}

TEST(GenicamFakeCamera, RefusesSettingsOutsideItsLimitsNamingFeatureAndRange) {
  GenicamFakeGvCamera fake;
  auto refusal = [](GenicamOptions o) -> std::string {
    try {
      GenicamSource::check_settings(o);
    } catch (const GenicamSettingRefused& e) {
      return e.what();
    }
    return "accepted";
  };
  GenicamOptions o = genicam_fake_options();
  o.exposure_us = 1e9;
  o.frame_rate_hz.reset();
  const std::string exposure = refusal(o);
  EXPECT_NE(exposure.find("exposure_us: ExposureTimeAbs 1e+09 µs is outside the camera's range ["), std::string::npos)
      << exposure;
  o = genicam_fake_options();
  o.frame_rate_hz = 1e6;
  const std::string rate = refusal(o);
  EXPECT_NE(rate.find("frame_rate_hz: AcquisitionFrameRate"), std::string::npos) << rate;
  EXPECT_NE(rate.find("range ["), std::string::npos) << rate;
  o = genicam_fake_options();
  o.gain_db = 3;
  EXPECT_NE(refusal(o).find("gain_db: the camera has no Gain feature in dB; it has GainRaw"), std::string::npos);
  o = genicam_fake_options();
  o.roi = GenicamRoi{0, 0, 4096, 4096};
  EXPECT_NE(refusal(o).find("roi_px"), std::string::npos);
  o = genicam_fake_options();
  o.features = {{"NoSuchFeature", std::int64_t{1}}};
  EXPECT_NE(refusal(o).find("features.NoSuchFeature: the camera has no feature"), std::string::npos);
  o = genicam_fake_options();
  o.features = {{"GainRaw", std::int64_t{100000}}};
  EXPECT_NE(refusal(o).find("features.GainRaw: GainRaw 100000 is outside the camera's range ["), std::string::npos)
      << refusal(o);
  EXPECT_EQ(refusal(genicam_fake_options()), "accepted");
}

TEST(GenicamFakeCamera, IsListedByAddressWithItsIdAndPixelFormats) {
  GenicamFakeGvCamera fake;
  const auto cameras = list_genicam_cameras({"127.0.0.1"}, false);
  ASSERT_EQ(cameras.size(), 1u);
  EXPECT_EQ(cameras[0].problem, "");
  EXPECT_NE(cameras[0].id.find("BOS01"), std::string::npos) << cameras[0].id;
  EXPECT_EQ(cameras[0].serial, "BOS01");
  EXPECT_EQ(cameras[0].protocol, "GigEVision");
  EXPECT_NE(std::find(cameras[0].pixel_formats.begin(), cameras[0].pixel_formats.end(), "Mono16"),
            cameras[0].pixel_formats.end());
}

struct GenicamRecorderBed {
  testing::TempDir dir;
  storage::RunStore store =
      storage::RunStore::create(dir / "run", {0, "t", 0, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                storage::RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "cam", "camera", "genicam", "127.0.0.1"});
  storage::RunWriter writer{store, {20ms, 10'000}};
  std::shared_ptr<FrameRecorder> recorder;

  explicit GenicamRecorderBed(GenicamOptions options) {
    FrameRecorderOptions recorder_options;
    recorder_options.backoff = {100ms, 400ms};
    recorder_options.recovery_frames = 2;
    recorder = std::make_shared<FrameRecorder>(std::make_unique<GenicamSource>(std::move(options)), "cam", device,
                                               store.dir(), writer, recorder_options);
    recorder->start();
  }
  ~GenicamRecorderBed() { recorder->stop(); }  // a failed test leaves no recorder reading the next test's camera
  // Waits (bounded) until `done` holds.
  bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      if (done()) return true;
      std::this_thread::sleep_for(20ms);
    }
    return done();
  }
  std::vector<storage::Event> events() {
    writer.flush();
    return store.events();
  }
  bool has_event(const std::string& kind) {
    const auto all = events();
    return std::any_of(all.begin(), all.end(), [&](const storage::Event& e) { return e.kind == kind; });
  }
};

TEST(GenicamFakeCamera, KilledAndRestartedCameraIsADisconnectThenAReconnect) {
  GenicamFakeGvCamera fake;
  GenicamRecorderBed bed(genicam_fake_options());
  ASSERT_TRUE(bed.wait_for([&] { return bed.recorder->stats().frames >= 5; }, 3s));
  fake.kill_now();
  ASSERT_TRUE(bed.wait_for([&] { return bed.has_event("disconnect"); }, 6s));
  const std::int64_t frames_before = bed.recorder->stats().frames;
  fake.start();
  ASSERT_TRUE(bed.wait_for([&] { return bed.has_event("reconnect"); }, 6s));
  EXPECT_TRUE(bed.wait_for([&] { return bed.recorder->stats().frames >= frames_before + 5; }, 3s));
  EXPECT_TRUE(bed.recorder->stop());
  bed.writer.flush();
  EXPECT_GE(bed.store.frames().size(), 10u);
  // Every frame keeps the camera's time and the host's arrival beside the mapped t_ns.
  const auto kept =
      testing::run_command("sqlite3 " + (bed.store.dir() / storage::RunStore::kDatabaseFileName).string() +
                           " 'SELECT COUNT(*) = SUM(device_t_ns IS NOT NULL AND arrival_ns IS NOT NULL) "
                           "FROM frames'");
  EXPECT_EQ(kept.output, "1\n");
}

TEST(GenicamFakeCamera, InjectedPacketLossIsCountedAsLostFrames) {
  GenicamFakeGvCamera fake(100);  // 10 % of the packets lost
  GenicamOptions o = genicam_fake_options();
  o.packet_resend = false;
  GenicamRecorderBed bed(o);
  ASSERT_TRUE(bed.wait_for([&] { return bed.recorder->stats().failures >= 3; }, 4s));
  EXPECT_TRUE(bed.recorder->stop());
  const auto events = bed.events();
  const auto lost = std::count_if(events.begin(), events.end(), [](const storage::Event& e) {
    return (e.kind == "error" && e.message.find("lost") != std::string::npos) || e.kind == "lost-frames";
  });
  EXPECT_GE(lost, 1);
}

// libaravis' fake GigE Vision camera in this process, its clock skewed: a
// known offset and drift from the host's, stamped on each buffer by the
// fill pattern.
struct GenicamSkew {
  double offset_s;  // camera = host0 + offset + (host − host0) · (1 + drift)
  double drift;
  std::int64_t host0_ns;
};

void genicam_skewed_fill(ArvBuffer* buffer, void* data, guint32, guint32, ArvPixelFormat) {
  const auto* skew = static_cast<const GenicamSkew*>(data);
  const double since_ns = static_cast<double>(utc_now_ns() - skew->host0_ns);
  arv_buffer_set_timestamp(buffer, static_cast<guint64>(static_cast<double>(skew->host0_ns) + skew->offset_s * 1e9 +
                                                        since_ns * (1 + skew->drift)));
}

TEST(GenicamFakeCamera, ASkewedCameraClockIsMappedToTheHostWithinItsResidual) {
  const GenicamSkew skew{-1000.0, 0.02, utc_now_ns()};  // 1000 s behind, 2 % fast
  ArvGvFakeCamera* fake = arv_gv_fake_camera_new("127.0.0.1", "SKEW01");
  ASSERT_NE(fake, nullptr);
  ASSERT_TRUE(arv_gv_fake_camera_is_running(fake));
  arv_fake_camera_set_fill_pattern(arv_gv_fake_camera_get_fake_camera(fake), genicam_skewed_fill,
                                   const_cast<GenicamSkew*>(&skew));
  std::vector<CapturedFrame> frames;
  std::vector<FrameSource::Note> notes;
  std::optional<GenicamClockMapping::Fit> fit;
  {
    GenicamOptions o = genicam_fake_options();
    o.pixel_format = "Mono8";
    GenicamSource source(o);
    source.connect();
    const auto start = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - start < 2500ms) {
      if (auto frame = source.next(100ms)) frames.push_back(std::move(*frame));
      for (auto& note : source.take_notes()) notes.push_back(note);
    }
    fit = source.clock_fit();
  }
  g_object_unref(fake);
  ASSERT_GE(frames.size(), 40u);
  // The camera's own time is kept as it came: about 1000 s behind the host.
  EXPECT_NEAR(static_cast<double>(*frames.back().device_t_ns - *frames.back().arrival_ns) * 1e-9, -1000, 10);
  // The fit finds the skew: host ns per camera ns 1 / 1.02 − 1 ≈ −19608 ppm
  // (within what arrival jitter over 2.5 s allows on a loaded machine). It
  // is the arrivals' lower envelope: every frame is mapped to no later than
  // it arrived, by no more than the latency the fit states, and to no
  // earlier than its true host time (the skew inverted) by more than the
  // stated residual.
  ASSERT_TRUE(fit);
  EXPECT_EQ(fit->kind, GenicamClockMapping::Pairs::kArrivals);
  EXPECT_NEAR(fit->drift * 1e6, (1 / 1.02 - 1) * 1e6, 3000);
  for (const CapturedFrame& f : frames) {
    const double mapped =
        fit->host_at_origin_ns + (1 + fit->drift) * static_cast<double>(*f.device_t_ns - fit->camera_origin_ns);
    const double lag_ns = static_cast<double>(*f.arrival_ns) - mapped;
    EXPECT_GE(lag_ns, -1e3) << f.origin;
    EXPECT_LE(lag_ns, fit->latency_max_ns + 1e3) << f.origin;
    const double truth_ns = static_cast<double>(skew.host0_ns) +
                            (static_cast<double>(*f.device_t_ns - skew.host0_ns) - skew.offset_s * 1e9) / (1 + skew.drift);
    EXPECT_GE(mapped - truth_ns, -fit->residual_max_ns - 50e3) << f.origin;
  }
  const auto clock = std::find_if(notes.rbegin(), notes.rend(), [](const auto& n) { return n.kind == "clock"; });
  ASSERT_NE(clock, notes.rend());
  EXPECT_NE(clock->message.find("residual"), std::string::npos) << clock->message;
}

// libaravis' fake camera has no link feature; one served with its own
// GenICam file, the stock one plus a DeviceLinkThroughputLimit of 2 MB/s,
// shows the check at start: 320×240 Mono16 (153,600 bytes) at 20 frames/s
// is 3.1 MB/s, refused naming the figures; at 10 frames/s it fits.
TEST(GenicamFakeCamera, ARateItsLinkCannotCarryIsRefusedAtStartNamingTheFigures) {
  ArvFakeCamera* stock = arv_fake_camera_new("LINK00");
  ASSERT_NE(stock, nullptr);
  size_t size = 0;
  const char* stock_xml = arv_fake_camera_get_genicam_xml(stock, &size);
  std::string xml = stock_xml != nullptr ? std::string(stock_xml, size) : "";
  g_object_unref(stock);
  const std::size_t end = xml.rfind("</RegisterDescription>");
  ASSERT_NE(end, std::string::npos);
  xml.insert(end, R"(<Integer Name="DeviceLinkThroughputLimit" NameSpace="Standard"><Value>2000000</Value></Integer>)"
                  "\n");
  testing::TempDir dir;
  const std::string path = (dir / "link-limited.xml").string();
  std::ofstream(path) << xml;
  ArvGvFakeCamera* fake = arv_gv_fake_camera_new_full("127.0.0.1", "LINK01", path.c_str());
  ASSERT_NE(fake, nullptr);
  ASSERT_TRUE(arv_gv_fake_camera_is_running(fake));
  GenicamOptions o = genicam_fake_options();
  std::string refusal;
  try {
    GenicamSource::check_settings(o);
  } catch (const GenicamSettingRefused& e) {
    refusal = e.what();
  }
  EXPECT_NE(refusal.find("frame_rate_hz"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("153600 bytes (PayloadSize)"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("DeviceLinkThroughputLimit = 2.0 MB/s"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("at most 13.0 frames/s"), std::string::npos) << refusal;
  o.frame_rate_hz = 10;
  EXPECT_NO_THROW(GenicamSource::check_settings(o));
  g_object_unref(fake);
}

}  // namespace
}  // namespace bosfuse::acquisition
