#pragma once
// The live page itself: one HTML document with inline CSS and script. It
// loads Chart.js from the server (/chart.js, never a CDN, so it works
// offline), the run's description from /api/run, and then follows
// /events with an EventSource: the chart of thermocouple channels against
// experiment seconds with the live BOS temperature at each (dashed), device
// states with polls ok/failed/skipped, active alarms and their limits, the
// run's events, frame count and rate, the latest frame (/frame.png) with the
// displacement at the probes drawn on it, and its image quality index.

#include <string_view>

namespace bosfuse::view {

std::string_view live_page_html();

}  // namespace bosfuse::view
