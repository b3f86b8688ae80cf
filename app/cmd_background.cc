// bosfuse background: a printable random-dot background pattern, the same
// file serving as the digital reference for `bosfuse quality`. The file
// is the output and its description (the printed size) the result on
// standard output; `-o -` is refused, as the format (PNG or TIFF, each with
// its resolution for printing) comes from the file name.

#include <fmt/format.h>

#include <iostream>

#include "app/command.h"
#include "app/output_stream.h"
#include "sim/background_pattern.h"

namespace bosfuse::app {
namespace {

struct BackgroundArgs {
  std::string out;
  sim::PatternOptions pattern;
};

void background(const BackgroundArgs& args) {
  refuse_standard_output(args.out, "--out", "the pattern is a .png or .tif image whose format comes from its name");
  check_output(args.out, "--out");
  const auto pattern = sim::generate_pattern(args.pattern);
  sim::write_pattern_image(args.out, sim::render_pattern(pattern), args.pattern.dpi);
  const double mm_per_px = 25.4 / args.pattern.dpi;
  // What was written, for the person: on stderr, as every command that
  // writes a file the user named says it (stdout is data only).
  std::cerr << fmt::format(
      "{}: {}x{} px, {} dots of {:.2f} px, coverage {:.0f}%, seed {}; printed at {} dpi: {:.1f}x{:.1f} mm, dots "
      "{:.3f} mm\n",
      args.out, pattern.size.width, pattern.size.height, pattern.dots.size(), pattern.dot_diameter_px,
      100 * args.pattern.coverage, args.pattern.seed, args.pattern.dpi, pattern.size.width * mm_per_px,
      pattern.size.height * mm_per_px, pattern.dot_diameter_px * mm_per_px);
}

void add_background(CLI::App& root) {
  auto args = std::make_shared<BackgroundArgs>();
  auto& p = args->pattern;
  CLI::App* cmd = root.add_subcommand("background", "Write a random-dot BOS background pattern (PNG or TIFF with dpi)");
  cmd->add_option("--out,-o", args->out, "Pattern file (.png or .tif)")->required();
  cmd->add_option("--width", p.width_px, "Width, px")->capture_default_str();
  cmd->add_option("--height", p.height_px, "Height, px")->capture_default_str();
  auto* px = cmd->add_option("--dot-px", p.dot_diameter_px, "Dot diameter, px")->capture_default_str();
  auto* mm = cmd->add_option("--dot-mm", p.dot_diameter_mm, "Dot diameter on paper, mm (uses --dpi)");
  px->excludes(mm);
  cmd->add_option("--dpi", p.dpi, "Printing resolution stored in the file")->capture_default_str();
  cmd->add_option("--coverage", p.coverage, "Fraction of the area covered by dots (0..1)")->capture_default_str();
  cmd->add_option("--grey-levels", p.grey_levels, "Dot grey levels, 0..255")->delimiter(',')->capture_default_str();
  cmd->add_option("--seed", p.seed, "Random seed (the same seed gives the same pattern)")->capture_default_str();
  cmd->callback([args] { background(*args); });
}

BOSFUSE_COMMAND(add_background);

}  // namespace
}  // namespace bosfuse::app
