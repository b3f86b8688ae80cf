#pragma once
// A GenicamClockMapping maps a camera's clock to the host UTC clock the
// thermocouples are on: host = offset + (1 + drift) · camera, fitted to
// pairs of the same instant read on both clocks. The pairs come from one
// of two places, and each is fitted as its errors require:
//
// - Latched (a camera with GevTimestampControlLatch or TimestampLatch):
//   the camera's timestamp latched while the host clock is read on either
//   side; the host reading's error is symmetric, so a least-squares line.
//   The residual (RMS and largest of host − mapped) is the alignment's
//   stated uncertainty.
// - Arrivals (a camera without a latch): each frame's camera timestamp
//   against its host arrival. An arrival is the true host time of the stamp
//   plus a latency that is never negative and has a long tail (scheduling,
//   load spikes), so a least-squares line would carry the mean latency and
//   its spread. The fit is the lower envelope instead, placed by the
//   least-delayed arrivals alone however loaded the rest: its drift is a
//   least-squares line through the least-delayed arrival of each of up to
//   16 stretches of camera time (a stretch under load throughout, whose
//   least delay is far above the others', left out), and its offset puts
//   it under every arrival, through the least-delayed one. (A line through
//   two neighbouring arrivals, as the lower hull's edge would be, can take
//   a drift of thousands of ppm from 100 µs of latency difference.) Its
//   residual is the spread of those stretches' least-delayed arrivals above
//   it: how sharply arrivals crowd onto it, so how well it is placed;
//   `latency_*` says how far arrivals lag it (the latency spread, which the
//   mapping removes). What the envelope cannot see is the camera's least
//   latency itself: the time from its stamp to the leader's arrival on the
//   quietest frames (on a LAN tens of µs; on a camera that stamps the start
//   of a long exposure, the exposure and readout too). That is a one-sided
//   systematic offset (mapped ≥ true by it) only a latch removes.
//
// Pairs are kept up to a bound by thinning the oldest half (arrivals: the
// lower of each two neighbours, so the envelope survives), so a long run
// keeps its early pairs in the fit.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bosfuse::acquisition {

class GenicamClockMapping {
 public:
  enum class Pairs { kLatched, kArrivals };

  struct Fit {
    std::int64_t camera_origin_ns = 0;  // the first pair's camera time
    double host_at_origin_ns = 0;       // the fitted host time there
    double drift = 0;                   // host ns per camera ns, minus 1
    // Latched: every pair about the line. Arrivals: the stretches' least-delayed pairs above it.
    double residual_rms_ns = 0;
    double residual_max_ns = 0;
    std::size_t pairs = 0;
    std::int64_t span_ns = 0;  // camera time from the first to the last pair
    Pairs kind = Pairs::kLatched;
    std::size_t envelope_pairs = 0;  // arrivals: the stretches' least-delayed pairs, the residual's
    // Arrivals: host arrival − mapped (≥ about 0 by construction) over the
    // latest `latency_pairs`, those thinning has not yet halved (it keeps
    // the earlier of two arrivals, which would bias the spread low).
    double latency_median_ns = 0;
    double latency_max_ns = 0;
    std::size_t latency_pairs = 0;
  };

  explicit GenicamClockMapping(Pairs kind = Pairs::kLatched, std::size_t max_pairs = 4096);

  void add(std::int64_t camera_ns, std::int64_t host_ns);
  void clear();
  Pairs kind() const { return kind_; }
  std::size_t size() const { return pairs_.size(); }
  // The fit; nullopt before the first pair. One pair gives an offset alone
  // (drift 0), as do pairs spanning less than a second of camera time.
  std::optional<Fit> fit() const;
  // `camera_ns` on the host clock by the current fit; nullopt before any pair.
  std::optional<std::int64_t> map(std::int64_t camera_ns) const;
  // "offset +1.234567 s at camera time … ns, drift +12.3 ppm, residual 45 µs RMS (120 µs max) over 300
  // pairs in 15.0 s" and, for arrivals, the envelope's size and the latency above it.
  static std::string describe(const Fit& fit);

 private:
  struct Pair {
    std::int64_t camera_ns;
    std::int64_t host_ns;
  };
  void thin();
  void refit() const;

  Pairs kind_;
  std::size_t max_pairs_;
  std::vector<Pair> pairs_;
  std::size_t unthinned_from_ = 0;  // pairs_[unthinned_from_..] are every pair added since the last thinning
  mutable std::optional<Fit> fit_;  // cached until the next add
};

}  // namespace bosfuse::acquisition
