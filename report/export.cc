#include "report/export.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "fitting/fit_json.h"
#include "report/csv_cell.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

std::ofstream open_for_writing(const fs::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
  return out;
}

void check_written(std::ofstream& out, const fs::path& path) {
  out.flush();
  if (!out) throw std::runtime_error("writing '" + path.string() + "' failed");
}

// Round-trip precision; empty for a value that does not exist.
std::string num(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); }

ordered_json json_num(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); }

std::string field(const std::string& text) { return csv_text_cell(text); }

bool fit_ok(const CurveSeries& s) { return s.fit && s.fit->ok(); }

}  // namespace

void write_series_csv(const ReportInput& input, const fs::path& path) {
  auto out = open_for_writing(path);
  out << "series,kind,t_s,temperature_c,fit_c,residual_c\n";
  for (const auto& s : input.series) {
    const std::string name = field(s.name), kind = to_string(s.kind);
    for (std::size_t i = 0; i < s.time_s.size() && i < s.temperature_c.size(); ++i) {
      const double model = fit_ok(s) ? s.fit->temperature_at(s.time_s[i]) : NAN;
      out << name << ',' << kind << ',' << num(s.time_s[i]) << ',' << num(s.temperature_c[i]) << ',' << num(model)
          << ',' << num(s.temperature_c[i] - model) << '\n';
    }
  }
  check_written(out, path);
}

void write_fits_csv(const ReportInput& input, const fs::path& path) {
  auto out = open_for_writing(path);
  out << "series,kind,ok,status,confidence,points,k_per_s,k_low,k_high,tau_s,tau_low,tau_high,T0_c,T0_low,T0_high,"
         "T_amb_c,T_amb_low,T_amb_high,ambient_fixed,residual_rms_c,residual_std_c,reduced_chi_square,"
         "lag1_autocorrelation,record_time_constants,message\n";
  for (const auto& s : input.series) {
    out << field(s.name) << ',' << to_string(s.kind) << ',';
    if (!s.fit) {
      out << "false,not fitted,,,,,,,,,,,,,,,,,,,,,\n";
      continue;
    }
    const auto& f = *s.fit;
    const auto& m = f.summary;
    const bool ok = f.ok();
    out << (ok ? "true" : "false") << ',' << fitting::to_string(m.status) << ',' << m.confidence << ','
        << m.points_used;
    for (const auto* e : {&f.k_per_s, &f.tau_s, &f.t0_c, &f.ambient_c}) {
      out << ',' << num(e->value) << ',' << num(e->low) << ',' << num(e->high);
    }
    out << ',' << (f.ambient_c.fixed ? "true" : "false") << ',' << num(ok ? m.residual_rms_c : NAN) << ','
        << num(ok ? m.residual_std_c : NAN) << ',' << num(m.reduced_chi_square.value_or(NAN)) << ','
        << num(ok ? m.lag1_autocorrelation : NAN) << ',' << num(ok ? m.record_time_constants : NAN) << ','
        << field(ok ? fmt::format("{}", fmt::join(m.warnings, " ")) : m.message) << '\n';
  }
  check_written(out, path);
}

void write_map_csv(const MapField& map, std::optional<double> px_per_mm, const fs::path& path) {
  cv::Mat values;
  map.values.convertTo(values, CV_64F);
  cv::Mat mask;
  if (!map.mask.empty()) map.mask.convertTo(mask, CV_8U);
  auto out = open_for_writing(path);
  out << "x_px,y_px,x_mm,y_mm,value,masked\n";
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      const double x = map.x0_px + c * map.step_px, y = map.y0_px + r * map.step_px;
      const double v = values.at<double>(r, c);
      const bool masked = (!mask.empty() && mask.at<std::uint8_t>(r, c) != 0) || !std::isfinite(v);
      out << num(x) << ',' << num(y) << ',' << (px_per_mm ? num(x / *px_per_mm) : "") << ','
          << (px_per_mm ? num(y / *px_per_mm) : "") << ',' << (masked ? "" : num(v)) << ',' << (masked ? 1 : 0) << '\n';
    }
  }
  check_written(out, path);
}

ordered_json fit_json(const fitting::NewtonFit& fit) { return fitting::to_json(fit); }

ordered_json agreement_json(const AgreementEntry& entry) {
  ordered_json j = {{"thermocouple", entry.thermocouple}, {"probe", entry.probe}};
  const ordered_json agreement = fitting::to_json(entry.agreement);
  for (auto it = agreement.begin(); it != agreement.end(); ++it) j[it.key()] = it.value();
  return j;
}

namespace {

ordered_json map_json(const MapField& map, std::optional<double> px_per_mm) {
  cv::Mat values;
  map.values.convertTo(values, CV_64F);
  cv::Mat mask;
  if (!map.mask.empty()) map.mask.convertTo(mask, CV_8U);
  double low = INFINITY, high = -INFINITY;
  std::size_t masked = 0;
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      const double v = values.at<double>(r, c);
      if ((!mask.empty() && mask.at<std::uint8_t>(r, c)) || !std::isfinite(v)) {
        ++masked;
        continue;
      }
      low = std::min(low, v);
      high = std::max(high, v);
    }
  }
  return {{"quantity", map.quantity}, {"unit", map.unit},
          {"time_s", map.time_s},     {"source", map.source},
          {"rows", values.rows},      {"cols", values.cols},
          {"x0_px", map.x0_px},       {"y0_px", map.y0_px},
          {"step_px", map.step_px},   {"px_per_mm", px_per_mm ? ordered_json(*px_per_mm) : ordered_json(nullptr)},
          {"masked_cells", masked},   {"min", json_num(low)},
          {"max", json_num(high)}};
}

}  // namespace

ordered_json report_json(const ReportInput& input, const std::vector<FigureFiles>& figures,
                         const std::vector<fs::path>& data_files) {
  ordered_json j;
  j["run"] = {
      {"name", input.run_name}, {"dir", input.run_dir}, {"started_utc", input.started_utc}, {"status", input.status}};
  j["conventions"] = {{"time", "seconds since the run's first sample"},
                      {"temperature", "degC"},
                      {"image", "pixels, origin at the top-left pixel's centre, x right, y down"}};
  j["notes"] = input.notes;
  ordered_json series = ordered_json::array();
  for (const auto& s : input.series) {
    ordered_json e = {{"name", s.name}, {"kind", to_string(s.kind)}};
    e["image_px"] = s.image_px ? ordered_json{{"x", s.image_px->x}, {"y", s.image_px->y}} : ordered_json(nullptr);
    e["samples"] = s.time_s.size();
    e["excluded_samples"] = s.excluded_samples;
    e["fit"] = s.fit ? fit_json(*s.fit) : ordered_json(nullptr);
    ordered_json t = ordered_json::array(), temp = ordered_json::array();
    for (std::size_t i = 0; i < s.time_s.size() && i < s.temperature_c.size(); ++i) {
      t.push_back(json_num(s.time_s[i]));
      temp.push_back(json_num(s.temperature_c[i]));
    }
    e["time_s"] = std::move(t);
    e["temperature_c"] = std::move(temp);
    series.push_back(std::move(e));
  }
  j["series"] = std::move(series);
  ordered_json agreements = ordered_json::array();
  for (const auto& a : input.agreements) agreements.push_back(agreement_json(a));
  j["agreements"] = std::move(agreements);
  ordered_json maps = ordered_json::array();
  for (const auto& m : input.displacement_maps) maps.push_back(map_json(m, input.px_per_mm));
  for (const auto& m : input.temperature_maps) maps.push_back(map_json(m, input.px_per_mm));
  j["maps"] = std::move(maps);
  if (input.quality) {
    const auto& q = input.quality->index;
    j["image_quality"] = {{"compared", input.quality->compared},
                          {"q_l", q.q_l},
                          {"q_c", q.q_c},
                          {"q_mod", q.q_mod},
                          {"mean_image", q.mean_image},
                          {"mean_reference", q.mean_reference},
                          {"std_image", q.std_image},
                          {"std_reference", q.std_reference}};
  } else {
    j["image_quality"] = nullptr;
  }
  ordered_json figs = ordered_json::array();
  for (const auto& f : figures) {
    figs.push_back({{"title", f.title},
                    {"png", f.png.filename().string()},
                    {"svg", f.svg.filename().string()},
                    {"caption", f.caption}});
  }
  j["figures"] = std::move(figs);
  ordered_json files = ordered_json::array();
  for (const auto& f : data_files) files.push_back(f.filename().string());
  j["data_files"] = std::move(files);
  return j;
}

}  // namespace bosfuse::report
