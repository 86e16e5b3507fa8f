// stiffbench HTML page, first script (experiments/output/html/errors.js): records every uncaught error,
// unhandled promise rejection and console.error call in the attribute data-errors of <html>, so
// a dumped DOM (scripts/check-html.sh) shows them. Written by hand for stiffbench; no library.
(function () {
  "use strict";
  var root = document.documentElement;
  function record(message) {
    var previous = root.getAttribute("data-errors");
    root.setAttribute("data-errors", (previous ? previous + " | " : "") + String(message));
  }
  window.addEventListener("error", function (e) {
    record(e.message || (e.target && e.target.tagName ? "failed to load " + e.target.tagName : "error"));
  }, true);
  window.addEventListener("unhandledrejection", function (e) {
    record("unhandled rejection: " + (e.reason && e.reason.message ? e.reason.message : e.reason));
  });
  var original = console.error;
  console.error = function () {
    record(Array.prototype.join.call(arguments, " "));
    return original.apply(console, arguments);
  };
})();
