/* Runs first, before any other script can fail. */
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
