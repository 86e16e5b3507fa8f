#!/usr/bin/env bash
# Opens REPORT_DIR/report.html (written by `stiffbench report --html`) in Debian's headless
# Chromium and checks it (docs/commands/report.md, "Browser check"):
#  - the scripts ran to the end (<html data-ready="1"> in the DOM Chromium dumps after loading),
#  - no error: none recorded by the page's first script (data-errors: uncaught errors, failed
#    loads, unhandled rejections, console.error) and no "CONSOLE" line in Chromium's log,
#  - every section of REPORT.md (its "## " headings) is a section of the page with that heading,
#    and every plot of REPORT.md (its "![" images) is an inline <svg> in a figure of the page,
#  - nothing is loaded from outside the page (no img/script/iframe/link… with a remote address),
#  - the sort self-test passed (the page opened with #selftest sorts every numeric column both
#    ways and writes data-selftest="ok: N columns"),
# and writes REPORT_DIR/report.png (a 1280x4000 screenshot). Then a negative control: the same
# page with one deliberate JavaScript error appended must fail the same check (so the check
# cannot pass silently, e.g. with a Chromium that runs no script or logs nothing).
# Exit 1 on any failure. Usage: scripts/check-html.sh DIR [PAGE MARKDOWN]
# (default PAGE report.html, MARKDOWN REPORT.md; `stiffbench profile --html`: profile.html
# profile.md; the screenshot is PAGE with .png; CHROMIUM=/path/to/chromium for another binary)
set -euo pipefail
dir="$(cd "${1:?usage: check-html.sh DIR [PAGE MARKDOWN]}" && pwd)"
page_name="${2:-report.html}"
md_name="${3:-REPORT.md}"
[ -f "$dir/$page_name" ] || { echo "check-html: no $dir/$page_name" >&2; exit 1; }
[ -f "$dir/$md_name" ] || { echo "check-html: no $dir/$md_name" >&2; exit 1; }
chromium="${CHROMIUM:-$(command -v chromium || true)}"
[ -n "$chromium" ] || { echo "check-html: chromium not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# check_page PAGE SCREENSHOT: loads PAGE twice (DOM dump with #selftest, screenshot) and checks
# the DOM against $dir/REPORT.md; prints the outcome, returns 1 on failure.
check_page() {
  local page="$1" shot="$2" tag
  tag="$(basename "$shot" .png)"
  # --no-sandbox: Chromium's sandbox refuses to run as root (CI). A fresh profile per load.
  local flags=(--headless --no-sandbox --disable-gpu --no-first-run --hide-scrollbars
               --enable-logging=stderr --v=0)
  # timeout: a hung browser fails the check rather than the CI job's time limit.
  if ! timeout 120 "$chromium" "${flags[@]}" --user-data-dir="$work/profile-$tag-dom" \
      --dump-dom "file://$page#selftest" >"$work/$tag.dom.html" 2>"$work/$tag.dom.log"; then
    tail -n 20 "$work/$tag.dom.log" >&2; echo "check-html: chromium --dump-dom failed" >&2; return 1
  fi
  if ! timeout 120 "$chromium" "${flags[@]}" --user-data-dir="$work/profile-$tag-shot" --window-size=1280,4000 \
      --screenshot="$shot" "file://$page" >/dev/null 2>"$work/$tag.shot.log"; then
    tail -n 20 "$work/$tag.shot.log" >&2; echo "check-html: chromium --screenshot failed" >&2; return 1
  fi
  python3 - "$dir/$md_name" "$work/$tag.dom.html" "$work/$tag.dom.log" "$work/$tag.shot.log" "$shot" <<'PY'
import html.parser, os, sys
report_md, dom_file, *logs, shot = sys.argv[1:]
md = open(report_md, encoding="utf-8").read()
want_sections = [l[3:].strip() for l in md.splitlines() if l.startswith("## ")]
want_plots = sum(1 for l in md.splitlines() if l.startswith("!["))

class Dom(html.parser.HTMLParser):
    """The <html> attributes, the heading of each <section class="report-section"> and the
    number of <svg> elements directly inside a <figure class="plot">."""
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.root, self.stack, self.sections, self.plots, self.h2 = {}, [], [], 0, None
        self.remote = []
    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "html": self.root = a
        # Addresses the browser fetches by itself when the page opens: a remote one would make
        # the "self-contained" page load from the network.
        loads = {"img": ["src", "srcset"], "script": ["src"], "iframe": ["src"], "embed": ["src"],
                 "source": ["src", "srcset"], "video": ["src", "poster"], "audio": ["src"],
                 "object": ["data"], "input": ["src"]}.get(tag, [])
        if tag == "link" and set((a.get("rel") or "").split()) & {"stylesheet", "icon", "preload", "prefetch"}:
            loads = ["href"]
        for attr in loads:
            v = (a.get(attr) or "").strip().lower()
            if v.startswith("//") or (":" in v.split("/")[0] and not v.startswith("data:")):
                self.remote.append(f"<{tag} {attr}={a.get(attr)}>")
        ptag, pattrs = self.stack[-1] if self.stack else (None, {})
        pclass = (pattrs.get("class") or "").split()
        if tag == "svg" and ptag == "figure" and "plot" in pclass: self.plots += 1
        if tag == "h2" and ptag == "section" and "report-section" in pclass: self.h2 = ""
        self.stack.append((tag, a))
    def handle_endtag(self, tag):
        while self.stack and self.stack.pop()[0] != tag: pass
        if tag == "h2" and self.h2 is not None:
            self.sections.append(self.h2.strip()); self.h2 = None
    def handle_data(self, data):
        if self.h2 is not None: self.h2 += data

dom = Dom()
dom.feed(open(dom_file, encoding="utf-8").read())
failures = []
if dom.root.get("data-ready") != "1":
    failures.append("the page's scripts did not run to the end (no data-ready)")
if dom.root.get("data-errors"):
    failures.append("errors recorded by the page: " + dom.root["data-errors"])
for log in logs:
    for line in open(log, encoding="utf-8", errors="replace"):
        if ":CONSOLE" in line: failures.append("console message: " + line.strip())
selftest = dom.root.get("data-selftest", "(missing)")
if not selftest.startswith("ok"): failures.append("sort self-test: " + selftest)
if dom.sections != want_sections:
    missing = [s for s in want_sections if s not in dom.sections]
    failures.append(f"sections: {len(dom.sections)} in the page, {len(want_sections)} in REPORT.md; missing {missing}")
if dom.remote:
    failures.append("loads from outside the page (remote addresses): " + ", ".join(dom.remote[:5]))
if dom.plots != want_plots:
    failures.append(f"plots: {dom.plots} inline SVG in the page, {want_plots} in REPORT.md")
# A blank 1280x4000 page is about 23 kB as PNG; report --quick gives about 690 kB.
if not os.path.isfile(shot) or os.path.getsize(shot) < 100000:
    failures.append("no screenshot with content (under 100 kB): " + shot)
if failures:
    print("check-html: FAIL " + dom_file, file=sys.stderr)
    for f in failures: print("  " + f, file=sys.stderr)
    sys.exit(1)
print(f"check-html: ok: {len(dom.sections)} sections, {dom.plots} inline SVG plots, sort self-test "
      f"{selftest}, no console error; screenshot {shot} ({os.path.getsize(shot)} bytes)")
PY
}

start=$(date +%s%N)
check_page "$dir/$page_name" "$dir/${page_name%.html}.png"
echo "check-html: the page took $(( ($(date +%s%N) - start) / 1000000 )) ms (two Chromium loads)"

# Negative control: a copy of the page (beside the original, so its relative links resolve the
# same) with a script calling an undefined function must fail, with the error recorded.
broken="$dir/.check-html-broken.html"
trap 'rm -rf "$work" "$broken"' EXIT
sed 's|</body>|<script>stiffbenchDeliberateError();</script></body>|' "$dir/$page_name" >"$broken"
if check_page "$broken" "$work/broken.png" 2>"$work/broken.err"; then
  echo "check-html: the negative control (a page with a deliberate error) passed the check" >&2
  exit 1
fi
if ! grep -q "stiffbenchDeliberateError" "$work/broken.err"; then
  cat "$work/broken.err" >&2
  echo "check-html: the negative control failed, but not on its deliberate error" >&2
  exit 1
fi
echo "check-html: negative control ok: a page with a deliberate error fails the check:"
sed 's/^/  | /' "$work/broken.err" | cut -c1-200

# Second negative control: the page with an image from another host must fail as loading from
# outside (the page is self-contained; a remote image in a note is written as a link instead).
sed 's|</body>|<img src="https://stiffbench.invalid/x.png" alt="remote"></body>|' "$dir/$page_name" >"$broken"
if check_page "$broken" "$work/remote.png" 2>"$work/remote.err"; then
  echo "check-html: the negative control (a page with a remote image) passed the check" >&2
  exit 1
fi
if ! grep -q "loads from outside the page" "$work/remote.err"; then
  cat "$work/remote.err" >&2
  echo "check-html: the remote-image control failed, but not on its remote image" >&2
  exit 1
fi
echo "check-html: negative control ok: a page with a remote image fails the check"
