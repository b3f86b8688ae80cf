#include "sim/simulated_genicam_camera.h"

#include <arpa/inet.h>
#include <arv.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "acquisition/clock.h"

namespace bosfuse::sim {

std::string SimulatedGenicamCameraOptions::Validate() const {
  if (serial.empty()) return "simulated camera: serial must not be empty";
  if (address.empty()) return "simulated camera: address must not be empty";
  // The fake camera's AcquisitionFrameRate feature spans 1..100 Hz.
  if (!(frame_rate_hz >= 1 && frame_rate_hz <= 100)) {
    return fmt::format("simulated camera: frame rate {} Hz is outside the fake camera's 1..100 Hz", frame_rate_hz);
  }
  if (!(speed > 0)) return "simulated camera: speed-up must be positive";
  if (reference_frames < 0) return "simulated camera: reference frames must not be negative";
  // Within 11 days of the host (camera timestamps stay positive, and the
  // stamp keeps its nanoseconds in a double) and 10 % of its rate.
  if (!(std::abs(clock_offset_s) <= 1e6)) {
    return fmt::format("simulated camera: clock offset {} s is outside ±1e6 s", clock_offset_s);
  }
  if (!(std::abs(clock_drift_ppm) < 1e5)) {
    return fmt::format("simulated camera: clock drift {} ppm is outside ±1e5 ppm", clock_drift_ppm);
  }
  return "";
}

struct SimulatedGenicamCamera::Impl {
  std::shared_ptr<const ConvectionScene> scene;
  BackgroundPattern pattern;
  CameraModel camera;
  SimulatedGenicamCameraOptions options;
  std::chrono::steady_clock::time_point scene_start;
  std::atomic<std::uint64_t> rendered{0};
  std::int64_t clock_start_ns = 0;  // host UTC time the camera clock's drift counts from
  // How long a frame takes to render, smoothed: the scene is rendered for
  // the instant the frame will be stamped. Only the fill thread uses it.
  std::chrono::nanoseconds render_estimate{0};
  ArvGvFakeCamera* gv_camera = nullptr;
  ArvFakeCamera* fake = nullptr;  // owned by gv_camera

  void fill(ArvBuffer* buffer, ArvPixelFormat pixel_format);
  std::int64_t camera_ns_at(std::int64_t host_ns) const {
    const double since_ns = static_cast<double>(host_ns - clock_start_ns);
    return host_ns + static_cast<std::int64_t>(std::llround(options.clock_offset_s * 1e9 +
                                                            since_ns * options.clock_drift_ppm * 1e-6));
  }
};

namespace {

// The scene's image at the depth the camera streams: Mono8 or Mono16 (the
// deeper format holds the 8-bit rendering in its high byte, as a sensor's
// ADC fills its most significant bits). Other formats are not offered for
// BOS and get a black frame.
cv::Mat simgc_at_depth(const cv::Mat& rendered, ArvPixelFormat pixel_format) {
  cv::Mat out;
  const double to8 = rendered.depth() == CV_16U ? 1.0 / 256 : 1.0;
  const double to16 = rendered.depth() == CV_16U ? 1.0 : 256.0;
  if (pixel_format == ARV_PIXEL_FORMAT_MONO_8) {
    rendered.convertTo(out, CV_8U, to8);
  } else if (pixel_format == ARV_PIXEL_FORMAT_MONO_16) {
    rendered.convertTo(out, CV_16U, to16);
  }
  return out;
}

// Whether `address`:3956 (GVCP) is free. Aravis' fake camera binds it with
// SO_REUSEADDR, so a second one would start beside the first and clients
// would reach either; a bind without it fails while one is there.
bool simgc_gvcp_port_free(const std::string& address) {
  sockaddr_in where{};
  where.sin_family = AF_INET;
  where.sin_port = htons(3956);
  if (inet_pton(AF_INET, address.c_str(), &where.sin_addr) != 1) return false;
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return false;
  const bool free = bind(fd, reinterpret_cast<const sockaddr*>(&where), sizeof where) == 0;
  close(fd);
  return free;
}

// Aravis' fill-pattern callback, on the fake camera's streaming thread.
void simgc_fill_pattern(ArvBuffer* buffer, void* data, guint32 /*exposure_time_us*/, guint32 /*gain*/,
                        ArvPixelFormat pixel_format) {
  static_cast<SimulatedGenicamCamera::Impl*>(data)->fill(buffer, pixel_format);
}

// The region the camera was set to, from the scene's top-left corner.
void simgc_copy_region(const cv::Mat& image, guint32 width, guint32 height, std::uint8_t* bytes, std::size_t size) {
  std::memset(bytes, 0, size);
  if (image.empty()) return;
  const int rows = std::min(static_cast<int>(height), image.rows);
  const std::size_t row_bytes = std::min<std::size_t>(width, static_cast<std::size_t>(image.cols)) * image.elemSize();
  const std::size_t stride = static_cast<std::size_t>(width) * image.elemSize();
  for (int y = 0; y < rows && (static_cast<std::size_t>(y) + 1) * stride <= size; ++y) {
    std::memcpy(bytes + y * stride, image.ptr(y), row_bytes);
  }
}

}  // namespace

void SimulatedGenicamCamera::Impl::fill(ArvBuffer* buffer, ArvPixelFormat pixel_format) {
  // The fake camera hands its own buffer to fill: the data is writable, and
  // it refuses to call here unless the buffer holds the payload (the size
  // arv_buffer_get_data reports is what was filled so far: none).
  auto* bytes = static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
  const std::size_t size = arv_fake_camera_get_payload(fake);
  const auto began = std::chrono::steady_clock::now();
  const double elapsed_s = std::chrono::duration<double>(began + render_estimate - scene_start).count();
  // Past its tabulated end the scene holds still (the recording ends there).
  const double scene_s = std::clamp(elapsed_s * options.speed, 0.0, scene->options().duration_s);
  const std::uint64_t index = rendered.fetch_add(1);
  const bool reference = index < static_cast<std::uint64_t>(options.reference_frames);
  const cv::Mat image = simgc_at_depth(scene->render_frame(pattern, camera, scene_s, !reference, index), pixel_format);
  // The region the client set, from the camera's registers: the buffer's
  // own image size is filled in only after this callback returns.
  guint32 width = 0, height = 0;
  arv_fake_camera_read_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, &width);
  arv_fake_camera_read_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, &height);
  if (bytes != nullptr) simgc_copy_region(image, width, height, bytes, size);
  // Stamped last: the leader, which carries the stamp, goes out next, so
  // the least latency a client sees is the loopback's, not the rendering's.
  const std::int64_t stamped_ns = acquisition::utc_now_ns();
  const auto took = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - began);
  render_estimate = index == 0 ? took : (render_estimate * 7 + took) / 8;
  arv_buffer_set_timestamp(buffer, static_cast<guint64>(camera_ns_at(stamped_ns)));
}

SimulatedGenicamCamera::SimulatedGenicamCamera(std::shared_ptr<const ConvectionScene> scene, BackgroundPattern pattern,
                                               CameraModel camera, SimulatedGenicamCameraOptions options,
                                               std::optional<std::chrono::steady_clock::time_point> scene_start)
    : impl_(std::make_unique<Impl>()) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (pattern.size != cv::Size(scene->options().width_px, scene->options().height_px)) {
    throw std::invalid_argument("simulated camera: background pattern size differs from the scene's image size");
  }
  impl_->scene = std::move(scene);
  impl_->pattern = std::move(pattern);
  impl_->camera = camera;
  impl_->options = std::move(options);
  impl_->scene_start = scene_start.value_or(std::chrono::steady_clock::now());
  impl_->clock_start_ns = acquisition::utc_now_ns();
  const auto& o = impl_->options;
  if (!simgc_gvcp_port_free(o.address)) {
    throw std::runtime_error(fmt::format(
        "simulated camera: cannot serve GigE Vision on {}: not a local IPv4 address, or its port 3956 is taken "
        "(another camera serving there?)",
        o.address));
  }
  impl_->gv_camera = arv_gv_fake_camera_new(o.address.c_str(), o.serial.c_str());
  if (impl_->gv_camera == nullptr || !arv_gv_fake_camera_is_running(impl_->gv_camera)) {
    if (impl_->gv_camera != nullptr) g_object_unref(impl_->gv_camera);
    throw std::runtime_error(fmt::format("simulated camera: Aravis could not serve GigE Vision on {}", o.address));
  }
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(impl_->gv_camera);
  impl_->fake = fake;
  // The scene's size and the requested rate, before any client connects.
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, impl_->scene->options().width_px);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, impl_->scene->options().height_px);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                 static_cast<guint32>(1e6 / o.frame_rate_hz));
  arv_fake_camera_set_fill_pattern(fake, simgc_fill_pattern, impl_.get());
}

SimulatedGenicamCamera::~SimulatedGenicamCamera() {
  // Unreferencing stops the camera's threads, so no fill runs after this.
  g_object_unref(impl_->gv_camera);
}

const SimulatedGenicamCameraOptions& SimulatedGenicamCamera::options() const { return impl_->options; }

std::uint64_t SimulatedGenicamCamera::frames_rendered() const { return impl_->rendered.load(); }

std::int64_t SimulatedGenicamCamera::camera_ns_at(std::int64_t host_ns) const { return impl_->camera_ns_at(host_ns); }

std::int64_t SimulatedGenicamCamera::host_ns_at(std::int64_t camera_ns) const {
  // camera − offset − start = (host − start) · (1 + drift)
  const auto& o = impl_->options;
  const double since_ns = static_cast<double>(camera_ns - impl_->clock_start_ns) - o.clock_offset_s * 1e9;
  return impl_->clock_start_ns + static_cast<std::int64_t>(std::llround(since_ns / (1 + o.clock_drift_ppm * 1e-6)));
}

}  // namespace bosfuse::sim
