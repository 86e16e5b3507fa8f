// stiffbench HTML page, last script (experiments/output/html/page.js): sortable tables and the
// self-test. Written by hand for stiffbench; no library.
//
// Every <table class="sortable"> sorts by a column when its header is clicked (again: reversed).
// Cells compare as numbers when both parse as numbers (1e-3 < 9e-3 < 1e-2, "-" and blanks last),
// otherwise as text. Opening the page with the hash #selftest sorts every numeric column of
// every table both ways and checks the order of the rows, then writes the outcome to
// <html data-selftest="ok: N columns"> (or "fail: ...") for scripts/check-html.sh.
(function () {
  "use strict";

  function cellText(row, col) {
    var cell = row.cells[col];
    return cell ? cell.textContent.trim() : "";
  }

  // A number, or NaN for text and for blanks / dashes.
  function numberOf(text) {
    var t = text.replace(/[\u2212]/g, "-").replace(/,/g, "");
    if (!/^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?%?$/.test(t) && !/^[-+]?(inf|nan)$/i.test(t))
      return NaN;
    if (/^[-+]?inf$/i.test(t)) return t.charAt(0) === "-" ? -Infinity : Infinity;
    return parseFloat(t);
  }

  // Cells fall in three classes, always in this order: numbers, text, empty; within a class
  // numbers compare by value and text by locale order (reversed for a descending sort).
  function rank(text) {
    if (text === "") return 2;
    return isNaN(numberOf(text)) ? 1 : 0;
  }
  function compare(a, b, descending) {
    var ra = rank(a), rb = rank(b);
    if (ra !== rb) return ra - rb;
    var c = 0;
    if (ra === 0) {
      var na = numberOf(a), nb = numberOf(b);
      c = na < nb ? -1 : (na > nb ? 1 : 0);
    } else if (ra === 1) {
      c = a.localeCompare(b, undefined, { numeric: true });
    }
    return descending ? -c : c;
  }

  function sortTable(table, col, descending) {
    var body = table.tBodies[0];
    if (!body) return;
    var rows = Array.prototype.slice.call(body.rows);
    var keyed = rows.map(function (row, index) {
      return { row: row, key: cellText(row, col), index: index };
    });
    keyed.sort(function (x, y) {
      var c = compare(x.key, y.key, descending);
      return c !== 0 ? c : x.index - y.index;  // stable
    });
    keyed.forEach(function (k) { body.appendChild(k.row); });
    var headers = table.tHead ? table.tHead.rows[0].cells : [];
    for (var i = 0; i < headers.length; ++i)
      headers[i].setAttribute("aria-sort", i === col ? (descending ? "descending" : "ascending") : "none");
  }

  function makeSortable(table) {
    if (!table.tHead || !table.tHead.rows.length) return;
    var headers = table.tHead.rows[0].cells;
    Array.prototype.forEach.call(headers, function (th, col) {
      th.setAttribute("aria-sort", "none");
      th.tabIndex = 0;
      th.title = "sort by this column";
      var activate = function () {
        sortTable(table, col, th.getAttribute("aria-sort") === "ascending");
      };
      th.addEventListener("click", activate);
      th.addEventListener("keydown", function (e) {
        if (e.key === "Enter" || e.key === " ") { e.preventDefault(); activate(); }
      });
    });
  }

  // #selftest: sort every column holding at least two numbers both ways and check that the
  // numeric cells then appear in order (text and blanks after them).
  function selfTest(tables) {
    var checked = 0, failures = [];
    tables.forEach(function (table, t) {
      if (!table.tBodies[0] || !table.tHead) return;
      var ncol = table.tHead.rows[0].cells.length;
      for (var col = 0; col < ncol; ++col) {
        var rows = table.tBodies[0].rows;
        var numeric = 0;
        for (var r = 0; r < rows.length; ++r) if (!isNaN(numberOf(cellText(rows[r], col)))) ++numeric;
        if (numeric < 2) continue;
        [false, true].forEach(function (descending) {
          table.tHead.rows[0].cells[col].click();
          if (descending !== (table.tHead.rows[0].cells[col].getAttribute("aria-sort") === "descending"))
            failures.push("table " + t + " column " + col + ": header click did not toggle");
          var values = [];
          var rows2 = table.tBodies[0].rows;
          for (var r2 = 0; r2 < rows2.length; ++r2) values.push(numberOf(cellText(rows2[r2], col)));
          var seenText = false;
          for (var k = 0; k < values.length; ++k) {
            if (isNaN(values[k])) { seenText = true; continue; }
            if (seenText) { failures.push("table " + t + " column " + col + ": number after text"); break; }
            if (k > 0 && !isNaN(values[k - 1]) &&
                (descending ? values[k - 1] < values[k] : values[k - 1] > values[k])) {
              failures.push("table " + t + " column " + col + (descending ? " descending" : " ascending") +
                            ": " + values[k - 1] + " before " + values[k]);
              break;
            }
          }
        });
        ++checked;
      }
    });
    if (checked === 0) failures.push("no numeric column to sort");
    document.documentElement.setAttribute(
        "data-selftest", failures.length ? "fail: " + failures.slice(0, 5).join("; ") : "ok: " + checked + " columns");
  }

  var tables = Array.prototype.slice.call(document.querySelectorAll("table.sortable"));
  tables.forEach(makeSortable);
  if (window.location.hash === "#selftest") selfTest(tables);
  document.documentElement.setAttribute("data-ready", "1");
})();
