#pragma once

// The static parts of the HTML report (private to report/): the stylesheet and scripts in
// report/assets/, embedded at build time (report/CMakeLists.txt), so that the report needs
// no file at run time and no network.
namespace parallax::internal {

// The stylesheet.
const char* HtmlReportStyle();
// Installed first: turns uncaught errors and console.error into a status the tests read.
const char* HtmlReportErrorTrapScript();
// SVG and canvas plots (bar charts, heatmap, image overlays); no libraries.
const char* HtmlReportPlotsScript();
// The WebGL point-cloud viewer (orbit, pan, zoom) with a canvas 2D fallback.
const char* HtmlReportViewerScript();
// Builds the page sections from the embedded data.
const char* HtmlReportMainScript();

}  // namespace parallax::internal
