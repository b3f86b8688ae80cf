#include "report/figures.h"

#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "fitting/sensor_lag.h"
#include "report/html.h"
#include "storage/partial_file.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

// cmap0 of every figure: 0 background, 1 foreground, 2 grid, 3 mask grey,
// 4 mask hatch, then series colours (Tableau 10).
constexpr int kBackground = 0, kInk = 1, kGrid = 2, kMaskFill = 3, kMaskHatch = 4, kFirstSeries = 5;
constexpr std::array<std::array<int, 3>, 15> kPalette{{{255, 255, 255},
                                                       {0, 0, 0},
                                                       {200, 200, 200},
                                                       {190, 190, 190},
                                                       {110, 110, 110},
                                                       {31, 119, 180},
                                                       {214, 39, 40},
                                                       {44, 160, 44},
                                                       {255, 127, 14},
                                                       {148, 103, 189},
                                                       {140, 86, 75},
                                                       {227, 119, 194},
                                                       {127, 127, 127},
                                                       {188, 189, 34},
                                                       {23, 190, 207}}};
constexpr int kSeriesColours = static_cast<int>(kPalette.size()) - kFirstSeries;
// A spare cmap0 slot after the palette, set to a translucent series colour to shade a band.
constexpr int kBandFill = static_cast<int>(kPalette.size());
constexpr double kBandAlpha = 0.22;
constexpr std::size_t kMaxPlottedPoints = 4000;
constexpr int kMaxDrawnCells = 250;  // per map side; finer grids are block-averaged for drawing  // per series; longer
                                     // records are decimated for drawing only

int series_colour(std::size_t i) { return kFirstSeries + static_cast<int>(i % kSeriesColours); }

// A cmap1 through these RGB (0..255) colours, evenly spaced.
template <std::size_t N>
void set_colour_map(const std::array<std::array<PLFLT, 3>, N>& colours) {
  std::array<PLFLT, N> pos{}, red{}, green{}, blue{};
  for (std::size_t i = 0; i < N; ++i) {
    pos[i] = static_cast<PLFLT>(i) / static_cast<PLFLT>(N - 1);
    red[i] = colours[i][0] / 255.0;
    green[i] = colours[i][1] / 255.0;
    blue[i] = colours[i][2] / 255.0;
  }
  plscmap1n(256);
  plscmap1l(1, static_cast<PLINT>(N), pos.data(), red.data(), green.data(), blue.data(), nullptr);
}

// cmap1 for maps of magnitudes: viridis (van der Walt and Smith, matplotlib),
// perceptually uniform and readable in grey, where jet invents bands at cyan
// and yellow.
void use_sequential_colour_map() {
  constexpr std::array<std::array<PLFLT, 3>, 9> kViridis{{{68, 1, 84},
                                                         {71, 44, 122},
                                                         {59, 81, 139},
                                                         {44, 113, 142},
                                                         {33, 144, 141},
                                                         {39, 173, 129},
                                                         {92, 200, 99},
                                                         {170, 220, 50},
                                                         {253, 231, 37}}};
  set_colour_map(kViridis);
}

// cmap1 for signed quantities: blue – white – red (ColorBrewer RdBu),
// white at zero, so the sign is read from the hue.
void use_diverging_colour_map() {
  constexpr std::array<std::array<PLFLT, 3>, 5> kRdBu{
      {{33, 102, 172}, {146, 197, 222}, {247, 247, 247}, {244, 165, 130}, {178, 24, 43}}};
  set_colour_map(kRdBu);
}

void load_palette() {
  std::array<PLINT, kPalette.size() + 1> r{}, g{}, b{};
  std::array<PLFLT, kPalette.size() + 1> alpha;
  alpha.fill(1.0);
  for (std::size_t i = 0; i < kPalette.size(); ++i) {
    r[i] = kPalette[i][0];
    g[i] = kPalette[i][1];
    b[i] = kPalette[i][2];
  }
  plscmap0a(r.data(), g.data(), b.data(), alpha.data(), static_cast<PLINT>(r.size()));
  use_sequential_colour_map();
}

// PLplot interprets '#' as the start of an escape sequence; "##" is a literal '#'.
std::string pl_text(const std::string& text) {
  std::string out;
  for (char c : text) {
    out += c;
    if (c == '#') out += '#';
  }
  return out;
}

// One PLplot stream on one device and file, ended when it goes out of scope.
class PlotStream {
 public:
  PlotStream(const char* device, const fs::path& file, const FigureSize& size) {
    plmkstrm(&stream_);
    plsdev(device);
    plsfnam(file.c_str());
    plspage(0, 0, size.width_px, size.height_px, 0, 0);
    load_palette();
    plinit();
    pladv(0);
    plcol0(kInk);
  }
  ~PlotStream() {
    plsstrm(stream_);
    plend1();
  }
  PlotStream(const PlotStream&) = delete;
  PlotStream& operator=(const PlotStream&) = delete;

 private:
  PLINT stream_ = 0;
};

void render_png_and_svg(const FigureFiles& files, const FigureSize& size, const std::function<void()>& draw) {
  if (size.width_px < 100 || size.height_px < 100 || size.width_px > 10000 || size.height_px > 10000) {
    throw std::invalid_argument(
        fmt::format("figure size {}×{} px is outside 100..10000", size.width_px, size.height_px));
  }
  if (!cairo_devices_available()) {
    throw std::runtime_error("PLplot has no pngcairo/svgcairo device: install the Debian package plplot-driver-cairo");
  }
  // PLplot's state is global: one figure at a time in this process.
  static std::mutex plplot_mutex;
  const std::lock_guard lock(plplot_mutex);
  // Each drawn under a temporary name and put in place once both are whole.
  storage::PartialFile png(files.png), svg(files.svg);
  for (const auto& [device, file] : {std::pair{"pngcairo", &png}, std::pair{"svgcairo", &svg}}) {
    const fs::path& path = file->path();
    // PLplot ends the process when it cannot open its output: find out first.
    if (!std::ofstream(path, std::ios::binary)) {
      throw std::runtime_error("cannot write '" + file->destination().string() + "'");
    }
    {
      PlotStream stream(device, path, size);
      draw();
    }
    if (!fs::exists(path) || fs::file_size(path) == 0) {
      throw std::runtime_error("PLplot wrote nothing to " + file->destination().string());
    }
  }
  png.commit();
  svg.commit();
}

FigureFiles files_for(const fs::path& base) {
  FigureFiles files;
  files.png = base;
  files.png += ".png";
  files.svg = base;
  files.svg += ".svg";
  return files;
}

struct Range {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  bool empty() const { return !(low <= high); }
  // Widened by a margin on both sides, never zero width.
  Range padded(double fraction) const {
    if (empty()) return {0, 1};
    const double span = high - low;
    const double pad = span > 0 ? span * fraction : std::max(std::abs(high) * 0.05, 0.5);
    return {low - pad, high + pad};
  }
};

std::vector<std::size_t> plotted_indices(std::size_t n) {
  std::vector<std::size_t> idx;
  const std::size_t stride = std::max<std::size_t>(1, (n + kMaxPlottedPoints - 1) / kMaxPlottedPoints);
  for (std::size_t i = 0; i < n; i += stride) idx.push_back(i);
  return idx;
}

bool fitted(const CurveSeries& s) { return s.fit && s.fit->ok(); }

// The fitted curve on [t_low, t_high] with its confidence band; no band
// when the fit has no covariance (one stored before it was kept).
struct FittedCurve {
  std::vector<PLFLT> t, temp, low, high;
  bool has_band() const { return !low.empty(); }
};

FittedCurve fitted_curve(const fitting::NewtonFit& fit, double t_low, double t_high) {
  constexpr int kPoints = 400;
  FittedCurve c;
  bool band = true;
  for (int i = 0; i < kPoints; ++i) {
    const double t = t_low + (t_high - t_low) * i / (kPoints - 1);
    const double half_width = fit.temperature_half_width_at(t);
    band = band && std::isfinite(half_width);
    c.t.push_back(t);
    c.temp.push_back(fit.temperature_at(t));
    c.low.push_back(c.temp.back() - half_width);
    c.high.push_back(c.temp.back() + half_width);
  }
  if (!band) {
    c.low.clear();
    c.high.clear();
  }
  return c;
}

void add_curve(Range& range, const FittedCurve& c) {
  for (const auto* values : {&c.temp, &c.low, &c.high})
    for (double v : *values) range.add(v);
}

// Shaded in a translucent `colour`, under the points and the line.
void draw_band(const FittedCurve& c, int colour) {
  if (!c.has_band()) return;
  std::vector<PLFLT> x = c.t, y = c.high;
  x.insert(x.end(), c.t.rbegin(), c.t.rend());
  y.insert(y.end(), c.low.rbegin(), c.low.rend());
  const auto& rgb = kPalette[colour];
  plscol0a(kBandFill, rgb[0], rgb[1], rgb[2], kBandAlpha);
  plcol0(kBandFill);
  plfill(static_cast<PLINT>(x.size()), x.data(), y.data());
}

void draw_line(const FittedCurve& c, int colour) {
  if (c.t.empty()) return;  // no fit
  plcol0(colour);
  plwidth(2);
  plline(static_cast<PLINT>(c.t.size()), c.t.data(), c.temp.data());
  plwidth(1);
}

std::string format_estimate(const fitting::Estimate& e, const char* unit) {
  if (e.fixed) return fmt::format("{} {} (fixed)", display_number(e.value, "{:.4g}"), unit);
  return fmt::format("{} {} [{}, {}]", display_number(e.value, "{:.4g}"), unit, display_number(e.low, "{:.4g}"),
                     display_number(e.high, "{:.4g}"));
}

// Short, as a journal's axes are; the time basis (origin, scale) is in
// every time figure's caption.
constexpr const char* kTimeAxisLabel = "t (s)";

std::size_t codepoints(const std::string& utf8) {
  return static_cast<std::size_t>(
      std::count_if(utf8.begin(), utf8.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// A label under the plot that is longer than the figure (a long time basis)
// is written smaller rather than cut off. PLplot has no public text-width
// query; 0.7 character heights per character is a little above DejaVu
// Sans's average, so the estimate errs towards fitting.
void bottom_label(const std::string& text, double disp) {
  PLFLT default_mm = 0, height_mm = 0, x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  plgchr(&default_mm, &height_mm);
  plgspa(&x0, &x1, &y0, &y1);
  const double width_mm = 0.7 * height_mm * static_cast<double>(codepoints(text));
  const double scale = width_mm > 0 ? std::min(1.0, 0.92 * (x1 - x0) / width_mm) : 1.0;
  plschr(0, scale);
  plmtex("b", disp / scale, 0.5, 0.5, text.c_str());
  plschr(0, 1);
}

std::string value_label(const CurveSeries& s) {
  return pl_text(s.unit == "°C" ? std::string("temperature (°C)") : "value (" + s.unit + ")");
}

std::string band_caption(const CurveSeries& s) {
  if (s.fit->covariance) {
    return fmt::format(", shaded with its {:.0f}% confidence band", 100 * s.fit->summary.confidence);
  }
  return " (no confidence band: the stored fit has no covariance)";
}

void draw_points(const std::vector<PLFLT>& x, const std::vector<PLFLT>& y, int colour) {
  if (x.empty()) return;
  plcol0(colour);
  plssym(0, x.size() > 600 ? 0.35 : (x.size() > 100 ? 0.6 : 1.0));
  plpoin(static_cast<PLINT>(x.size()), x.data(), y.data(), 17);  // 17: small filled dot
  plssym(0, 1);
}

}  // namespace

bool cairo_devices_available() {
  static const bool available = [] {
    // plgDevs fills at most `count` entries (the last one a null terminator).
    static const char* menus[256];
    static const char* names[256];
    const char** menu_ptr = menus;
    const char** name_ptr = names;
    int count = 256;
    plgDevs(&menu_ptr, &name_ptr, &count);
    bool png = false, svg = false;
    for (int i = 0; i < count; ++i) {
      if (names[i] && std::strcmp(names[i], "pngcairo") == 0) png = true;
      if (names[i] && std::strcmp(names[i], "svgcairo") == 0) svg = true;
    }
    return png && svg;
  }();
  return available;
}

FigureFiles write_curve_figure(const CurveSeries& series, const FigureSize& size, const fs::path& base,
                               const std::string& time_basis) {
  if (series.time_s.size() != series.temperature_c.size()) {
    throw std::invalid_argument("series '" + series.name + "': times and temperatures differ in length");
  }
  if (series.time_s.empty()) throw std::invalid_argument("series '" + series.name + "' has no samples to draw");
  FigureFiles files = files_for(base);
  const bool has_fit = fitted(series);
  files.title = fmt::format("{} {}", to_string(series.kind), series.name);
  files.caption =
      has_fit ? fmt::format(
                    "Samples of {} ({} points) with the fitted Newton curve (red){}; below, the residuals "
                    "(data − fit). k = {}, τ = {}. t in {}.",
                    series.name, series.time_s.size(), band_caption(series),
                    format_estimate(series.fit->k_per_s, "1/s"), format_estimate(series.fit->tau_s, "s"), time_basis)
              : fmt::format("Samples of {} ({} points). No Newton fit: {}. t in {}.", series.name, series.time_s.size(),
                            series.fit ? series.fit->summary.message : std::string("not fitted"), time_basis);

  std::vector<PLFLT> t, temp, residual;
  Range t_range, temp_range, residual_range;
  for (std::size_t i : plotted_indices(series.time_s.size())) {
    if (!std::isfinite(series.time_s[i]) || !std::isfinite(series.temperature_c[i])) continue;
    t.push_back(series.time_s[i]);
    temp.push_back(series.temperature_c[i]);
    t_range.add(t.back());
    temp_range.add(temp.back());
    if (has_fit) {
      residual.push_back(temp.back() - series.fit->temperature_at(t.back()));
      residual_range.add(residual.back());
    }
  }
  if (t.empty()) throw std::invalid_argument("series '" + series.name + "' has no finite samples to draw");
  FittedCurve curve;
  if (has_fit) {
    curve = fitted_curve(*series.fit, t_range.low, t_range.high);
    add_curve(temp_range, curve);
  }
  const Range tr = t_range.padded(0.02), yr = temp_range.padded(0.05);
  // Residual axis symmetric about zero.
  const double rmax = residual_range.empty()
                          ? 1.0
                          : std::max({std::abs(residual_range.low), std::abs(residual_range.high), 1e-6}) * 1.1;

  render_png_and_svg(files, size, [&] {
    const std::string title = pl_text(files.title);
    plvpor(0.1, 0.95, has_fit ? 0.40 : 0.12, 0.92);
    plwind(tr.low, tr.high, yr.low, yr.high);
    plcol0(kGrid);
    plbox("g", 0, 0, "g", 0, 0);
    plcol0(kInk);
    plbox(has_fit ? "bcst" : "bcnst", 0, 0, "bcnstv", 0, 0);
    plmtex("l", 4.5, 0.5, 0.5, value_label(series).c_str());
    plmtex("t", 1.5, 0.5, 0.5, title.c_str());
    draw_band(curve, kFirstSeries + 1);
    draw_line(curve, kFirstSeries + 1);  // under the points, so no sample is hidden by its fit
    draw_points(t, temp, kFirstSeries);
    if (has_fit) {
      const auto& f = *series.fit;
      const std::string fit_text = pl_text(
          fmt::format("k = {:.4g} 1/s [{:.4g}, {:.4g}]   T0 = {:.2f} {}   T_amb = {:.2f} {}", f.k_per_s.value,
                      f.k_per_s.low, f.k_per_s.high, f.t0_c.value, series.unit, f.ambient_c.value, series.unit));
      plcol0(kInk);
      plschr(0, 0.8);
      plmtex("t", -1.5, 0.97, 1.0, fit_text.c_str());
      plschr(0, 1);

      plvpor(0.1, 0.95, 0.10, 0.34);
      plwind(tr.low, tr.high, -rmax, rmax);
      plcol0(kGrid);
      plbox("g", 0, 0, "g", 0, 0);
      plcol0(kInk);
      plbox("bcnst", 0, 0, "bcnstv", 0, 3);
      const std::array<PLFLT, 2> zx{tr.low, tr.high}, zy{0, 0};
      plcol0(kFirstSeries + 1);
      plline(2, zx.data(), zy.data());
      draw_points(t, residual, kFirstSeries);
      plcol0(kInk);
      plmtex("l", 4.5, 0.5, 0.5, "residual (°C)");
    }
    if (!has_fit) {
      const std::string why =
          pl_text("no Newton fit: " +
                  (series.fit ? std::string(fitting::to_string(series.fit->summary.status)) : "not fitted"));
      plcol0(kFirstSeries + 1);
      plschr(0, 0.8);
      plmtex("t", -1.5, 0.97, 1.0, why.c_str());
      plschr(0, 1);
    }
    plcol0(kInk);
    bottom_label(kTimeAxisLabel, 3.0);
  });
  return files;
}

FigureFiles write_overview_figure(const std::vector<CurveSeries>& series, const FigureSize& size, const fs::path& base,
                                  const std::string& time_basis) {
  if (series.empty()) throw std::invalid_argument("no series to draw");
  FigureFiles files = files_for(base);
  files.title = "All cooling curves";
  files.caption =
      "Every series (points) with its fitted Newton curve (line of the same colour) and the curve's confidence band "
      "(shaded); thermocouples as dots, BOS probes as crosses. t in " +
      time_basis + ".";
  Range tr, yr;
  std::vector<std::vector<PLFLT>> ts(series.size()), ys(series.size());
  std::vector<FittedCurve> curves(series.size());
  for (std::size_t s = 0; s < series.size(); ++s) {
    const auto& cs = series[s];
    if (cs.time_s.size() != cs.temperature_c.size()) {
      throw std::invalid_argument("series '" + cs.name + "': times and temperatures differ in length");
    }
    Range own;
    for (std::size_t i : plotted_indices(cs.time_s.size())) {
      if (!std::isfinite(cs.time_s[i]) || !std::isfinite(cs.temperature_c[i])) continue;
      ts[s].push_back(cs.time_s[i]);
      ys[s].push_back(cs.temperature_c[i]);
      tr.add(cs.time_s[i]);
      own.add(cs.time_s[i]);
      yr.add(cs.temperature_c[i]);
    }
    if (fitted(cs) && !own.empty()) {
      curves[s] = fitted_curve(*cs.fit, own.low, own.high);
      add_curve(yr, curves[s]);
    }
  }
  if (tr.empty()) throw std::invalid_argument("no finite samples to draw");
  const Range t_range = tr.padded(0.02), y_range = yr.padded(0.05);

  render_png_and_svg(files, size, [&] {
    plvpor(0.1, 0.95, 0.12, 0.92);
    plwind(t_range.low, t_range.high, y_range.low, y_range.high);
    plcol0(kGrid);
    plbox("g", 0, 0, "g", 0, 0);
    plcol0(kInk);
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    pllab("", "temperature (°C)", "All cooling curves");
    bottom_label(kTimeAxisLabel, 3.2);
    // Bands, then every fit line, then every series' points on top: a fit
    // never hides the measurements it was fitted to.
    for (std::size_t s = 0; s < series.size(); ++s) draw_band(curves[s], series_colour(s));
    for (std::size_t s = 0; s < series.size(); ++s) draw_line(curves[s], series_colour(s));
    for (std::size_t s = 0; s < series.size(); ++s) {
      if (series[s].kind != SeriesKind::kBosProbe) draw_points(ts[s], ys[s], series_colour(s));
    }
    // BOS frames are few (tens): large bold crosses over the dense thermocouple dots.
    for (std::size_t s = 0; s < series.size(); ++s) {
      if (series[s].kind != SeriesKind::kBosProbe) continue;
      plcol0(series_colour(s));
      plwidth(2.5);
      plssym(0, 1.3);
      plpoin(static_cast<PLINT>(ts[s].size()), ts[s].data(), ys[s].data(), 5);  // 5: ×
      plssym(0, 1);
      plwidth(1);
    }
    // Legend to the right of the plot.
    const auto n = static_cast<PLINT>(series.size());
    std::vector<PLINT> opts(n, PL_LEGEND_LINE | PL_LEGEND_SYMBOL), colours(n), styles(n, 1), symbol_numbers(n, 3),
        text_colours(n, kInk), box_colours(n, 0), box_patterns(n, 0);
    std::vector<PLFLT> widths(n, 2.0), symbol_scales(n, 0.8), box_scales(n, 0.8), box_widths(n, 1.0);
    std::vector<std::string> texts(n), symbols(n);
    std::vector<const char*> text_ptrs(n), symbol_ptrs(n);
    for (PLINT s = 0; s < n; ++s) {
      colours[s] = series_colour(s);
      if (curves[s].t.empty()) opts[s] = PL_LEGEND_SYMBOL;  // no fitted curve to show
      texts[s] = pl_text(series[s].name);
      symbols[s] = series[s].kind == SeriesKind::kBosProbe ? "×" : "•";
      text_ptrs[s] = texts[s].c_str();
      symbol_ptrs[s] = symbols[s].c_str();
    }
    PLFLT legend_width = 0, legend_height = 0;
    plschr(0, 0.85);
    pllegend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
             PL_POSITION_RIGHT | PL_POSITION_TOP | PL_POSITION_INSIDE | PL_POSITION_VIEWPORT, 0.02, 0.02, 0.06,
             kBackground, kInk, 1, 0, 0, n, opts.data(), 1.0, 0.85, 2.0, 0.0, text_colours.data(), text_ptrs.data(),
             box_colours.data(), box_patterns.data(), box_scales.data(), box_widths.data(), colours.data(),
             styles.data(), widths.data(), colours.data(), symbol_scales.data(), symbol_numbers.data(),
             symbol_ptrs.data());
    plschr(0, 1);
  });
  return files;
}

AgreementPairs agreement_pairs(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement) {
  AgreementPairs pairs;
  pairs.time_constant_s = agreement.lag.time_constant_s;
  auto sa = fitting::clean_series(a.time_s, a.temperature_c, 0.0);
  if (pairs.time_constant_s > 0) {
    if (!fitted(a)) return pairs;  // no slope to de-lag with: lagged pairs would not be the agreement's
    sa = fitting::delagged(sa, *a.fit, pairs.time_constant_s);
  }
  const auto sb = fitting::clean_series(b.time_s, b.temperature_c, 0.0);
  for (std::size_t i = 0; i < sb.size(); ++i) {
    const auto reading = fitting::interpolate(sa, sb.time_s[i]);
    if (!reading) continue;
    pairs.time_s.push_back(sb.time_s[i]);
    pairs.mean_c.push_back(0.5 * (*reading + sb.temperature_c[i]));
    pairs.difference_c.push_back(*reading - sb.temperature_c[i]);
  }
  return pairs;
}

FigureFiles write_agreement_figure(const CurveSeries& a, const CurveSeries& b, const fitting::Agreement& agreement,
                                   const FigureSize& size, const fs::path& base) {
  const AgreementPairs pairs = agreement_pairs(a, b, agreement);
  if (pairs.mean_c.size() < 2) {
    throw std::invalid_argument(a.name + " and " + b.name + " share fewer than two times: nothing to compare");
  }
  // Thinned for drawing only: the caption's n and the statistics are of every pair.
  std::vector<PLFLT> mean, difference;
  Range mr, dr;
  for (const std::size_t i : plotted_indices(pairs.mean_c.size())) {
    mean.push_back(pairs.mean_c[i]);
    difference.push_back(pairs.difference_c[i]);
    mr.add(mean.back());
    dr.add(difference.back());
  }
  const auto& stats = agreement.series;
  if (stats) {
    dr.add(stats->limits_of_agreement_low_c);
    dr.add(stats->limits_of_agreement_high_c);
  }
  dr.add(0);
  FigureFiles files = files_for(base);
  files.title = fmt::format("Agreement of {} and {}", a.name, b.name);
  files.caption = fmt::format("Bland–Altman plot: {} − {} against their mean at the {} times of {} (n = {}; {} interpolated there{})",
                              a.name, b.name, pairs.mean_c.size(), b.name, pairs.mean_c.size(), a.name,
                              pairs.time_constant_s > 0
                                  ? fmt::format(", de-lagged by τ = {} s", display_number(pairs.time_constant_s, "{:.3g}"))
                                  : std::string());
  if (stats) {
    files.caption +=
        fmt::format("; red: bias {} °C, dashed: limits of agreement [{}, {}] °C",
                    display_number(stats->bias_c, "{:.3g}"), display_number(stats->limits_of_agreement_low_c, "{:.3g}"),
                    display_number(stats->limits_of_agreement_high_c, "{:.3g}"));
  }
  files.caption += ". " + agreement.verdict;
  const Range x = mr.padded(0.03), y = dr.padded(0.1);
  render_png_and_svg(files, size, [&] {
    plvpor(0.1, 0.95, 0.12, 0.92);
    plwind(x.low, x.high, y.low, y.high);
    plcol0(kGrid);
    plbox("g", 0, 0, "g", 0, 0);
    plcol0(kInk);
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    const std::string xl = pl_text(fmt::format("mean of {} and {} (°C)", a.name, b.name));
    const std::string yl = pl_text(fmt::format("{} − {} (°C)", a.name, b.name));
    const std::string title = pl_text(files.title);
    pllab(xl.c_str(), yl.c_str(), title.c_str());
    draw_points(mean, difference, kFirstSeries);
    const std::array<PLFLT, 2> lx{x.low, x.high};
    auto hline = [&](double value, int colour, int style) {
      if (!std::isfinite(value)) return;  // a line where there is no number would be a lie
      const std::array<PLFLT, 2> ly{value, value};
      plcol0(colour);
      pllsty(style);
      plwidth(2);
      plline(2, lx.data(), ly.data());
      plwidth(1);
      pllsty(1);
    };
    hline(0, kMaskHatch, 1);
    if (stats) {
      hline(stats->bias_c, kFirstSeries + 1, 1);
      hline(stats->limits_of_agreement_low_c, kFirstSeries + 1, 2);
      hline(stats->limits_of_agreement_high_c, kFirstSeries + 1, 2);
    }
  });
  return files;
}

namespace {

// A rectangle of grid nodes, rows r0..r1 and columns c0..c1 inclusive, every
// one of them measured.
struct MeasuredBlock {
  int r0, r1, c0, c1;
};

// The measured part of the grid as rectangles whose nodes are all measured:
// the runs of whole cells (four measured corners) along each row of cells,
// a run extended downwards while the next row has the same run. Colour bands
// and contours are computed inside these only, from measured values alone,
// so nothing is interpolated into or across a masked region and a contour
// neither enters the mask nor dives towards it at its edge.
std::vector<MeasuredBlock> measured_blocks(const cv::Mat& masked) {
  std::vector<MeasuredBlock> blocks;
  std::map<std::pair<int, int>, std::size_t> open;  // run (c0, c1) → block reaching the previous row of cells
  auto measured = [&](int r, int c) { return masked.at<std::uint8_t>(r, c) == 0; };
  for (int r = 0; r + 1 < masked.rows; ++r) {
    std::map<std::pair<int, int>, std::size_t> next;
    for (int c = 0; c + 1 < masked.cols;) {
      auto whole = [&](int cc) {
        return measured(r, cc) && measured(r, cc + 1) && measured(r + 1, cc) && measured(r + 1, cc + 1);
      };
      if (!whole(c)) {
        ++c;
        continue;
      }
      int end = c;
      while (end + 2 < masked.cols && whole(end + 1)) ++end;
      const std::pair run{c, end + 1};  // node columns
      if (const auto it = open.find(run); it != open.end()) {
        blocks[it->second].r1 = r + 1;
        next[run] = it->second;
      } else {
        blocks.push_back({r, r + 1, run.first, run.second});
        next[run] = blocks.size() - 1;
      }
      c = end + 1;
    }
    open = std::move(next);
  }
  return blocks;
}

// A measured node beside a not-measured one (or on a thin grid) lies on the
// edge of the bands drawn in measured_blocks(): it is drawn as its own cell in
// its own colour, so it shows without a value being invented beside it.
bool needs_own_cell(const cv::Mat& masked, int r, int c) {
  if (masked.at<std::uint8_t>(r, c)) return false;
  if (masked.rows < 2 || masked.cols < 2) return true;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int dc = -1; dc <= 1; ++dc) {
      const int rr = r + dr, cc = c + dc;
      if (rr >= 0 && cc >= 0 && rr < masked.rows && cc < masked.cols && masked.at<std::uint8_t>(rr, cc)) return true;
    }
  }
  return false;
}

// The legend's one entry, in the figure's bottom right corner: the hatch
// pattern of the cells that hold no measurement.
// World units per mm of the current viewport, along x and y.
std::array<double, 2> world_per_mm() {
  PLFLT sx0 = 0, sx1 = 0, sy0 = 0, sy1 = 0, vx0 = 0, vx1 = 0, vy0 = 0, vy1 = 0, wx0 = 0, wx1 = 0, wy0 = 0, wy1 = 0;
  plgspa(&sx0, &sx1, &sy0, &sy1);
  plgvpd(&vx0, &vx1, &vy0, &vy1);
  plgvpw(&wx0, &wx1, &wy0, &wy1);
  return {std::abs(wx1 - wx0) / ((vx1 - vx0) * (sx1 - sx0)), std::abs(wy1 - wy0) / ((vy1 - vy0) * (sy1 - sy0))};
}

// Thermocouple positions: a black dot ringed in white, its name in black on
// a white box beside it, so it reads on any colour of the map.
void draw_markers(const std::vector<MapMarker>& markers, double scale, std::array<double, 2> wx,
                  std::array<double, 2> wy) {
  plschr(0, 0.8);
  PLFLT default_mm = 0, height_mm = 0;
  plgchr(&default_mm, &height_mm);
  const auto [per_mm_x, per_mm_y] = world_per_mm();
  for (const auto& m : markers) {
    const PLFLT x = m.image_px.x * scale, y = m.image_px.y * scale;
    if (x < wx[0] || x > wx[1] || y < wy[0] || y > wy[1]) continue;
    plcol0(kBackground);
    plssym(0, 1.6);
    plpoin(1, &x, &y, 17);
    plcol0(kInk);
    plssym(0, 1.2);
    plpoin(1, &x, &y, 17);
    const std::string label = pl_text(m.name);
    const double left = x + 0.02 * (wx[1] - wx[0]);
    const double width = (0.72 * height_mm * static_cast<double>(codepoints(m.name)) + 1.5) * per_mm_x;
    const double half_height = 0.9 * height_mm * per_mm_y;
    const double pad = 0.75 * per_mm_x;
    const std::array<PLFLT, 4> bx{left - pad, left + width, left + width, left - pad};
    const std::array<PLFLT, 4> by{y - half_height, y - half_height, y + half_height, y + half_height};
    plcol0(kBackground);
    plfill(4, bx.data(), by.data());
    plcol0(kInk);
    plptex(left, y, 1, 0, 0, label.c_str());
  }
  plssym(0, 1);
  plschr(0, 1);
}

void draw_mask_legend() {
  const PLINT opts[] = {PL_LEGEND_COLOR_BOX}, text_colours[] = {kInk}, box_colours[] = {kMaskHatch},
              box_patterns[] = {3}, unused_int[] = {0};
  const PLFLT box_scales[] = {1.2}, box_widths[] = {1.0}, unused_float[] = {0};
  const char* texts[] = {"hatched: masked or not measured (no value)"};
  const char* no_symbol[] = {""};
  PLFLT width = 0, height = 0;
  plschr(0, 0.8);
  pllegend(&width, &height, 0, PL_POSITION_RIGHT | PL_POSITION_BOTTOM | PL_POSITION_INSIDE | PL_POSITION_SUBPAGE, 0.01,
           0.01, 0.05, kBackground, kInk, 1, 0, 0, 1, opts, 0.5, 0.8, 1.5, 1.0, text_colours,
           texts, box_colours, box_patterns, box_scales, box_widths, unused_int, unused_int, unused_float, unused_int,
           unused_float, unused_int, no_symbol);
  plschr(0, 1);
}

struct GridTransform {
  double x0, y0, step, scale;  // world = (x0 + i·step)·scale
};

void grid_to_world(PLFLT i, PLFLT j, PLFLT* x, PLFLT* y, PLPointer data) {
  const auto* g = static_cast<const GridTransform*>(data);
  *x = (g->x0 + i * g->step) * g->scale;
  *y = (g->y0 + j * g->step) * g->scale;
}

// At most about 32 arrows a side, on every stride-th node of the grid:
// denser arrows are unreadable. PLplot scales them so the longest spans
// about one drawn cell.
void draw_arrows(const MapField& map, double scale) {
  if (map.u_px.size() != map.values.size() || map.v_px.size() != map.values.size()) {
    throw std::invalid_argument("map '" + map.quantity + "': arrows need u and v of the values' size");
  }
  constexpr int kMaxArrowsPerSide = 32;
  const int stride = std::max(1, (std::max(map.values.rows, map.values.cols) + kMaxArrowsPerSide - 1) / kMaxArrowsPerSide);
  const int nx = (map.values.cols + stride - 1) / stride, ny = (map.values.rows + stride - 1) / stride;
  std::vector<std::vector<PLFLT>> u(nx, std::vector<PLFLT>(ny, 0.0)), v(nx, std::vector<PLFLT>(ny, 0.0));
  for (int c = 0; c < nx; ++c) {
    for (int r = 0; r < ny; ++r) {
      const double du = map.u_px.at<double>(r * stride, c * stride), dv = map.v_px.at<double>(r * stride, c * stride);
      if (!std::isfinite(du) || !std::isfinite(dv)) continue;  // zero length: PLplot draws nothing there
      u[c][r] = du;
      v[c][r] = dv;
    }
  }
  std::vector<const PLFLT*> u_rows(nx), v_rows(nx);
  for (int c = 0; c < nx; ++c) {
    u_rows[c] = u[c].data();
    v_rows[c] = v[c].data();
  }
  GridTransform transform{map.x0_px, map.y0_px, map.step_px * stride, scale};
  plcol0(kInk);
  plvect(u_rows.data(), v_rows.data(), nx, ny, 0.0, grid_to_world, &transform);
}

}  // namespace

FigureFiles write_map_figure(const MapField& map, double contour_spacing, const std::vector<MapMarker>& markers,
                             std::optional<double> px_per_mm, const FigureSize& size, const fs::path& base) {
  if (map.values.empty() || map.values.channels() != 1) {
    throw std::invalid_argument("map '" + map.quantity + "' has no single-channel values to draw");
  }
  if (!(map.step_px > 0)) throw std::invalid_argument("map '" + map.quantity + "': step_px must be positive");
  if (px_per_mm && !(*px_per_mm > 0)) throw std::invalid_argument("px per mm must be positive");
  cv::Mat values;
  map.values.convertTo(values, CV_64F);
  cv::Mat masked = cv::Mat::zeros(values.size(), CV_8U);
  if (!map.mask.empty()) {
    if (map.mask.size() != values.size()) throw std::invalid_argument("map mask and values differ in size");
    cv::Mat m;
    map.mask.convertTo(m, CV_8U);
    masked = m != 0;
  }
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      if (!std::isfinite(values.at<double>(r, c))) masked.at<std::uint8_t>(r, c) = 255;
    }
  }
  // A fine grid (a per-pixel temperature field) is averaged over blocks for
  // drawing, so the figure stays light; the CSV keeps every cell.
  double x0 = map.x0_px, y0 = map.y0_px, step = map.step_px;
  const int block = (std::max(values.rows, values.cols) + kMaxDrawnCells - 1) / kMaxDrawnCells;
  if (block > 1) {
    const int rows = (values.rows + block - 1) / block, cols = (values.cols + block - 1) / block;
    cv::Mat coarse(rows, cols, CV_64F, cv::Scalar(0)), coarse_masked(rows, cols, CV_8U, cv::Scalar(0));
    for (int R = 0; R < rows; ++R) {
      for (int C = 0; C < cols; ++C) {
        double sum = 0;
        int known = 0, total = 0;
        for (int r = R * block; r < std::min(values.rows, (R + 1) * block); ++r) {
          for (int c = C * block; c < std::min(values.cols, (C + 1) * block); ++c) {
            ++total;
            if (masked.at<std::uint8_t>(r, c)) continue;
            sum += values.at<double>(r, c);
            ++known;
          }
        }
        // A block is drawn as data only when every cell in it was measured: a mean over measured and
        // not-measured cells would show a value where there is none.
        if (known == total && known > 0) {
          coarse.at<double>(R, C) = sum / known;
        } else {
          coarse_masked.at<std::uint8_t>(R, C) = 255;
        }
      }
    }
    values = coarse;
    masked = coarse_masked;
    x0 += 0.5 * (block - 1) * step;
    y0 += 0.5 * (block - 1) * step;
    step *= block;
  }
  Range range;
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      if (!masked.at<std::uint8_t>(r, c)) range.add(values.at<double>(r, c));
    }
  }
  const bool any_data = !range.empty();
  if (!any_data) range = {0, 1};
  // Both signs: a diverging map symmetric about zero, white at zero.
  const bool signed_values = any_data && range.low < 0 && range.high > 0;
  if (signed_values) range = {-std::max(-range.low, range.high), std::max(-range.low, range.high)};
  if (range.high - range.low < 1e-9)
    range = {range.low - 0.5 * std::max(1e-3, std::abs(range.low) * 0.01),
             range.high + 0.5 * std::max(1e-3, std::abs(range.high) * 0.01)};
  const std::vector<MeasuredBlock> blocks = measured_blocks(masked);
  const bool any_masked = cv::countNonZero(masked) > 0;

  // Contour levels at multiples of the spacing; widened when there would be too many.
  constexpr int kMaxContours = 60;
  double spacing = contour_spacing > 0 ? contour_spacing : 0;
  std::vector<PLFLT> contours;
  bool widened = false;
  if (spacing > 0 && any_data) {
    while ((range.high - range.low) / spacing > kMaxContours) {
      spacing *= 2;
      widened = true;
    }
    for (double level = std::ceil(range.low / spacing) * spacing; level <= range.high && contours.size() < 200;
         level += spacing) {
      contours.push_back(level);
    }
  }
  constexpr int kBands = 24;
  std::vector<PLFLT> edges(kBands + 1);
  for (int i = 0; i <= kBands; ++i) edges[i] = range.low + (range.high - range.low) * i / kBands;

  const double scale = px_per_mm ? 1.0 / *px_per_mm : 1.0;
  const char* unit_axis = px_per_mm ? "mm" : "px";
  const cv::Size extent = map.image_size_px.empty()
                              ? cv::Size(static_cast<int>(std::ceil(map.x0_px + map.step_px * map.values.cols)),
                                         static_cast<int>(std::ceil(map.y0_px + map.step_px * map.values.rows)))
                              : map.image_size_px;
  const double wx0 = -0.5 * scale, wx1 = (extent.width - 0.5) * scale;
  const double wy0 = -0.5 * scale, wy1 = (extent.height - 0.5) * scale;
  GridTransform transform{x0, y0, step, scale};

  // PLplot grids are indexed [x][y].
  const int nx = values.cols, ny = values.rows;
  std::vector<std::vector<PLFLT>> z(nx, std::vector<PLFLT>(ny));
  for (int c = 0; c < nx; ++c) {
    for (int r = 0; r < ny; ++r) z[c][r] = values.at<double>(r, c);  // read only inside measured blocks
  }
  std::vector<const PLFLT*> z_rows(nx);
  for (int c = 0; c < nx; ++c) z_rows[c] = z[c].data();

  FigureFiles files = files_for(base);
  // A pair evaluated outside a run has no time to state.
  const std::string when = map.time_s ? fmt::format(" at t = {:.1f} s", *map.time_s) : std::string();
  files.title = map.quantity + when;
  files.caption = fmt::format(
      "{} ({}){}{}. Colour: value (bar on the right); black lines: contours every {:.3g} {}{}; hatched "
      "grey: masked or not measured ({} of {} cells), where no value is shown and no contour is drawn (bands and "
      "contours are computed from measured cells only); markers: thermocouple positions. Axes in {} from the image's "
      "top-left pixel, y pointing down.",
      map.quantity, map.unit, when, map.source.empty() ? "" : ", " + map.source, spacing, map.unit,
      widened ? " (widened from the requested spacing to keep the map readable)" : "", cv::countNonZero(masked),
      values.total(), unit_axis);
  if (!any_data) files.caption += " Every cell is masked: nothing was measured.";
  if (block > 1) {
    files.caption += fmt::format(
        " Drawn averaged over {0}×{0} cells of the {1}×{2} grid, a block with any cell not measured hatched (the CSV "
        "holds every cell).",
        block, map.values.cols, map.values.rows);
  }

  if (signed_values) files.caption += " Colour: blue below zero, red above, white at zero.";
  if (map.arrows) {
    files.caption += " Arrows: the measured displacement (u, v) on a thinned grid, scaled so the longest spans about "
                     "one arrow spacing; none where nothing was measured.";
  }
  render_png_and_svg(files, size, [&] {
    if (signed_values) use_diverging_colour_map();
    const double aspect = (wy1 - wy0) / (wx1 - wx0);
    plvpas(0.11, 0.80, 0.10, 0.92, aspect);
    plwind(wx0, wx1, wy1, wy0);  // y down, as in the image
    // Outside the grid nothing was evaluated: grey background first.
    plcol0(kMaskFill);
    const std::array<PLFLT, 4> bx{wx0, wx1, wx1, wx0}, by{wy0, wy0, wy1, wy1};
    plfill(4, bx.data(), by.data());
    const double half = 0.5 * step * scale;
    auto cell = [&](int r, int c, std::array<PLFLT, 4>& x, std::array<PLFLT, 4>& y) {
      const double cx = (x0 + c * step) * scale, cy = (y0 + r * step) * scale;
      x = {cx - half, cx + half, cx + half, cx - half};
      y = {cy - half, cy - half, cy + half, cy + half};
    };
    std::array<PLFLT, 4> x, y;
    plpsty(0);
    for (int r = 0; r < ny; ++r) {
      for (int c = 0; c < nx; ++c) {
        if (!needs_own_cell(masked, r, c)) continue;
        cell(r, c, x, y);
        plcol1((values.at<double>(r, c) - range.low) / (range.high - range.low));
        plfill(4, x.data(), y.data());
      }
    }
    for (const auto& b : blocks) {
      // The block's nodes as a PLplot matrix of its own ([x][y]: columns of z from c0, rows from r0).
      std::vector<const PLFLT*> columns;
      for (int c = b.c0; c <= b.c1; ++c) columns.push_back(z[c].data() + b.r0);
      plshades(columns.data(), b.c1 - b.c0 + 1, b.r1 - b.r0 + 1, nullptr, (x0 + b.c0 * step) * scale,
               (x0 + b.c1 * step) * scale, (y0 + b.r0 * step) * scale, (y0 + b.r1 * step) * scale, edges.data(),
               kBands + 1, 0, 0, 0, plfill, 1, nullptr, nullptr);
    }
    if (!contours.empty()) {
      plcol0(kInk);
      plwidth(1);
      for (const auto& b : blocks) {  // kx, lx, ky, ly: the block's node range, 1-based
        plcont(z_rows.data(), nx, ny, b.c0 + 1, b.c1 + 1, b.r0 + 1, b.r1 + 1, contours.data(),
               static_cast<PLINT>(contours.size()), grid_to_world, &transform);
      }
    }
    // Masked cells: grey, hatched.
    for (int r = 0; r < ny; ++r) {
      for (int c = 0; c < nx; ++c) {
        if (!masked.at<std::uint8_t>(r, c)) continue;
        cell(r, c, x, y);
        plpsty(0);
        plcol0(kMaskFill);
        plfill(4, x.data(), y.data());
        plpsty(3);
        plcol0(kMaskHatch);
        plfill(4, x.data(), y.data());
      }
    }
    plpsty(0);
    if (map.arrows) draw_arrows(map, scale);
    if (any_masked) draw_mask_legend();
    draw_markers(markers, scale, {wx0, wx1}, {wy0, wy1});
    plcol0(kInk);
    plbox("bcnst", 0, 0, "bcnstv", 0, 0);
    const std::string x_label = fmt::format("x ({})", unit_axis), y_label = fmt::format("y ({}, down)", unit_axis);
    const std::string title = pl_text(files.title);
    pllab(x_label.c_str(), y_label.c_str(), title.c_str());
    // Colour bar.
    const std::string bar_label = pl_text(fmt::format("{} ({})", map.quantity, map.unit));
    const PLINT label_opts[] = {PL_COLORBAR_LABEL_RIGHT};
    const char* labels[] = {bar_label.c_str()};
    const char* axis_opts[] = {"bcvtm"};
    const PLFLT ticks[] = {0};
    const PLINT sub_ticks[] = {0};
    const PLINT n_values[] = {kBands + 1};
    const PLFLT* value_rows[] = {edges.data()};
    PLFLT bar_width = 0, bar_height = 0;
    plschr(0, 0.8);
    plcolorbar(&bar_width, &bar_height, PL_COLORBAR_SHADE,
               PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02, 0, 0.04, 1.0, kBackground, kInk, 1,
               0, 0, 0, 0, 1, label_opts, labels, 1, axis_opts, ticks, sub_ticks, n_values, value_rows);
    plschr(0, 1);
  });
  return files;
}

std::filesystem::path figure_base(const std::filesystem::path& png_path) {
  if (png_path.extension() != ".png") {
    throw std::invalid_argument("'" + png_path.string() + "': a figure is named by its PNG file (name.png); its SVG "
                                "is written beside it");
  }
  return std::filesystem::path(png_path).replace_extension();
}

}  // namespace bosfuse::report
