#pragma once
// The live page itself: one HTML document with inline CSS and script. It
// loads Chart.js from the server (/chart.js, never a CDN, so it works
// offline), the run's description from /api/run, and then follows
// /events with an EventSource: the chart of thermocouple channels against
// experiment seconds, device states, the run's events and frame counts.

#include <string_view>

namespace bosfuse::view {

std::string_view live_page_html();

}  // namespace bosfuse::view
