#include "report/run_input.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "fusion/image_quality.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

std::optional<std::int64_t> first_sample_ns(const storage::RunStore& store) {
  std::optional<std::int64_t> first;
  for (const auto& summary : store.channel_summaries()) {
    if (summary.first_ns && (!first || *summary.first_ns < *first)) first = summary.first_ns;
  }
  return first;
}

double seconds_since(std::int64_t t_ns, std::int64_t origin_ns) { return static_cast<double>(t_ns - origin_ns) * 1e-9; }

cv::Mat read_frame(const storage::RunStore& store, const storage::FrameRecord& frame) {
  const fs::path path = store.dir() / frame.path;
  if (!fs::is_regular_file(path)) {
    throw std::runtime_error("cannot read frame " + std::to_string(frame.id) + " ('" + path.string() +
                             "'): no such file");
  }
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty())
    throw std::runtime_error("cannot read frame " + std::to_string(frame.id) + " ('" + path.string() + "')");
  return image;
}

}  // namespace

std::string iso8601_utc(std::int64_t t_ns) {
  std::int64_t seconds = t_ns / 1'000'000'000;
  std::int64_t rest = t_ns % 1'000'000'000;
  if (rest < 0) {
    rest += 1'000'000'000;
    --seconds;
  }
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm fields{};
  gmtime_r(&t, &fields);
  return fmt::format("{:04d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}.{:03d}Z", fields.tm_year + 1900, fields.tm_mon + 1,
                     fields.tm_mday, fields.tm_hour, fields.tm_min, fields.tm_sec, rest / 1'000'000);
}

MapField displacement_magnitude_map(const fusion::DisplacementField& field, cv::Size image_size_px) {
  if (field.rows <= 0 || field.cols <= 0 || field.size() != static_cast<std::size_t>(field.rows) * field.cols) {
    throw std::invalid_argument("the displacement field has no grid to map");
  }
  MapField map;
  map.quantity = "|displacement|";
  map.unit = "px";
  map.values = cv::Mat(field.rows, field.cols, CV_64F);
  map.mask = cv::Mat::zeros(field.rows, field.cols, CV_8U);
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const auto& v = field.at(r, c);
      const bool shown = v.valid() || v.flag == fusion::VectorFlag::kOutlierReplaced;
      map.values.at<double>(r, c) = shown ? std::hypot(v.u_px, v.v_px) : 0.0;
      map.mask.at<std::uint8_t>(r, c) = shown ? 0 : 255;
    }
  }
  map.x0_px = field.at(0, 0).x_px;
  map.y0_px = field.at(0, 0).y_px;
  if (field.cols > 1) {
    map.step_px = field.at(0, 1).x_px - field.at(0, 0).x_px;
  } else if (field.rows > 1) {
    map.step_px = field.at(1, 0).y_px - field.at(0, 0).y_px;
  }
  if (!(map.step_px > 0)) map.step_px = 1;
  map.image_size_px = image_size_px;
  return map;
}

ReportInput build_report_input(const storage::RunStore& store, const RunReportOptions& options) {
  ReportInput input;
  const auto run = store.run();
  input.run_name = run.name;
  input.run_dir = store.dir().string();
  input.started_utc = iso8601_utc(run.started_ns);
  input.status = std::string(storage::to_string(run.status));
  input.px_per_mm = options.px_per_mm;

  const auto frames = store.frames();
  std::int64_t origin_ns = run.started_ns;
  if (const auto first = first_sample_ns(store)) {
    origin_ns = *first;
  } else if (!frames.empty()) {
    origin_ns = frames.front().t_ns;
  }

  auto progress = [&](const std::string& line) {
    if (options.on_progress) options.on_progress(line);
  };
  // Thermocouples.
  for (const auto& channel : store.channels()) {
    if (channel.kind != "thermocouple") continue;
    CurveSeries s;
    s.name = channel.name;
    s.kind = SeriesKind::kThermocouple;
    if (channel.image_x_px && channel.image_y_px) s.image_px = cv::Point2d(*channel.image_x_px, *channel.image_y_px);
    for (const auto& sample : store.read_samples(channel.id)) {
      if (sample.status != storage::SampleStatus::kOk || !sample.value) {
        ++s.excluded_samples;
        continue;
      }
      s.time_s.push_back(seconds_since(sample.t_ns, origin_ns));
      s.temperature_c.push_back(*sample.value);
    }
    input.series.push_back(std::move(s));
  }
  if (input.series.empty()) input.notes.push_back("The run has no thermocouple channels.");
  progress(fmt::format("fitting {} thermocouple series", input.series.size()));
  fit_missing(input, options.fit);

  // Frames: reference, measurements nearest the chosen times, quality of the last one.
  if (frames.empty()) {
    input.displacement_maps_note = "the run has no frames";
    return input;
  }
  auto reference_it = std::find_if(frames.begin(), frames.end(), [](const auto& f) { return f.is_reference; });
  if (reference_it == frames.end()) {
    reference_it = frames.begin();
    input.notes.push_back(
        fmt::format("No frame is marked as the reference; the first frame ({}) is used.", reference_it->path));
  }
  const storage::FrameRecord reference = *reference_it;
  std::vector<storage::FrameRecord> measurements;
  for (const auto& f : frames) {
    if (f.id != reference.id) measurements.push_back(f);
  }
  if (measurements.empty()) {
    input.displacement_maps_note = "the run has a reference frame but no measurement frame";
    return input;
  }
  cv::Mat reference_image;
  try {
    reference_image = read_frame(store, reference);
  } catch (const std::exception& e) {
    input.displacement_maps_note = e.what();
    return input;
  }

  if (!options.mask.empty() && options.mask.size() != reference_image.size()) {
    input.displacement_maps_note = fmt::format("the mask is {}×{} px but the frames are {}×{} px", options.mask.cols,
                                               options.mask.rows, reference_image.cols, reference_image.rows);
    return input;
  }
  std::set<std::int64_t> done;
  for (double t : options.map_times_s) {
    const auto nearest = std::min_element(measurements.begin(), measurements.end(), [&](const auto& a, const auto& b) {
      return std::abs(seconds_since(a.t_ns, origin_ns) - t) < std::abs(seconds_since(b.t_ns, origin_ns) - t);
    });
    if (!done.insert(nearest->id).second) continue;  // two times chose the same frame
    const double frame_t = seconds_since(nearest->t_ns, origin_ns);
    progress(fmt::format("evaluating frame {} (t = {:.1f} s) against reference frame {}", nearest->id, frame_t,
                         reference.id));
    try {
      const cv::Mat image = read_frame(store, *nearest);
      const auto result = fusion::evaluate_displacement(reference_image, image, options.evaluator, options.mask);
      MapField map = displacement_magnitude_map(result.field, reference_image.size());
      map.time_s = frame_t;
      map.source = fmt::format("frame {} ({}) against reference frame {}, nearest to the requested t = {:g} s; {}",
                               nearest->id, nearest->path, reference.id, t, result.summary.BriefReport());
      input.displacement_maps.push_back(std::move(map));
    } catch (const std::exception& e) {
      input.notes.push_back(fmt::format("No displacement map at t = {:.1f} s: {}", frame_t, e.what()));
    }
  }
  if (input.displacement_maps.empty() && input.displacement_maps_note.empty()) {
    input.displacement_maps_note = "no map time was requested, or every evaluation failed (see the notes above)";
  }

  const auto& last = *std::max_element(measurements.begin(), measurements.end(),
                                       [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });
  try {
    QualityInfo quality;
    quality.index = fusion::modified_quality_index(read_frame(store, last), reference_image);
    quality.compared = fmt::format("Last frame {} (t = {:.1f} s) against reference frame {}", last.id,
                                   seconds_since(last.t_ns, origin_ns), reference.id);
    input.quality = quality;
  } catch (const std::exception& e) {
    input.notes.push_back(std::string("No image quality index: ") + e.what());
  }
  return input;
}

}  // namespace bosfuse::report
