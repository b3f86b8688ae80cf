#include "report/report.h"

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "report/export.h"
#include "report/html.h"
#include "report/summary.h"
#include "storage/partial_file.h"

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

std::string figure_html(const FigureFiles& f, const FigureSize& size) {
  return fmt::format(
      "<figure><img class=\"figure\" src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{}\">"
      "<figcaption><b>{}</b> — {} <small>(also {} and {})</small></figcaption></figure>\n",
      data_uri(f.png, "image/png"), size.width_px, size.height_px, esc(f.title), esc(f.title), esc(f.caption),
      esc(f.png.filename().string()), esc(f.svg.filename().string()));
}

std::string n3(double v) { return display_number(v, "{:.3f}"); }

std::string quality_html(const ReportInput& input) {
  if (!input.quality) {
    return "<p class=\"note\">No image quality index: the run has no frames to compare.</p>\n";
  }
  const auto& q = input.quality->index;
  std::ostringstream h;
  h << "<table class=\"quality\"><tr><th>Q_L (luminance)</th><th>Q_C (contrast)</th><th>Q_mod</th>"
       "<th>mean image / reference</th><th>σ image / reference</th></tr>\n"
    << fmt::format("<tr><td>{}</td><td>{}</td><td><b>{}</b></td><td>{} / {}</td><td>{} / {}</td></tr></table>\n",
                   n3(q.q_l), n3(q.q_c), n3(q.q_mod), n3(q.mean_image), n3(q.mean_reference), n3(q.std_image),
                   n3(q.std_reference))
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

const CurveSeries* find_series(const ReportInput& input, const std::string& name) {
  for (const auto& s : input.series) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

// Where the report's files go, each with a unique name.
struct Output {
  fs::path dir;
  ReportOptions options;
  std::set<std::string> used{"report", "series", "fits", "summary"};
  fs::path base(const std::string& stem) { return unique_base(dir, stem, used); }
};

// The figures in the order the page shows them; `all` also lists them for the files section.
struct Figures {
  std::optional<FigureFiles> overview;
  std::vector<FigureFiles> curves;
  std::vector<FigureFiles> agreements;
  std::vector<std::string> agreement_notes;  // pairs that could not be drawn, and why
  std::vector<FigureFiles> displacement_maps;
  std::vector<FigureFiles> temperature_maps;
  std::vector<fs::path> map_csv;
  std::vector<FigureFiles> all;
};

void draw_curves(const ReportInput& input, Output& out, Figures& f) {
  std::vector<const CurveSeries*> drawable;
  for (const auto& s : input.series) {
    if (!s.time_s.empty()) drawable.push_back(&s);
  }
  if (drawable.size() > 1) {
    std::vector<CurveSeries> copies;
    for (const auto* s : drawable) copies.push_back(*s);
    f.overview = write_overview_figure(copies, out.options.curve_size, out.base("curves_all"), input.time_basis);
    f.all.push_back(*f.overview);
  }
  for (const auto* s : drawable) {
    const std::string prefix = s->kind == SeriesKind::kBosProbe ? "curve_probe_" : "curve_";
    f.curves.push_back(
        write_curve_figure(*s, out.options.curve_size, out.base(prefix + slug(s->name)), input.time_basis));
    f.all.push_back(f.curves.back());
  }
}

void draw_agreements(const ReportInput& input, Output& out, Figures& f) {
  for (const auto& e : input.agreements) {
    const auto* a = find_series(input, e.thermocouple);
    const auto* b = find_series(input, e.probe);
    if (!a || !b) {
      f.agreement_notes.push_back(
          fmt::format("No plot of {} against {}: the report holds no series named so.", e.thermocouple, e.probe));
      continue;
    }
    if (const auto* other = a->unit != "°C" ? a : (b->unit != "°C" ? b : nullptr)) {
      f.agreement_notes.push_back(fmt::format("No Bland–Altman plot of {} against {}: {} is in {}, not °C.",
                                              e.thermocouple, e.probe, other->name, other->unit));
      continue;
    }
    try {
      f.agreements.push_back(
          write_agreement_figure(*a, *b, e.agreement, out.options.curve_size,
                                 out.base("agreement_" + slug(e.thermocouple) + "_" + slug(e.probe))));
      f.all.push_back(f.agreements.back());
    } catch (const std::invalid_argument& error) {
      f.agreement_notes.push_back(error.what());
    }
  }
}

std::vector<FigureFiles> draw_maps(const std::vector<MapField>& maps, const std::string& kind, double default_spacing,
                                   const ReportInput& input, Output& out, Figures& f) {
  const auto markers = thermocouple_markers(input);
  std::vector<FigureFiles> drawn;
  for (const auto& m : maps) {
    const double spacing = m.contour_spacing > 0 ? m.contour_spacing : default_spacing;
    const fs::path base = out.base(fmt::format("map_{}{}", kind, m.time_s ? "_t" + time_tag(*m.time_s) : ""));
    drawn.push_back(write_map_figure(m, spacing, markers, input.px_per_mm, out.options.map_size, base));
    f.all.push_back(drawn.back());
    fs::path csv = drawn.back().png;
    csv.replace_extension(".csv");
    write_map_csv(m, input.px_per_mm, csv);
    f.map_csv.push_back(csv);
  }
  return drawn;
}

Figures draw_figures(const ReportInput& input, Output& out) {
  Figures f;
  draw_curves(input, out, f);
  draw_agreements(input, out, f);
  f.displacement_maps =
      draw_maps(input.displacement_maps, "displacement", out.options.displacement_contour_px, input, out, f);
  f.temperature_maps =
      draw_maps(input.temperature_maps, "temperature", out.options.temperature_contour_c, input, out, f);
  return f;
}

void write_text(const fs::path& path, const std::string& text) {
  storage::PartialFileStream file(path);
  file.stream() << text;
  file.close();
}

void write_data(const ReportInput& input, const ReportSummary& summary, const Figures& f, const fs::path& dir,
                ReportFiles& files) {
  files.csv = {dir / "summary.csv", dir / "series.csv", dir / "fits.csv"};
  files.csv.insert(files.csv.end(), f.map_csv.begin(), f.map_csv.end());
  write_summary_csv(summary, dir / "summary.csv");
  write_series_csv(input, dir / "series.csv");
  write_fits_csv(input, dir / "fits.csv");
  files.json = dir / "report.json";
  std::vector<fs::path> data = files.csv;
  data.push_back(files.json);
  write_text(files.json, report_json(input, summary, f.all, data).dump(2) + "\n");
}

std::string page_head(const std::string& title, const ReportInput& input) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << esc(title)
    << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  h << "<h1>" << esc(title) << "</h1>\n<dl class=\"run\">"
    << "<dt>run</dt><dd>" << esc(input.run_name) << "</dd><dt>folder</dt><dd><code>" << esc(input.run_dir)
    << "</code></dd><dt>started (UTC)</dt><dd>" << esc(input.started_utc) << "</dd><dt>status</dt><dd>"
    << esc(input.status) << "</dd><dt>time</dt><dd>" << esc(input.time_basis) << "</dd></dl>\n";
  for (const auto& note : input.notes) h << "<p class=\"note\">" << esc(note) << "</p>\n";
  return h.str();
}

// Why the BOS results are not there: processing failed, or has not been done.
std::string bos_missing(const ReportInput& input) {
  return input.bos_missing.empty() ? std::string(kNotProcessed) : esc(input.bos_missing) + ".";
}

std::string summary_section(const ReportInput& input, const ReportSummary& summary) {
  std::string h = "<h2 id=\"summary\">Summary</h2>\n" + summary_html(summary);
  if (!input.thermocouples_only.empty()) {
    return h + "<p class=\"note\">Thermocouples only: " + esc(input.thermocouples_only) +
           ", so this report has no BOS probes, agreement, maps or image quality index.</p>\n";
  }
  if (!input.agreements.empty()) return h;
  if (!input.has_probes()) return h + "<p class=\"note\">Thermocouples against BOS probes: " + bos_missing(input) + "</p>\n";
  return h + "<p class=\"note\">No thermocouple has a BOS probe at its position to compare with.</p>\n";
}

std::string curves_section(const ReportInput& input, const Figures& f, const ReportOptions& options) {
  std::string h = "<h2 id=\"curves\">Cooling curves</h2>\n";
  if (f.curves.empty()) h += "<p class=\"note\">The run has no temperature samples.</p>\n";
  if (!input.has_probes() && input.thermocouples_only.empty()) {
    h += "<p class=\"note\">BOS probe curves: " + bos_missing(input) + "</p>\n";
  }
  if (f.overview) h += figure_html(*f.overview, options.curve_size);
  for (const auto& figure : f.curves) h += figure_html(figure, options.curve_size);
  return h;
}

std::string agreement_section(const ReportInput& input, const Figures& f, const ReportOptions& options) {
  std::string h = "<h2 id=\"agreement\">Agreement of thermocouples and BOS probes</h2>\n";
  if (input.agreements.empty()) return h + "<p class=\"note\">No pairs to compare (see the summary).</p>\n";
  h += "<p>Δk, z, the RMS difference, the bias and the limits of agreement of each pair are in the summary at the "
       "top. Below, the Bland–Altman plots.</p>\n";
  for (const auto& note : f.agreement_notes) h += "<p class=\"note\">" + esc(note) + "</p>\n";
  for (const auto& figure : f.agreements) h += figure_html(figure, options.curve_size);
  return h;
}

std::string uncertainty_section(const ReportInput& input) {
  const auto& u = input.uncertainty;
  if (!u.budget && u.probes.empty() && u.fits.empty() && u.notes.empty()) return {};
  return uncertainty_html(u);
}

std::string maps_sections(const ReportInput& input, const Figures& f, const ReportOptions& options) {
  std::string h = "<h2 id=\"displacement\">Displacement maps</h2>\n";
  if (f.displacement_maps.empty()) {
    h += "<p class=\"note\">No displacement maps" +
         (input.displacement_maps_note.empty() ? "." : ": " + esc(input.displacement_maps_note) + ".") + "</p>\n";
  }
  for (const auto& figure : f.displacement_maps) h += figure_html(figure, options.map_size);
  h += "<h2 id=\"temperature\">Temperature maps</h2>\n";
  if (f.temperature_maps.empty()) h += "<p class=\"note\">" + bos_missing(input) + "</p>\n";
  for (const auto& figure : f.temperature_maps) h += figure_html(figure, options.map_size);
  return h;
}

std::string files_section(const ReportFiles& files) {
  std::string h = "<h2 id=\"files\">Files beside this report</h2>\n<ul class=\"files\">";
  for (const auto& f : files.figures) {
    h += "<li>" + esc(f.png.filename().string()) + "</li><li>" + esc(f.svg.filename().string()) + "</li>";
  }
  for (const auto& f : files.csv) h += "<li>" + esc(f.filename().string()) + "</li>";
  return h + "<li>report.json</li></ul>\n";
}

// The same files once moved from the staging folder into `dir`.
ReportFiles moved_to(ReportFiles files, const fs::path& dir) {
  const auto move = [&](fs::path& p) { p = dir / p.filename(); };
  move(files.html);
  move(files.json);
  for (auto& p : files.csv) move(p);
  for (auto& f : files.figures) {
    move(f.png);
    move(f.svg);
  }
  return files;
}

}  // namespace

ReportFiles write_report(const ReportInput& input, const ReportOptions& options, const fs::path& out_dir) {
  // Every file is written into a staging folder and moved in at the end: a
  // report that fails half-way leaves the folder's earlier report whole.
  storage::PartialFolder folder(out_dir);
  const std::string title = options.title.empty()
                                ? "Cooling report — " + (input.run_name.empty() ? std::string("run") : input.run_name)
                                : options.title;
  Output out{folder.path(), options};
  const Figures figures = draw_figures(input, out);
  const ReportSummary summary = summarize(input);
  ReportFiles files;
  files.figures = figures.all;
  write_data(input, summary, figures, folder.path(), files);

  files.html = folder.path() / "report.html";
  // A run with nothing for BOS gets the thermocouples' sections alone.
  const bool bos = input.thermocouples_only.empty();
  write_text(files.html, page_head(title, input) + summary_section(input, summary) +
                             (bos ? "<h2 id=\"quality\">Image quality index</h2>\n" + quality_html(input) : "") +
                             curves_section(input, figures, options) +
                             (bos ? agreement_section(input, figures, options) : "") + uncertainty_section(input) +
                             (bos ? maps_sections(input, figures, options) : "") + files_section(files) +
                             "</body>\n</html>\n");
  folder.commit();
  return moved_to(std::move(files), out_dir);
}

}  // namespace bosfuse::report
