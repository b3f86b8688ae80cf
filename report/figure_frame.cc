#include "report/figure_frame.h"

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <utility>

#include "storage/partial_file.h"

namespace bosfuse::report {
namespace figure_frame {
namespace {

namespace fs = std::filesystem;

// Per series; longer records are decimated for drawing only.
constexpr std::size_t kMaxPlottedPoints = 4000;

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

}  // namespace

void use_diverging_colour_map() {
  constexpr std::array<std::array<PLFLT, 3>, 5> kRdBu{
      {{33, 102, 172}, {146, 197, 222}, {247, 247, 247}, {244, 165, 130}, {178, 24, 43}}};
  set_colour_map(kRdBu);
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

std::size_t codepoints(const std::string& utf8) {
  return static_cast<std::size_t>(
      std::count_if(utf8.begin(), utf8.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

// PLplot has no public text-width query; 0.7 character heights per
// character is a little above DejaVu Sans's average, so the estimate errs
// towards fitting.
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

std::vector<std::size_t> plotted_indices(std::size_t n) {
  std::vector<std::size_t> idx;
  const std::size_t stride = std::max<std::size_t>(1, (n + kMaxPlottedPoints - 1) / kMaxPlottedPoints);
  for (std::size_t i = 0; i < n; i += stride) idx.push_back(i);
  return idx;
}

void draw_points(const std::vector<PLFLT>& x, const std::vector<PLFLT>& y, int colour) {
  if (x.empty()) return;
  plcol0(colour);
  plssym(0, x.size() > 600 ? 0.35 : (x.size() > 100 ? 0.6 : 1.0));
  plpoin(static_cast<PLINT>(x.size()), x.data(), y.data(), 17);  // 17: small filled dot
  plssym(0, 1);
}

FigureFiles files_for(const fs::path& base) {
  FigureFiles files;
  files.png = base;
  files.png += ".png";
  files.svg = base;
  files.svg += ".svg";
  return files;
}

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

}  // namespace figure_frame

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

std::filesystem::path figure_base(const std::filesystem::path& png_path) {
  if (png_path.extension() != ".png") {
    throw std::invalid_argument("'" + png_path.string() + "': a figure is named by its PNG file (name.png); its SVG "
                                "is written beside it");
  }
  return std::filesystem::path(png_path).replace_extension();
}

}  // namespace bosfuse::report
