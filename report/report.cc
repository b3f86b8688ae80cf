#include "report/report.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "report/export.h"
#include "report/html.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

constexpr const char* kNotProcessed =
    "Not processed yet — run <code>bosfuse process RUN</code> to evaluate the frames into BOS probes and temperature "
    "fields, then make the report again.";

constexpr const char* kStyle = R"css(
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 2em auto; max-width: 1000px; color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: right; vertical-align: top; }
th { background: #f2f2f2; }
td.text, th.text { text-align: left; }
figure { margin: 1.5em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #444; }
.note { background: #fff8e1; border-left: 4px solid #f0b400; padding: 0.5em 1em; margin: 1em 0; }
.warning { color: #9a5b00; }
.error { color: #b00020; }
dl.run { display: grid; grid-template-columns: max-content auto; gap: 0.2em 1em; }
dl.run dt { font-weight: bold; }
dl.run dd { margin: 0; }
ul.files { columns: 2; font-family: monospace; }
)css";

std::string esc(const std::string& text) { return html_escape(text); }

// A number, or "—" where it could not be computed: never "nan" in a table.
std::string num(double value, const char* format) {
  return std::isfinite(value) ? fmt::format(fmt::runtime(format), value) : "—";
}

std::string fmt_estimate(const fitting::Estimate& e, const char* format) {
  if (!std::isfinite(e.value)) return "—";
  const std::string value = fmt::format(fmt::runtime(format), e.value);
  if (e.fixed) return value + " (fixed)";
  return fmt::format("{}<br><small>[{}, {}]</small>", value, num(e.low, format), num(e.high, format));
}

std::string figure_html(const FigureFiles& f, const FigureSize& size) {
  return fmt::format(
      "<figure><img class=\"figure\" src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{}\">"
      "<figcaption><b>{}</b> — {} <small>(also {} and {})</small></figcaption></figure>\n",
      data_uri(f.png, "image/png"), size.width_px, size.height_px, esc(f.title), esc(f.title), esc(f.caption),
      esc(f.png.filename().string()), esc(f.svg.filename().string()));
}

std::string fits_table(const ReportInput& input) {
  double confidence = 0.95;  // the fits' own, as they were made
  for (const auto& s : input.series) {
    if (s.fit) confidence = s.fit->summary.confidence;
  }
  std::ostringstream h;
  h << "<table class=\"fits\"><tr><th class=\"text\">series</th><th class=\"text\">kind</th><th>points</th>"
    << fmt::format("<th>k (1/s)<br><small>{:.0f}% interval</small></th>", confidence * 100)
    << "<th>τ (s)</th><th>T0 (°C)</th><th>T_amb (°C)</th><th>residual RMS (°C)</th>"
       "<th class=\"text\">status</th></tr>\n";
  for (const auto& s : input.series) {
    h << "<tr><td class=\"text\">" << esc(s.name) << "</td><td class=\"text\">" << to_string(s.kind) << "</td>";
    if (!s.fit) {
      h << "<td>" << s.time_s.size() << "</td><td colspan=\"5\"></td><td class=\"text\">not fitted</td></tr>\n";
      continue;
    }
    const auto& f = *s.fit;
    h << "<td>" << f.summary.points_used << "</td>";
    if (!f.ok()) {
      h << "<td colspan=\"5\">—</td><td class=\"text error\">" << esc(fitting::to_string(f.summary.status)) << ": "
        << esc(f.summary.message) << "</td></tr>\n";
      continue;
    }
    h << "<td>" << fmt_estimate(f.k_per_s, "{:.4g}") << "</td><td>" << fmt_estimate(f.tau_s, "{:.4g}") << "</td><td>"
      << fmt_estimate(f.t0_c, "{:.2f}") << "</td><td>" << fmt_estimate(f.ambient_c, "{:.2f}") << "</td><td>"
      << num(f.summary.residual_rms_c, "{:.3g}") << "</td><td class=\"text\">ok";
    for (const auto& w : f.summary.warnings) h << "<br><span class=\"warning\">" << esc(w) << "</span>";
    if (s.excluded_samples > 0) {
      h << "<br>" << s.excluded_samples << " samples without a temperature (non-ok status) left out";
    }
    h << "</td></tr>\n";
  }
  h << "</table>\n";
  h << "<p><small>Model T(t) = T_amb + (T0 − T_amb)·exp(−k·t), t in s since the run's first sample (so T0 is the "
       "fitted temperature then). Intervals from the fit's covariance, scaled by the residual variance unless the "
       "measurement σ was given (docs/FITTING.md).</small></p>\n";
  return h.str();
}

std::string agreement_table(const ReportInput& input) {
  std::ostringstream h;
  h << "<table class=\"agreement\"><tr><th class=\"text\">thermocouple</th><th class=\"text\">BOS probe</th>"
       "<th>Δk (1/s)</th><th>z</th><th>RMS difference (°C)</th><th>bias (°C)</th><th>95% limits of agreement "
       "(°C)</th><th class=\"text\">verdict</th></tr>\n";
  for (const auto& e : input.agreements) {
    const auto& a = e.agreement;
    h << "<tr><td class=\"text\">" << esc(e.thermocouple) << "</td><td class=\"text\">" << esc(e.probe) << "</td>";
    if (a.k) {
      h << "<td>" << num(a.k->difference_per_s, "{:.3g}") << " ± " << num(a.k->std_error_per_s, "{:.2g}") << "</td><td>"
        << num(a.k->z, "{:.2f}") << "</td>";
    } else {
      h << "<td>—</td><td>—</td>";
    }
    if (a.series) {
      const auto& d = *a.series;
      h << "<td>" << num(d.rms_difference_c, "{:.3g}") << "</td><td>" << num(d.bias_c, "{:.3g}") << "</td><td>["
        << num(d.limits_of_agreement_low_c, "{:.3g}") << ", " << num(d.limits_of_agreement_high_c, "{:.3g}")
        << "]</td>";
    } else {
      h << "<td colspan=\"3\">too few common times</td>";
    }
    h << "<td class=\"text\">" << esc(a.verdict) << "</td></tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

std::string quality_html(const ReportInput& input) {
  if (!input.quality) {
    return "<p class=\"note\">No image quality index: the run has no frames to compare.</p>\n";
  }
  const auto& q = input.quality->index;
  std::ostringstream h;
  h << "<table class=\"quality\"><tr><th>Q_L (luminance)</th><th>Q_C (contrast)</th><th>Q_mod</th>"
       "<th>mean image / reference</th><th>σ image / reference</th></tr>\n"
    << fmt::format(
           "<tr><td>{:.3f}</td><td>{:.3f}</td><td><b>{:.3f}</b></td><td>{:.3f} / {:.3f}</td>"
           "<td>{:.3f} / {:.3f}</td></tr></table>\n",
           q.q_l, q.q_c, q.q_mod, q.mean_image, q.mean_reference, q.std_image, q.std_reference)
    << "<p>" << esc(input.quality->compared)
    << ". Q_mod = Q_L·Q_C (Gojani &amp; Obayashi 2012): cross-correlation failed on images with Q_mod ≈ 0.01 and "
       "worked on Q_mod ≈ 0.7; values near 1 mean the two images have the same brightness and contrast.</p>\n";
  return h.str();
}

std::vector<MapMarker> thermocouple_markers(const ReportInput& input) {
  std::vector<MapMarker> markers;
  for (const auto& s : input.series) {
    if (s.kind == SeriesKind::kThermocouple && s.image_px) markers.push_back({s.name, *s.image_px});
  }
  return markers;
}

// A unique file base name in `dir`.
fs::path unique_base(const fs::path& dir, const std::string& stem, std::set<std::string>& used) {
  std::string name = stem;
  for (int i = 2; used.count(name) && i < 100000; ++i) name = stem + "_" + std::to_string(i);
  used.insert(name);
  return dir / name;
}

std::string time_tag(double t_s) {
  const long rounded = std::lround(t_s);
  return rounded < 0 ? fmt::format("m{}s", -rounded) : fmt::format("{}s", rounded);
}

}  // namespace

ReportFiles write_report(const ReportInput& input, const ReportOptions& options, const fs::path& out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) {
    throw std::runtime_error("cannot create the report folder '" + out_dir.string() + "': " + ec.message());
  }
  ReportFiles files;
  std::set<std::string> used{"report", "series", "fits"};
  const std::string title = options.title.empty()
                                ? "Cooling report — " + (input.run_name.empty() ? std::string("run") : input.run_name)
                                : options.title;

  // Figures.
  std::vector<FigureFiles> curve_figures;
  std::optional<FigureFiles> overview;
  std::vector<const CurveSeries*> drawable;
  for (const auto& s : input.series) {
    if (!s.time_s.empty()) drawable.push_back(&s);
  }
  if (drawable.size() > 1) {
    std::vector<CurveSeries> copies;
    for (const auto* s : drawable) copies.push_back(*s);
    overview = write_overview_figure(copies, options.curve_size, unique_base(out_dir, "curves_all", used));
    files.figures.push_back(*overview);
  }
  for (const auto* s : drawable) {
    const std::string prefix = s->kind == SeriesKind::kBosProbe ? "curve_probe_" : "curve_";
    curve_figures.push_back(
        write_curve_figure(*s, options.curve_size, unique_base(out_dir, prefix + slug(s->name), used)));
    files.figures.push_back(curve_figures.back());
  }
  const auto markers = thermocouple_markers(input);
  auto draw_maps = [&](const std::vector<MapField>& maps, const std::string& kind, double default_spacing) {
    std::vector<FigureFiles> out;
    for (std::size_t i = 0; i < maps.size(); ++i) {
      const auto& m = maps[i];
      const double spacing = m.contour_spacing > 0 ? m.contour_spacing : default_spacing;
      const std::string stem = fmt::format("map_{}_t{}", kind, time_tag(m.time_s));
      out.push_back(
          write_map_figure(m, spacing, markers, input.px_per_mm, options.map_size, unique_base(out_dir, stem, used)));
      files.figures.push_back(out.back());
      fs::path csv = out.back().png;
      csv.replace_extension(".csv");
      write_map_csv(m, input.px_per_mm, csv);
      files.csv.push_back(csv);
    }
    return out;
  };
  std::vector<FigureFiles> agreement_figures;
  std::vector<std::string> agreement_notes;
  auto find_series = [&](const std::string& name) -> const CurveSeries* {
    for (const auto& s : input.series) {
      if (s.name == name) return &s;
    }
    return nullptr;
  };
  for (const auto& e : input.agreements) {
    const auto* a = find_series(e.thermocouple);
    const auto* b = find_series(e.probe);
    if (!a || !b) {
      agreement_notes.push_back(
          fmt::format("No plot of {} against {}: the report holds no series named so.", e.thermocouple, e.probe));
      continue;
    }
    try {
      agreement_figures.push_back(write_agreement_figure(
          *a, *b, e.agreement, options.curve_size,
          unique_base(out_dir, "agreement_" + slug(e.thermocouple) + "_" + slug(e.probe), used)));
      files.figures.push_back(agreement_figures.back());
    } catch (const std::invalid_argument& error) {
      agreement_notes.push_back(error.what());
    }
  }
  const auto displacement_figures = draw_maps(input.displacement_maps, "displacement", options.displacement_contour_px);
  const auto temperature_figures = draw_maps(input.temperature_maps, "temperature", options.temperature_contour_c);

  // Data.
  files.csv.insert(files.csv.begin(), {out_dir / "series.csv", out_dir / "fits.csv"});
  write_series_csv(input, out_dir / "series.csv");
  write_fits_csv(input, out_dir / "fits.csv");
  files.json = out_dir / "report.json";
  {
    std::vector<fs::path> data = files.csv;
    data.push_back(files.json);
    std::ofstream out(files.json);
    if (!out) throw std::runtime_error("cannot write '" + files.json.string() + "'");
    out << report_json(input, files.figures, data).dump(2) << "\n";
    if (!out) throw std::runtime_error("writing '" + files.json.string() + "' failed");
  }

  // The page.
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << esc(title)
    << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  h << "<h1>" << esc(title) << "</h1>\n<dl class=\"run\">"
    << "<dt>run</dt><dd>" << esc(input.run_name) << "</dd><dt>folder</dt><dd><code>" << esc(input.run_dir)
    << "</code></dd><dt>started (UTC)</dt><dd>" << esc(input.started_utc) << "</dd><dt>status</dt><dd>"
    << esc(input.status) << "</dd></dl>\n";
  for (const auto& note : input.notes) h << "<p class=\"note\">" << esc(note) << "</p>\n";

  h << "<h2 id=\"quality\">Image quality index</h2>\n" << quality_html(input);

  h << "<h2 id=\"curves\">Cooling curves</h2>\n";
  if (drawable.empty()) h << "<p class=\"note\">The run has no temperature samples.</p>\n";
  if (!input.has_probes()) {
    h << "<p class=\"note\">BOS probe curves: " << kNotProcessed << "</p>\n";
  }
  if (overview) h << figure_html(*overview, options.curve_size);
  for (const auto& f : curve_figures) h << figure_html(f, options.curve_size);

  h << "<h2 id=\"fits\">Fitted parameters</h2>\n" << fits_table(input);

  h << "<h2 id=\"agreement\">Agreement of thermocouples and BOS probes</h2>\n";
  if (!input.agreements.empty()) {
    h << agreement_table(input);
    for (const auto& note : agreement_notes) h << "<p class=\"note\">" << esc(note) << "</p>\n";
    for (const auto& f : agreement_figures) h << figure_html(f, options.curve_size);
  } else if (!input.has_probes()) {
    h << "<p class=\"note\">" << kNotProcessed << "</p>\n";
  } else {
    h << "<p class=\"note\">No thermocouple has a BOS probe at its position to compare with.</p>\n";
  }

  h << "<h2 id=\"displacement\">Displacement maps</h2>\n";
  if (displacement_figures.empty()) {
    h << "<p class=\"note\">No displacement maps"
      << (input.displacement_maps_note.empty() ? "." : ": " + esc(input.displacement_maps_note) + ".") << "</p>\n";
  }
  for (const auto& f : displacement_figures) h << figure_html(f, options.map_size);

  h << "<h2 id=\"temperature\">Temperature maps</h2>\n";
  if (temperature_figures.empty()) h << "<p class=\"note\">" << kNotProcessed << "</p>\n";
  for (const auto& f : temperature_figures) h << figure_html(f, options.map_size);

  h << "<h2 id=\"files\">Files beside this report</h2>\n<ul class=\"files\">";
  for (const auto& f : files.figures) {
    h << "<li>" << esc(f.png.filename().string()) << "</li><li>" << esc(f.svg.filename().string()) << "</li>";
  }
  for (const auto& f : files.csv) h << "<li>" << esc(f.filename().string()) << "</li>";
  h << "<li>report.json</li></ul>\n</body>\n</html>\n";

  files.html = out_dir / "report.html";
  std::ofstream out(files.html);
  if (!out) throw std::runtime_error("cannot write '" + files.html.string() + "'");
  out << h.str();
  out.flush();
  if (!out) throw std::runtime_error("writing '" + files.html.string() + "' failed");
  return files;
}

}  // namespace bosfuse::report
