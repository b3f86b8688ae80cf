#pragma once
// A GenicamClockMapping maps a camera's clock to the host UTC clock the
// thermocouples are on: host = offset + (1 + drift) · camera, fitted by
// least squares to pairs of the same instant read on both clocks. The
// pairs come from latching the camera's timestamp while the host clock is
// read around the latch (a camera with GevTimestampControlLatch or
// TimestampLatch), else from each frame's camera timestamp against its
// host arrival time, which carries the transfer's latency: that mapping's
// offset includes the mean latency, and its residual shows the latency's
// spread. The residual (RMS and largest of host − mapped) is the alignment's
// stated uncertainty. Pairs are kept up to a bound by thinning the oldest
// half, so a long run keeps its early pairs in the fit.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bosfuse::acquisition {

class GenicamClockMapping {
 public:
  struct Fit {
    std::int64_t camera_origin_ns = 0;  // the first pair's camera time
    double host_at_origin_ns = 0;       // the fitted host time there
    double drift = 0;                   // host ns per camera ns, minus 1
    double residual_rms_ns = 0;
    double residual_max_ns = 0;
    std::size_t pairs = 0;
    std::int64_t span_ns = 0;  // camera time from the first to the last pair
  };

  explicit GenicamClockMapping(std::size_t max_pairs = 4096);

  void add(std::int64_t camera_ns, std::int64_t host_ns);
  void clear();
  std::size_t size() const { return pairs_.size(); }
  // The least-squares fit; nullopt before the first pair. One pair gives
  // an offset alone (drift 0).
  std::optional<Fit> fit() const;
  // `camera_ns` on the host clock by the current fit; nullopt before any pair.
  std::optional<std::int64_t> map(std::int64_t camera_ns) const;
  // "offset +1.234567 s, drift +12.3 ppm, residual 45 µs RMS (120 µs max) over 300 pairs in 15.0 s"
  static std::string describe(const Fit& fit);

 private:
  void refit() const;

  struct Pair {
    std::int64_t camera_ns;
    std::int64_t host_ns;
  };
  std::size_t max_pairs_;
  std::vector<Pair> pairs_;
  mutable std::optional<Fit> fit_;  // cached until the next add
};

}  // namespace bosfuse::acquisition
