#pragma once
// What the simulation of a demo knows and its measurement must find: the
// true cooling rates of the cylinder and of the plume at the thermocouples,
// and at each thermocouple the rate of the point and of the processing
// window's mean. `bosfuse demo` prints the plume's beside the fitted rates
// and writes all of it to the run's demo-truth.json for whoever checks the
// demo (its end-to-end test does, and bench/demo_seeds).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <vector>

#include "sim/demo_setup.h"

namespace bosfuse::sim {

// The cooling rate a plume thermocouple sees, 1/s of experiment time.
double true_plume_cooling_rate(const DemoSetup& setup);

// Least-squares slope of −ln(excess) against t: the rate of a curve that is
// exponential to within its slow drift.
double log_linear_rate(const std::vector<double>& t_s, const std::vector<double>& excess_c);

// Per thermocouple, at the demo's frame times: the excess at t = 0 and the
// rate of the point's temperature and of its mean over kDemoWindowPx.
nlohmann::json probe_truths(const DemoOptions& options, const DemoSetup& setup);

// Writes <run_dir>/demo-truth.json.
void write_truth(const std::filesystem::path& run_dir, const DemoOptions& options, const DemoSetup& setup);

// The table the demo ends with: every Newton fit the processing of the run
// at `run_dir` stored (in experiment time, like everything in the run), its
// k beside `true_k_per_s`, and the agreements' verdicts.
void print_rates_beside_truth(std::ostream& out, const std::filesystem::path& run_dir, double true_k_per_s);

}  // namespace bosfuse::sim
