#include "parallax/report/html_report_assets.h"

// The stylesheet and the error trap of the HTML report, kept as raw strings (see html_report_assets.h).
namespace parallax::internal {

const char* HtmlReportStyle() {
  // Light page, dark 3D viewport; no web fonts (offline).
  return R"CSS(
:root {
  --ink: #1d2330; --muted: #5d6677; --line: #dfe3ea; --page: #f3f5f8; --card: #ffffff;
  --accent: #2f6fdf; --accent2: #e8833a; --good: #2e9d62; --bad: #d2423b; --scene: #131822;
}
* { box-sizing: border-box; }
body { margin: 0; background: var(--page); color: var(--ink);
  font: 14px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
header.top { background: linear-gradient(120deg, #18203a, #2b3f73); color: #fff; padding: 26px 0 20px; }
header.top .wrap, main .wrap, nav .wrap { max-width: 1320px; margin: 0 auto; padding: 0 24px; }
header.top h1 { margin: 0 0 4px; font-size: 26px; font-weight: 650; letter-spacing: 0.2px; }
header.top p { margin: 0; color: #c9d3ee; }
nav { position: sticky; top: 0; z-index: 5; background: rgba(255,255,255,0.94);
  border-bottom: 1px solid var(--line); backdrop-filter: blur(4px); }
nav .wrap { display: flex; gap: 18px; flex-wrap: wrap; padding-top: 8px; padding-bottom: 8px; }
nav a { color: var(--muted); text-decoration: none; font-weight: 550; font-size: 13px; }
nav a:hover { color: var(--accent); }
section.card { background: var(--card); border: 1px solid var(--line); border-radius: 10px;
  margin: 20px 0; padding: 18px 22px 20px; box-shadow: 0 1px 2px rgba(20,30,50,0.05); }
section.card > h2 { margin: 0 0 4px; font-size: 19px; font-weight: 650; }
section.card > p.lead { margin: 0 0 14px; color: var(--muted); }
h3 { font-size: 15px; margin: 18px 0 6px; font-weight: 620; }
p.note { color: var(--muted); margin: 4px 0 10px; font-size: 13px; }
p.missing { color: var(--muted); font-style: italic; background: #f6f7f9; padding: 10px 12px;
  border-radius: 6px; }
.cards { display: grid; grid-template-columns: repeat(auto-fit, minmax(170px, 1fr)); gap: 12px; }
.stat { border: 1px solid var(--line); border-radius: 8px; padding: 12px 14px; background: #fafbfd; }
.stat .value { font-size: 24px; font-weight: 680; font-variant-numeric: tabular-nums; }
.stat .label { color: var(--muted); font-size: 12.5px; }
.grid2 { display: grid; grid-template-columns: 1fr 1fr; gap: 18px; }
.grid4 { display: grid; grid-template-columns: repeat(4, 1fr); gap: 10px; }
figure { margin: 0; }
figcaption { color: var(--muted); font-size: 12.5px; margin-top: 4px; }
svg.frame { width: 100%; height: auto; display: block; border-radius: 6px; background: #e9ecf1; }
svg.chart { width: 100%; height: auto; display: block; }
svg.chart text { font-size: 11px; fill: #4a5365; }
svg.chart .axis-title { font-size: 12px; fill: #2c3444; font-weight: 600; }
.legend { display: flex; gap: 16px; font-size: 12.5px; color: var(--muted); margin: 4px 0 2px; }
.legend span::before { content: ""; display: inline-block; width: 11px; height: 11px;
  border-radius: 2px; margin-right: 6px; vertical-align: -1px; background: var(--swatch); }
.viewer { position: relative; background: var(--scene); border-radius: 8px; overflow: hidden; }
.viewer canvas { display: block; width: 100%; }
.viewer.main canvas { height: 620px; cursor: grab; }
.viewer.main canvas:active { cursor: grabbing; }
.viewer.small canvas { height: 230px; }
.viewer .tag { position: absolute; left: 10px; top: 8px; color: #dfe6f5; font-size: 12px;
  font-weight: 600; background: rgba(0,0,0,0.35); padding: 2px 8px; border-radius: 4px; }
.controls { display: flex; gap: 18px; align-items: center; flex-wrap: wrap; margin: 10px 0 14px;
  color: var(--muted); font-size: 13px; }
.controls button { border: 1px solid var(--line); background: #fff; border-radius: 6px;
  padding: 4px 12px; cursor: pointer; font: inherit; color: var(--ink); }
.controls button:hover { border-color: var(--accent); color: var(--accent); }
.heat { display: flex; gap: 20px; flex-wrap: wrap; align-items: flex-start; }
.heat canvas { image-rendering: pixelated; border: 1px solid var(--line); }
table.data { border-collapse: collapse; width: 100%; font-size: 13px; font-variant-numeric: tabular-nums; }
table.data th, table.data td { padding: 5px 10px; border-bottom: 1px solid var(--line); text-align: right; }
table.data th { color: var(--muted); font-weight: 600; background: #f7f8fa; position: sticky; top: 41px; }
table.data td:first-child, table.data th:first-child, table.data .left { text-align: left; }
table.data tr.unregistered td { color: var(--bad); }
table.data.kv { width: auto; min-width: 560px; margin-bottom: 6px; }
table.data.kv td:last-child { padding-left: 40px; }
.scroll { max-height: 560px; overflow: auto; border: 1px solid var(--line); border-radius: 6px; }
.scroll table.data th { top: 0; }
.pill { display: inline-block; padding: 0 8px; border-radius: 10px; font-size: 12px; font-weight: 600; }
.pill.yes { background: #e3f4ea; color: var(--good); }
.pill.no { background: #fbe6e5; color: var(--bad); }
.tooltip { position: fixed; pointer-events: none; background: rgba(20,25,35,0.92); color: #fff;
  font-size: 12px; padding: 4px 8px; border-radius: 4px; display: none; z-index: 10;
  white-space: pre; }
footer { color: var(--muted); font-size: 12px; text-align: center; padding: 10px 0 30px; }
@media (max-width: 900px) { .grid2, .grid4 { grid-template-columns: 1fr; } }
)CSS";
}

const char* HtmlReportErrorTrapScript() {
  // Runs first, before any other script can fail.
  return R"JS(
// Records the first uncaught error, failed resource or console.error in #report-status so
// that a headless browser test can read it from the DOM.
(function () {
  'use strict';
  var errors = [];
  window.reportErrors = errors;
  function record(text) {
    errors.push(String(text));
    var status = document.getElementById('report-status');
    if (status) status.textContent = 'error: ' + errors[0];
  }
  window.reportError = record;
  window.addEventListener('error', function (event) {
    var target = event.target;
    if (target && target !== window && target.tagName) {
      record('failed to load a ' + target.tagName.toLowerCase() + ' element');
      return;
    }
    record((event.message || 'script error') + ' (line ' + (event.lineno || '?') + ')');
  }, true);
  window.addEventListener('unhandledrejection', function (event) {
    record('unhandled rejection: ' + event.reason);
  });
  var consoleError = console.error;
  console.error = function () {
    record(Array.prototype.join.call(arguments, ' '));
    consoleError.apply(console, arguments);
  };
})();
)JS";
}

}  // namespace parallax::internal
