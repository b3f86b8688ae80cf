#include "report/export.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "fitting/fit_json.h"
#include "report/csv_cell.h"
#include "storage/partial_file.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

// Round-trip precision; empty for a value that does not exist.
std::string num(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); }

std::string field(const std::string& text) { return csv_text_cell(text); }

bool fit_ok(const CurveSeries& s) { return s.fit && s.fit->ok(); }

// Units for programs: plain ASCII, as in "conventions".
std::string machine_unit(const std::string& unit) { return unit == "°C" ? "degC" : unit; }

// Sets j[key] only when the number exists.
void put_finite(ordered_json& j, const char* key, double v) {
  if (std::isfinite(v)) j[key] = v;
}

void drop_null_members(ordered_json& j) {
  if (!j.is_object()) return;
  for (auto it = j.begin(); it != j.end();) {
    if (it->is_null()) {
      it = j.erase(it);
    } else {
      drop_null_members(*it++);
    }
  }
}

std::string optional_num(const std::optional<double>& v) { return v ? num(*v) : std::string(); }

void summary_csv_row(std::ostream& out, const std::string& series, const std::string& kind,
                     const std::string& compared_with, const char* quantity, const SummaryQuantity& q,
                     const std::string& note) {
  out << field(series) << ',' << field(kind) << ',' << field(compared_with) << ',' << quantity << ','
      << optional_num(q.value) << ',' << optional_num(q.std_error) << ',' << optional_num(q.low) << ','
      << optional_num(q.high) << ',' << field(machine_unit(q.unit)) << ',' << field(q.value ? note : q.reason) << '\n';
}

void summary_csv_series(std::ostream& out, const SeriesSummary& r) {
  const std::string kind = to_string(r.kind);
  SummaryQuantity points;
  points.value = static_cast<double>(r.points);
  summary_csv_row(out, r.name, kind, "", "points", points, "");
  summary_csv_row(out, r.name, kind, "", "k", r.k, "");
  summary_csv_row(out, r.name, kind, "", "tau", r.tau, "");
  summary_csv_row(out, r.name, kind, "", "T0", r.t0, "");
  summary_csv_row(out, r.name, kind, "", "T_amb", r.ambient, r.ambient.fixed ? "fixed in the fit" : "");
  summary_csv_row(out, r.name, kind, "", "residual_rms", r.residual_rms, "");
}

void summary_csv_pair(std::ostream& out, const PairSummary& p) {
  const auto row = [&](const char* quantity, const SummaryQuantity& q, const std::string& note) {
    summary_csv_row(out, p.thermocouple, "agreement", p.probe, quantity, q, note);
  };
  row("delta_k", p.delta_k, "k_thermocouple - k_probe; std_error: combined");
  row("z", p.z, "");
  row("rms_difference", p.rms_difference, "");
  row("bias", p.bias, "low, high: 95% limits of agreement");
  SummaryQuantity verdict;
  verdict.reason = p.verdict;  // text, not a number: always in note
  row("verdict", verdict, "");
}

ordered_json quantity_json(const SummaryQuantity& q) {
  ordered_json j;
  if (!q.value) return {{"unit", machine_unit(q.unit)}, {"not_computed", q.reason}};
  j["value"] = *q.value;
  if (q.std_error) j["std_error"] = *q.std_error;
  if (q.low) j["low"] = *q.low;
  if (q.high) j["high"] = *q.high;
  if (q.fixed) j["fixed"] = true;
  j["unit"] = machine_unit(q.unit);
  return j;
}

}  // namespace

void write_series_csv(const ReportInput& input, const fs::path& path) {
  storage::PartialFileStream file(path);  // in place only once whole
  std::ostream& out = file.stream();
  out << "series,kind,t_s,temperature_c,fit_c,residual_c,fit_half_width_c\n";
  for (const auto& s : input.series) {
    const std::string name = field(s.name), kind = to_string(s.kind);
    for (std::size_t i = 0; i < s.time_s.size() && i < s.temperature_c.size(); ++i) {
      const double model = fit_ok(s) ? s.fit->temperature_at(s.time_s[i]) : NAN;
      const double half_width = fit_ok(s) ? s.fit->temperature_half_width_at(s.time_s[i]) : NAN;
      out << name << ',' << kind << ',' << num(s.time_s[i]) << ',' << num(s.temperature_c[i]) << ',' << num(model)
          << ',' << num(s.temperature_c[i] - model) << ',' << num(half_width) << '\n';
    }
  }
  file.close();
}

void write_fits_csv(const ReportInput& input, const fs::path& path) {
  storage::PartialFileStream file(path);  // in place only once whole
  std::ostream& out = file.stream();
  out << "series,kind,ok,status,confidence,points,k_per_s,k_low,k_high,tau_s,tau_low,tau_high,T0_c,T0_low,T0_high,"
         "T0_t_s,T_amb_c,T_amb_low,T_amb_high,ambient_fixed,residual_rms_c,residual_std_c,reduced_chi_square,"
         "lag1_autocorrelation,record_time_constants,message\n";
  for (const auto& s : input.series) {
    out << field(s.name) << ',' << to_string(s.kind) << ',';
    if (!s.fit) {
      out << "false,not fitted,,,,,,,,,,,,,,,,,,,,,,\n";
      continue;
    }
    const auto& f = *s.fit;
    const auto& m = f.summary;
    const bool ok = f.ok();
    out << (ok ? "true" : "false") << ',' << fitting::to_string(m.status) << ',' << m.confidence << ','
        << m.points_used;
    for (const auto* e : {&f.k_per_s, &f.tau_s, &f.t0_c, &f.ambient_c}) {
      out << ',' << num(e->value) << ',' << num(e->low) << ',' << num(e->high);
      // The time T0 is the temperature at: the origin, or the first sample when the origin lies too far from the data.
      if (e == &f.t0_c) out << ',' << num(ok ? f.origin_s + f.t0_reference_s : NAN);
    }
    out << ',' << (f.ambient_c.fixed ? "true" : "false") << ',' << num(ok ? m.residual_rms_c : NAN) << ','
        << num(ok ? m.residual_std_c : NAN) << ',' << num(m.reduced_chi_square.value_or(NAN)) << ','
        << num(ok ? m.lag1_autocorrelation : NAN) << ',' << num(ok ? m.record_time_constants : NAN) << ','
        << field(ok ? fmt::format("{}", fmt::join(m.warnings, " ")) : m.message) << '\n';
  }
  file.close();
}

void write_map_csv(const MapField& map, std::optional<double> px_per_mm, const fs::path& path) {
  cv::Mat values;
  map.values.convertTo(values, CV_64F);
  cv::Mat mask;
  if (!map.mask.empty()) map.mask.convertTo(mask, CV_8U);
  storage::PartialFileStream file(path);  // in place only once whole
  std::ostream& out = file.stream();
  out << "x_px,y_px,x_mm,y_mm,value,masked\n";
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      const double x = map.x0_px + c * map.step_px, y = map.y0_px + r * map.step_px;
      const double v = values.at<double>(r, c);
      const bool masked = (!mask.empty() && mask.at<std::uint8_t>(r, c) != 0) || !std::isfinite(v);
      // A cell that holds no measurement says so twice: `nan` (not an empty cell, which a reader could take
      // for a missing column) and masked = 1.
      out << num(x) << ',' << num(y) << ',' << (px_per_mm ? num(x / *px_per_mm) : "") << ','
          << (px_per_mm ? num(y / *px_per_mm) : "") << ',' << (masked ? "nan" : num(v)) << ',' << (masked ? 1 : 0)
          << '\n';
    }
  }
  file.close();
}

void write_summary_csv(const ReportSummary& summary, const fs::path& path) {
  storage::PartialFileStream file(path);  // in place only once whole
  std::ostream& out = file.stream();
  out << "series,kind,compared_with,quantity,value,std_error,low,high,unit,note\n";
  for (const auto& r : summary.series) summary_csv_series(out, r);
  for (const auto& p : summary.pairs) summary_csv_pair(out, p);
  file.close();
}

ordered_json fit_json(const fitting::NewtonFit& fit) {
  ordered_json j = fitting::to_json(fit);
  drop_null_members(j);
  return j;
}

ordered_json agreement_json(const AgreementEntry& entry, const PairSummary& summary) {
  ordered_json j = {{"thermocouple", entry.thermocouple}, {"probe", entry.probe}};
  const ordered_json agreement = fitting::to_json(entry.agreement);
  for (auto it = agreement.begin(); it != agreement.end(); ++it) j[it.key()] = it.value();
  j["verdict"] = summary.verdict;  // without a sentence on °C differences for a px series
  if (!summary.delta_k.value && j["k"].is_null()) j["k"] = summary.delta_k.reason;
  if (!summary.rms_difference.value && !summary.bias.value) j["series"] = summary.bias.reason;
  drop_null_members(j);
  return j;
}

ordered_json summary_json(const ReportSummary& summary) {
  ordered_json series = ordered_json::array();
  for (const auto& r : summary.series) {
    series.push_back({{"name", r.name},
                      {"kind", to_string(r.kind)},
                      {"points", r.points},
                      {"k", quantity_json(r.k)},
                      {"tau", quantity_json(r.tau)},
                      {"T0", quantity_json(r.t0)},
                      {"T_amb", quantity_json(r.ambient)},
                      {"residual_rms", quantity_json(r.residual_rms)},
                      {"notes", r.notes}});
  }
  ordered_json pairs = ordered_json::array();
  for (const auto& p : summary.pairs) {
    ordered_json j = {{"thermocouple", p.thermocouple},
                      {"probe", p.probe},
                      {"delta_k", quantity_json(p.delta_k)},
                      {"z", quantity_json(p.z)}};
    if (p.k_agree) j["k_agree"] = *p.k_agree;
    j["verdict"] = p.verdict;
    j["rms_difference"] = quantity_json(p.rms_difference);
    j["bias"] = quantity_json(p.bias);  // low, high: the 95% limits of agreement
    pairs.push_back(std::move(j));
  }
  return {{"time_basis", summary.time_basis},
          {"confidence", summary.confidence},
          {"series", std::move(series)},
          {"pairs", std::move(pairs)}};
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
  ordered_json j = {{"quantity", map.quantity}, {"unit", map.unit},    {"time_s", map.time_s ? ordered_json(*map.time_s) : ordered_json()},
                    {"source", map.source},     {"rows", values.rows}, {"cols", values.cols},
                    {"x0_px", map.x0_px},       {"y0_px", map.y0_px},  {"step_px", map.step_px}};
  if (px_per_mm) j["px_per_mm"] = *px_per_mm;
  j["masked_cells"] = masked;
  if (!(low <= high)) {
    j["range"] = "no value: every cell is masked or not measured";
    return j;
  }
  j["min"] = low;
  j["max"] = high;
  return j;
}

// Only the samples where both time and value are numbers: the arrays stay
// aligned, and the count left out is said.
void put_samples(ordered_json& e, const CurveSeries& s) {
  ordered_json t = ordered_json::array(), values = ordered_json::array();
  std::size_t left_out = 0;
  for (std::size_t i = 0; i < s.time_s.size() && i < s.temperature_c.size(); ++i) {
    if (!std::isfinite(s.time_s[i]) || !std::isfinite(s.temperature_c[i])) {
      ++left_out;
      continue;
    }
    t.push_back(s.time_s[i]);
    values.push_back(s.temperature_c[i]);
  }
  if (left_out > 0) e["non_finite_samples_left_out"] = left_out;
  e["time_s"] = std::move(t);
  e["temperature_c"] = std::move(values);
}

ordered_json series_json(const CurveSeries& s) {
  ordered_json e = {{"name", s.name}, {"kind", to_string(s.kind)}, {"unit", machine_unit(s.unit)}};
  if (s.image_px) e["image_px"] = {{"x", s.image_px->x}, {"y", s.image_px->y}};
  e["samples"] = s.time_s.size();
  e["excluded_samples"] = s.excluded_samples;
  if (s.fit) {
    e["fit"] = fit_json(*s.fit);
  } else {
    e["fit"] = "not fitted";
  }
  put_samples(e, s);
  return e;
}

ordered_json quality_json(const std::optional<QualityInfo>& quality) {
  if (!quality) return "not computed: the run has no frames to compare";
  const auto& q = quality->index;
  ordered_json j = {{"compared", quality->compared}};
  put_finite(j, "q_l", q.q_l);
  put_finite(j, "q_c", q.q_c);
  put_finite(j, "q_mod", q.q_mod);
  put_finite(j, "mean_image", q.mean_image);
  put_finite(j, "mean_reference", q.mean_reference);
  put_finite(j, "std_image", q.std_image);
  put_finite(j, "std_reference", q.std_reference);
  return j;
}

}  // namespace

ordered_json report_json(const ReportInput& input, const ReportSummary& summary,
                         const std::vector<FigureFiles>& figures, const std::vector<fs::path>& data_files) {
  ordered_json j;
  j["run"] = {
      {"name", input.run_name}, {"dir", input.run_dir}, {"started_utc", input.started_utc}, {"status", input.status}};
  j["time_basis"] = input.time_basis;
  j["conventions"] = {{"time", input.time_basis},
                      {"temperature", "degC"},
                      {"image", "pixels, origin at the top-left pixel's centre, x right, y down"}};
  j["notes"] = input.notes;
  j["summary"] = summary_json(summary);
  ordered_json series = ordered_json::array();
  for (const auto& s : input.series) series.push_back(series_json(s));
  j["series"] = std::move(series);
  ordered_json agreements = ordered_json::array();
  for (std::size_t i = 0; i < input.agreements.size() && i < summary.pairs.size(); ++i) {
    agreements.push_back(agreement_json(input.agreements[i], summary.pairs[i]));
  }
  j["agreements"] = std::move(agreements);
  ordered_json maps = ordered_json::array();
  for (const auto& m : input.displacement_maps) maps.push_back(map_json(m, input.px_per_mm));
  for (const auto& m : input.temperature_maps) maps.push_back(map_json(m, input.px_per_mm));
  j["maps"] = std::move(maps);
  j["image_quality"] = quality_json(input.quality);
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
