#!/usr/bin/env bash
# Opens REPORT_DIR/report.html (written by `stiffbench report --html`) in Debian's headless
# Chromium and checks it (docs/commands/report.md, "Browser check"):
#  - the scripts ran to the end (<html data-ready="1"> in the DOM Chromium dumps after loading),
#  - no error: none recorded by the page's first script (data-errors: uncaught errors, failed
#    loads, unhandled rejections, console.error) and no "CONSOLE" line in Chromium's log,
#  - every section of REPORT.md (its "## " headings) is a section of the page with that heading,
#    and every plot of REPORT.md (its "![" images) is an inline <svg> in a figure of the page,
#  - the sort self-test passed (the page opened with #selftest sorts every numeric column both
#    ways and writes data-selftest="ok: N columns"),
# and writes REPORT_DIR/report.png (a 1280x4000 screenshot). Exit 1 on any failure.
# Usage: scripts/check-html.sh REPORT_DIR   (CHROMIUM=/path/to/chromium to use another binary)
set -euo pipefail
dir="${1:?usage: check-html.sh REPORT_DIR}"
page="$(cd "$dir" && pwd)/report.html"
[ -f "$page" ] || { echo "check-html: no $page" >&2; exit 1; }
chromium="${CHROMIUM:-$(command -v chromium || true)}"
[ -n "$chromium" ] || { echo "check-html: chromium not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# --no-sandbox: Chromium's sandbox refuses to run as root (CI). A fresh profile per run.
flags=(--headless --no-sandbox --disable-gpu --no-first-run --hide-scrollbars
       --user-data-dir="$work/profile" --enable-logging=stderr --v=0)
start=$(date +%s%N)
"$chromium" "${flags[@]}" --dump-dom "file://$page#selftest" >"$work/dom.html" 2>"$work/dom.log" || {
  cat "$work/dom.log" >&2; echo "check-html: chromium --dump-dom failed" >&2; exit 1; }
"$chromium" "${flags[@]}" --window-size=1280,4000 --screenshot="$dir/report.png" "file://$page" \
  >/dev/null 2>"$work/shot.log" || {
  cat "$work/shot.log" >&2; echo "check-html: chromium --screenshot failed" >&2; exit 1; }
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
python3 - "$dir/REPORT.md" "$work/dom.html" "$work/dom.log" "$work/shot.log" "$dir/report.png" <<'PY'
import html.parser, os, re, sys
report_md, dom_file, *logs, shot = sys.argv[1:]
md = open(report_md, encoding="utf-8").read()
want_sections = [l[3:].strip() for l in md.splitlines() if l.startswith("## ")]
want_plots = sum(1 for l in md.splitlines() if l.startswith("!["))

class Dom(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.root = {}
        self.stack = []          # open tags
        self.sections = []       # heading text of each <section class="report-section">
        self.plots = 0           # <svg> directly inside <figure class="plot">
        self.in_h2 = None
    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "html": self.root = a
        parent = self.stack[-1] if self.stack else (None, {})
        if tag == "svg" and parent[0] == "figure" and "plot" in parent[1].get("class", "").split():
            self.plots += 1
        if tag == "h2" and parent[0] == "section" and "report-section" in parent[1].get("class", "").split():
            self.in_h2 = ""
        self.stack.append((tag, a))
    def handle_endtag(self, tag):
        while self.stack:
            t, _ = self.stack.pop()
            if t == tag: break
        if tag == "h2" and self.in_h2 is not None:
            self.sections.append(self.in_h2.strip()); self.in_h2 = None
    def handle_data(self, data):
        if self.in_h2 is not None: self.in_h2 += data

dom = Dom()
dom.feed(open(dom_file, encoding="utf-8").read())
failures = []
if dom.root.get("data-ready") != "1":
    failures.append("the page's scripts did not run to the end (no data-ready)")
if dom.root.get("data-errors"):
    failures.append("errors recorded by the page: " + dom.root["data-errors"])
for log in logs:
    for line in open(log, encoding="utf-8", errors="replace"):
        if ":CONSOLE" in line:
            failures.append("console message: " + line.strip())
selftest = dom.root.get("data-selftest", "(missing)")
if not selftest.startswith("ok"):
    failures.append("sort self-test: " + selftest)
if dom.sections != want_sections:
    missing = [s for s in want_sections if s not in dom.sections]
    failures.append(f"sections: {len(dom.sections)} in the page, {len(want_sections)} in REPORT.md; missing {missing}")
if dom.plots != want_plots:
    failures.append(f"plots: {dom.plots} inline SVG in the page, {want_plots} in REPORT.md")
if not os.path.isfile(shot) or os.path.getsize(shot) < 10000:
    failures.append("no screenshot " + shot)
if failures:
    print("check-html: FAIL", file=sys.stderr)
    for f in failures: print("  " + f, file=sys.stderr)
    sys.exit(1)
print(f"check-html: ok: {len(dom.sections)} sections, {dom.plots} inline SVG plots, sort self-test {selftest}, "
      f"no console error; screenshot {shot} ({os.path.getsize(shot)} bytes)")
PY
echo "check-html: chromium took ${elapsed_ms} ms (two page loads)"
