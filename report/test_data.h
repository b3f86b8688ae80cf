#pragma once
// Report inputs for the report tests: Newton cooling curves with noise and a
// bump-shaped displacement map with a masked block, all with known values.

#include <cmath>
#include <random>
#include <string>

#include "report/report_input.h"

namespace bosfuse::report::testdata {

inline CurveSeries cooling_series(const std::string& name, double k_per_s, double t0_c, double ambient_c, std::size_t n,
                                  double dt_s, double sigma_c, unsigned seed) {
  CurveSeries s;
  s.name = name;
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0, sigma_c);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = i * dt_s;
    s.time_s.push_back(t);
    s.temperature_c.push_back(ambient_c + (t0_c - ambient_c) * std::exp(-k_per_s * t) + noise(random));
  }
  return s;
}

// A smooth hot spot with a masked block (the holder) in the lower middle.
inline MapField bump_map(int rows = 24, int cols = 32, double step_px = 8) {
  MapField map;
  map.quantity = "|displacement|";
  map.unit = "px";
  map.time_s = 10;
  map.values = cv::Mat(rows, cols, CV_64F);
  map.mask = cv::Mat::zeros(rows, cols, CV_8U);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double dx = c - cols / 2.0, dy = r - rows / 3.0;
      map.values.at<double>(r, c) = 0.4 * std::exp(-(dx * dx + dy * dy) / 40.0);
      if (r > rows * 2 / 3 && std::abs(dx) < 4) map.mask.at<std::uint8_t>(r, c) = 255;
    }
  }
  map.x0_px = 8;
  map.y0_px = 8;
  map.step_px = step_px;
  map.image_size_px = cv::Size(static_cast<int>(cols * step_px + 16), static_cast<int>(rows * step_px + 16));
  return map;
}

inline ReportInput sample_input(bool with_maps) {
  ReportInput input;
  input.run_name = "unit <run> & co";
  input.run_dir = "/tmp/run";
  input.started_utc = "2026-11-23T10:00:00.000Z";
  input.status = "complete";
  input.series.push_back(cooling_series("tc0", 0.01, 80, 22, 200, 2.0, 0.1, 1));
  input.series.push_back(cooling_series("tc1", 0.012, 70, 22, 200, 2.0, 0.1, 2));
  input.series[0].image_px = cv::Point2d(120, 60);
  input.series[1].image_px = cv::Point2d(200, 60);
  if (with_maps) {
    input.displacement_maps.push_back(bump_map());
    input.px_per_mm = 30;
    QualityInfo quality;
    quality.index.q_l = 0.99;
    quality.index.q_c = 0.8;
    quality.index.q_mod = 0.792;
    quality.compared = "Last frame 3 against reference frame 1";
    input.quality = quality;
  } else {
    input.displacement_maps_note = "the run has no frames";
  }
  return input;
}

}  // namespace bosfuse::report::testdata
