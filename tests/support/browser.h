#pragma once
// A report page opened in a real headless browser (Debian's chromium), to
// check that every figure renders: a small script added to a copy of the
// page draws each <img> on a canvas once loaded and writes what it found
// into the DOM, which chromium --dump-dom hands back.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/subprocess.h"

namespace bosfuse::testing {

// For each <img> of the page, once loaded: "complete WxH spread", where
// spread is max − min of the channel values the browser decoded (drawn on a
// canvas; data: URIs do not taint it), so a blank image shows as spread 0.
inline constexpr const char* kRenderCheckScript = R"js(<script>
window.addEventListener('load', () => {
  const out = [];
  for (const img of document.images) {
    let spread = -1;
    try {
      const canvas = document.createElement('canvas');
      canvas.width = img.naturalWidth;
      canvas.height = img.naturalHeight;
      const g = canvas.getContext('2d');
      g.drawImage(img, 0, 0);
      const d = g.getImageData(0, 0, canvas.width, canvas.height).data;
      let lo = 255, hi = 0;
      for (let i = 0; i < d.length; i += 4 * 7) {
        lo = Math.min(lo, d[i], d[i + 1], d[i + 2]);
        hi = Math.max(hi, d[i], d[i + 1], d[i + 2]);
      }
      spread = hi - lo;
    } catch (e) {
      spread = -2;
    }
    out.push(img.complete + ' ' + img.naturalWidth + 'x' + img.naturalHeight + ' ' + spread);
  }
  const pre = document.createElement('pre');
  pre.id = 'render-check';
  pre.textContent = out.join(';');
  document.body.appendChild(pre);
});
</script>)js";

struct RenderedImage {
  bool complete = false;
  std::string size;  // natural size WxH as decoded by the browser; 0x0 when it could not decode it
  int spread = -1;   // max − min of the decoded pixel values; 0 for a blank image
};

inline bool have_chromium() { return run_command("which chromium", 10).exit_code == 0; }

// A path in single quotes for /bin/sh (the tests' temporary paths hold no quote).
inline std::string shell_quote(const std::filesystem::path& path) {
  std::string out = "'";  // appended piecewise: GCC 12 warns (-Wrestrict) on "'" + s + "'"
  out += path.string();
  out += '\'';
  return out;
}

// chromium headless with its profile in `scratch`, bounded by `timeout_s`.
inline CommandResult chromium(const std::filesystem::path& scratch, const std::string& args, int timeout_s = 120) {
  return run_command(
      "chromium --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run "
      "--hide-scrollbars --user-data-dir=" +
          shell_quote(scratch / "chromium-profile") + " " + args,
      timeout_s);
}

// Opens a copy of `html` (written to `copy`) with kRenderCheckScript added
// and reads back what the browser found per <img>.
inline std::vector<RenderedImage> render_check(std::string html, const std::filesystem::path& copy,
                                               const std::filesystem::path& scratch) {
  const auto body_end = html.rfind("</body>");
  if (body_end == std::string::npos) {
    ADD_FAILURE() << "no </body>";
    return {};
  }
  html.insert(body_end, kRenderCheckScript);
  std::ofstream(copy) << html;
  const auto dom = chromium(scratch, "--virtual-time-budget=15000 --dump-dom " +
                                         shell_quote(std::filesystem::path("file://" + copy.string())));
  EXPECT_EQ(dom.exit_code, 0) << dom.output.substr(0, 2000);
  const std::string tag = "<pre id=\"render-check\">";
  const auto start = dom.output.find(tag);
  if (start == std::string::npos) {
    ADD_FAILURE() << "the check script did not run:\n" << dom.output.substr(0, 2000);
    return {};
  }
  const auto text_start = start + tag.size();
  std::stringstream items(dom.output.substr(text_start, dom.output.find("</pre>", text_start) - text_start));
  std::vector<RenderedImage> images;
  for (std::string item; std::getline(items, item, ';') && images.size() < 1000;) {
    std::stringstream fields(item);
    std::string complete;
    RenderedImage image;
    fields >> complete >> image.size >> image.spread;
    image.complete = complete == "true";
    images.push_back(image);
  }
  return images;
}

}  // namespace bosfuse::testing
