// Writes issue 30's synthetic pairs (bench/bench_scenes.h) to a folder, for
// other PIV programs to evaluate beside bosfuse: bench/openpiv_compare.py.
//   build/bench/write_bench_pairs DIR
// DIR/pairs.json lists each pair: its name, the two PNG files (relative to
// DIR) and the true uniform shift (u, v) in px, x right and y down.

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "bench/bench_scenes.h"

namespace fs = std::filesystem;

namespace {

void write(const fs::path& dir, const std::string& name, const bosfuse::sim::SyntheticPair& pair, cv::Point2d shift,
           nlohmann::ordered_json& list) {
  const std::string reference = name + "_a.png", measurement = name + "_b.png";
  if (!cv::imwrite((dir / reference).string(), pair.reference) ||
      !cv::imwrite((dir / measurement).string(), pair.measurement)) {
    throw std::runtime_error("cannot write " + (dir / name).string() + "_*.png");
  }
  list.push_back({{"name", name}, {"a", reference}, {"b", measurement}, {"u_px", shift.x}, {"v_px", shift.y}});
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: write_bench_pairs DIR\n";
    return 2;
  }
  try {
    const fs::path dir = argv[1];
    fs::create_directories(dir);
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const int noise_permille : {4, 10}) {
      for (int i = 0; i < 3; ++i) {
        write(dir, "lowcontrast_noise" + std::to_string(noise_permille) + "permille_" + std::to_string(i),
              bosfuse::bench::low_contrast_pair(i, noise_permille * 1e-3), bosfuse::bench::low_contrast_shift(i),
              list);
      }
    }
    write(dir, "largeshift_5.3_-3.7", bosfuse::bench::large_shift_pair(5.3, -3.7), {5.3, -3.7}, list);
    std::ofstream(dir / "pairs.json") << list.dump(1) << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "write_bench_pairs: " << e.what() << "\n";
    return 1;
  }
}
