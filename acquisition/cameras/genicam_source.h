#pragma once
// GenicamSource reads a GigE Vision or USB3 Vision camera through Aravis.
// connect() opens the camera named by GenicamOptions::device, applies the
// settings in a fixed order (pixel format, region, exposure, gain, frame
// rate, trigger, then `features`), each checked against the camera's own
// feature limits first: a value outside them is refused with the feature's
// name and range (GenicamSettingRefused), as is a setting the camera lacks
// (gain_db on a camera with only GainRaw), a frame rate it cannot
// deliver with those settings, and one whose frames its link cannot carry
// (genicam_link_budget.h). Then it streams: frames come as the camera
// sends them (free-run or a hardware trigger) or as next() triggers them
// (a software trigger at its period).
//
// Each frame keeps the camera's timestamp as device_t_ns and its host
// arrival as arrival_ns; t_ns is the camera time mapped to the host clock
// (genicam_clock_mapping.h), fitted from latched camera timestamps where
// the camera has a latch, else from frame timestamps against arrivals
// (their lower envelope, as arrivals are only ever late). The
// fit is noted as a "clock" event with its residual when it starts and at
// every clock_report_period. A frame the stream could not complete (missing
// packets, a timeout) is a FrameLost; frames that never reached a buffer
// (gaps in the frame ids) and the stream's resent and missing packets are
// notes. A camera that stops answering (the control channel lost, or no
// frame for frame_timeout and no answer to a register read) is a
// DeviceError, so the recorder reconnects with backoff.

#include <atomic>
#include <future>
#include <memory>

#include "acquisition/cameras/frame_source.h"
#include "acquisition/cameras/genicam_clock_mapping.h"
#include "acquisition/cameras/genicam_options.h"

namespace bosfuse::acquisition {

// A setting the camera refuses: outside its limits, or a feature it lacks.
class GenicamSettingRefused : public DeviceError {
 public:
  using DeviceError::DeviceError;
};

class GenicamSource : public FrameSource {
 public:
  explicit GenicamSource(GenicamOptions options);  // throws std::invalid_argument for invalid options
  ~GenicamSource() override;

  std::string kind() const override { return "genicam"; }
  std::string describe() const override { return "GenICam camera " + options_.device; }
  void connect() override;
  void disconnect() override;
  std::optional<CapturedFrame> next(std::chrono::milliseconds wait) override;
  std::vector<Note> take_notes() override;

  // What connect() found: the pixel format and size it streams, and the
  // camera's frame rate with these settings (0 where it has none).
  struct Streaming {
    std::string pixel_format;
    int width_px = 0;
    int height_px = 0;
    double frame_rate_hz = 0;
    bool latched_clock = false;  // the time mapping is fitted from a timestamp latch
  };
  Streaming streaming() const { return streaming_; }
  // The camera-clock mapping as fitted so far (nullopt before a frame).
  std::optional<GenicamClockMapping::Fit> clock_fit() const { return clock_.fit(); }

  // Opens the camera, applies and checks every setting, and closes it: the
  // start of logging refuses a camera whose settings cannot work. Throws
  // GenicamSettingRefused, or DeviceError when the camera cannot be reached.
  static Streaming check_settings(const GenicamOptions& options);

 private:
  struct Handles;
  void apply_settings();
  void start_stream();
  std::optional<CapturedFrame> take_buffer(std::chrono::milliseconds wait);
  void software_trigger_if_due();
  void latch_clock_if_due();
  void probe_if_silent();
  void note_frame_gap(std::uint64_t frame_id);
  void note_clock_if_due(bool force);
  void note_rate(std::chrono::steady_clock::time_point now);
  void note_stream_statistics();

  GenicamOptions options_;
  // Set by Aravis' heartbeat thread; declared before handles_ so it
  // outlives the signal handler that handles_ disconnects.
  std::atomic<bool> control_lost_{false};
  // The camera stopped answering: disconnect() does not wait on it again.
  bool gone_ = false;
  // Releasing a camera that is gone waits out its protocol's timeouts
  // (about 6 s on GigE Vision: the stream's and the control channel's
  // last writes), so it is done on a thread of its own: the disconnect is
  // recorded at once and a restarted camera can be reached meanwhile. The
  // destructor waits for them.
  std::vector<std::future<void>> releases_;
  std::unique_ptr<Handles> handles_;
  Streaming streaming_;
  GenicamClockMapping clock_;
  std::vector<Note> notes_;
  std::optional<std::uint64_t> last_frame_id_;
  std::int64_t frames_read_ = 0;
  std::chrono::steady_clock::time_point rate_since_;  // the delivered rate is measured from here
  std::int64_t rate_frames_ = 0;
  std::chrono::steady_clock::time_point last_frame_at_;
  std::chrono::steady_clock::time_point next_trigger_at_;
  std::chrono::steady_clock::time_point next_latch_at_;
  std::chrono::steady_clock::time_point next_clock_note_at_;
  bool clock_noted_ = false;
  std::uint64_t resent_packets_ = 0;
  std::uint64_t missing_packets_ = 0;
};

}  // namespace bosfuse::acquisition
