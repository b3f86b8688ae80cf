#pragma once
// The memory an evaluation will need, set against the memory this process
// can still get, checked before the evaluation allocates anything. Decoding
// refuses images over 100 megapixels (acquisition/cameras/image_file.h), but a pair
// under that limit can still need more than the machine or the process's
// limits allow — a 100 MP pair needs 400 MB for each float copy, and DIS
// optical flow over 200 bytes a pixel — and that would end in
// std::bad_alloc or the OOM killer in the middle of a run. Evaluators call
// check_*_memory first, and a pair that cannot fit is refused with a message
// that says what it needs, what is available, and what would fit.
//
// The estimates count what cross_correlation.cc and optical_flow.cc allocate
// at their peak (float copies, warped images, flow fields, integral images,
// grid copies; see the .cc for the term-by-term account) plus, for optical
// flow, OpenCV's own buffers as measured per pixel. They are upper bounds,
// 4 to 16 % above the measured peak of a fresh process at 1 to 4 MP (most
// of that is a fixed 8 MB; memory_budget_test.cc checks them against VmHWM
// within 20 %). Probe mode of cross-correlation works on crops around the
// probes and is never refused.
//
// What is available is the least of the sources AvailableMemory holds
// (MemAvailable, the memory cgroup's headroom, ulimit -v and -d). fusion/
// does not read the system: the program installs a probe at its start
// (pipeline/available_memory.h reads /proc, /sys and getrlimit, and honours
// BOSFUSE_MEMORY_CHECK=off), and without one nothing is checked.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fusion/cross_correlation.h"
#include "fusion/optical_flow.h"

namespace bosfuse::fusion {

// What the estimate needs to know of an image pair: its size and OpenCV type
// as decoded (colour input costs a grey copy on the way), and the mask's.
struct PairShape {
  cv::Size size;
  int type = CV_8UC1;
  int mask_type = -1;  // -1: no mask

  static PairShape of(const cv::Mat& reference, const cv::Mat& mask = {});
};

// Peak bytes evaluate_xcorr / evaluate_flow allocate for such a pair.
std::uint64_t xcorr_bytes_needed(const PairShape& pair, const XcorrOptions& options);
std::uint64_t flow_bytes_needed(const PairShape& pair, const FlowOptions& options);

// The memory this process can still allocate, by source; a source that does
// not apply (no cgroup limit, unlimited ulimit) or cannot be read is empty.
struct AvailableMemory {
  std::optional<std::uint64_t> mem_available_bytes;  // /proc/meminfo MemAvailable
  std::optional<std::uint64_t> cgroup_bytes;         // cgroup limit minus usage
  std::optional<std::uint64_t> address_space_bytes;  // RLIMIT_AS minus VmSize
  std::optional<std::uint64_t> data_bytes;           // RLIMIT_DATA minus VmData

  // The least of the known sources; nullopt when none is known.
  std::optional<std::uint64_t> bytes() const;
  // "MemAvailable", "the cgroup limit", "ulimit -v" or "ulimit -d": the source of bytes().
  std::string limited_by() const;
};

// What this process can still get, asked before each full-field
// evaluation; nullopt when the memory is not to be checked.
using AvailableMemoryProbe = std::optional<AvailableMemory> (*)();

// Installs the probe check_*_memory ask; nullptr (the default) checks
// nothing. Install once at start-up, before evaluations run.
void install_available_memory_probe(AvailableMemoryProbe probe);

// An evaluation that would need more memory than the process can get.
class InsufficientMemory : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// What a refusal says; `settings` describes the options ("window 16 px,
// 3 passes"), `remedies` what would fit ("evaluate a region (--roi)").
struct MemoryRequest {
  cv::Size size;
  std::uint64_t needed_bytes = 0;
  std::string settings;
  std::vector<std::string> remedies;
};

// Throws InsufficientMemory when `request` needs more than `available`
// holds; does nothing when nothing is known of the available memory.
// Returns the account of both ("memory: 4000x3000 pair needs ..."), for the
// caller's log at debug level.
std::string check_memory(const MemoryRequest& request, const AvailableMemory& available);

// check_memory for an evaluation of this pair with these options, against
// what the installed probe says is available (nothing checked without a
// probe or when it says so). Allocates nothing of image size. Returns
// check_memory's account, empty when nothing was checked.
std::string check_xcorr_memory(const cv::Mat& reference, const cv::Mat& mask, const XcorrOptions& options);
std::string check_flow_memory(const cv::Mat& reference, const cv::Mat& mask, const FlowOptions& options);

// "6.4 GB", "512 MB": decimal units, as `free -h` and the message use them.
std::string format_bytes(std::uint64_t bytes);

}  // namespace bosfuse::fusion
