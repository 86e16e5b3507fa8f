// The HTML page writer (experiments/output/html.hpp): the Markdown subset, escaping, SVG inlining
// and the page itself. The expected strings are written out by hand from the rules in html.hpp (the
// HTML a reader would write for each input), not produced by the code under test.
#include "experiments/output/html.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace stiffbench;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("stiffbench_html_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A file shaped like gnuplot's svg terminal output: declaration, doctype, ids and references.
const char* kSvg =
    "<?xml version=\"1.0\" encoding=\"utf-8\"  standalone=\"no\"?>\n"
    "<svg \n width=\"600\" height=\"400\" viewBox=\"0 0 600 400\"\n"
    " xmlns=\"http://www.w3.org/2000/svg\"\n xmlns:xlink=\"http://www.w3.org/1999/xlink\"\n>\n"
    "<defs>\n\t<path id='gpDot' d='M-1,0 h2'/>\n\t<path id=\"gpPt0\" d=\"M-1,0 h2\"/>\n"
    "\t<clipPath id=\"clip\"><rect x=\"0\"/></clipPath>\n</defs>\n"
    "<g id=\"gnuplot_plot_1\" ><title>rk4 &lt;x&gt;</title>\n"
    "\t<use xlink:href=\"#gpPt0\" x=\"1\"/>\n\t<path clip-path=\"url(#clip)\" d=\"M0,0\"/>\n"
    "</g>\n</svg>\n\n";

}  // namespace

TEST(Html, EscapeReplacesTheFiveSpecialCharacters) {
  EXPECT_EQ(html_escape("<a href=\"x\">Tom & Jerry's</a>"),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; Jerry&#39;s&lt;/a&gt;");
  EXPECT_EQ(html_escape("h = 1e-3, ‖y‖∞"), "h = 1e-3, ‖y‖∞");  // UTF-8 passes unchanged
}

TEST(Html, MarkdownHeadingsParagraphsAndInlineElements) {
  EXPECT_EQ(markdown_to_html("## Orders & slopes ##\n"), "<h2>Orders &amp; slopes</h2>\n");
  // Two lines of one paragraph, a blank line, a second paragraph; underscores stay literal.
  EXPECT_EQ(markdown_to_html("The order of e_k/e_{k+1}\nis *p* or **p+1**.\n\nSee `t_end < 1`."),
            "<p>The order of e_k/e_{k+1}\nis <em>p</em> or <strong>p+1</strong>.</p>\n"
            "<p>See <code>t_end &lt; 1</code>.</p>\n");
  // A '*' followed by a space is not emphasis; a backslash escapes punctuation.
  EXPECT_EQ(markdown_to_html("2 * 3 * 4 and \\*x\\*"), "<p>2 * 3 * 4 and *x*</p>\n");
  EXPECT_EQ(markdown_to_html("[the CSV](osc/convergence.csv) ![plot](osc/a b.png)"),
            "<p><a href=\"osc/convergence.csv\">the CSV</a> "
            "<img src=\"osc/a b.png\" alt=\"plot\"></p>\n");
  // Only http, https, mailto and relative addresses become links; the text stays.
  EXPECT_EQ(markdown_to_html("[x](javascript:alert(1)) [y](https://a.org/?q=\"1\")"),
            "<p>x) <a href=\"https://a.org/?q=&quot;1&quot;\">y</a></p>\n");
  // A remote image is not loaded by the self-contained page: it becomes a link to the image.
  EXPECT_EQ(markdown_to_html("![p](https://a.org/p.png) ![q](//b.org/q.png)"),
            "<p><a href=\"https://a.org/p.png\">p (remote image)</a> "
            "<a href=\"//b.org/q.png\">q (remote image)</a></p>\n");
  EXPECT_EQ(markdown_to_html("<script>alert('x')</script>"),
            "<p>&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;</p>\n");
}

TEST(Html, MarkdownPipeTables) {
  const std::string md =
      "| integrator | order | note |\n"
      "|---|--:|:-:|\n"
      "| rk4 | 4 | `a\\|b` |\n"
      "| *heun* | 2 |\n";
  EXPECT_EQ(markdown_to_html(md),
            "<div class=\"table-wrap\"><table class=\"sortable\"><thead><tr>"
            "<th>integrator</th><th style=\"text-align:right\">order</th>"
            "<th style=\"text-align:center\">note</th></tr></thead><tbody>\n"
            "<tr><td>rk4</td><td style=\"text-align:right\">4</td>"
            "<td style=\"text-align:center\"><code>a|b</code></td></tr>\n"
            "<tr><td><em>heun</em></td><td style=\"text-align:right\">2</td>"
            "<td style=\"text-align:center\"></td></tr>\n"
            "</tbody></table></div>\n");
  // A line with pipes but no separator line under it is a paragraph.
  EXPECT_EQ(markdown_to_html("a | b\nc"), "<p>a | b\nc</p>\n");
}

TEST(Html, MarkdownListsAndCodeBlocks) {
  EXPECT_EQ(markdown_to_html("Dropped:\n- xpbd: 16 points\n  not measured\n- rk4 <ok>\n\nAfter."),
            "<p>Dropped:</p>\n<ul>\n<li>xpbd: 16 points\nnot measured</li>\n"
            "<li>rk4 &lt;ok&gt;</li>\n</ul>\n<p>After.</p>\n");
  EXPECT_EQ(markdown_to_html("1. first\n2. second\n"),
            "<ol>\n<li>first</li>\n<li>second</li>\n</ol>\n");
  EXPECT_EQ(markdown_to_html("```\nstiffbench run a.toml > *x*\n```\n"),
            "<pre><code>stiffbench run a.toml &gt; *x*\n</code></pre>\n");
}

TEST(Html, InlineSvgDropsTheDeclarationAndPrefixesIds) {
  const fs::path dir = scratch("svg");
  std::ofstream(dir / "p.svg") << kSvg;
  const std::string svg = inline_svg(dir / "p.svg", "s1p0");
  EXPECT_EQ(svg.rfind("<svg \n width=\"600\"", 0), 0u) << svg.substr(0, 80);
  EXPECT_EQ(svg.substr(svg.size() - 6), "</svg>");
  EXPECT_NE(svg.find("<path id=\"s1p0-gpPt0\""), std::string::npos);
  EXPECT_NE(svg.find("<clipPath id=\"s1p0-clip\">"), std::string::npos);
  EXPECT_NE(svg.find("<g id=\"s1p0-gnuplot_plot_1\" >"), std::string::npos);
  EXPECT_NE(svg.find("xlink:href=\"#s1p0-gpPt0\""), std::string::npos);
  EXPECT_NE(svg.find("clip-path=\"url(#s1p0-clip)\""), std::string::npos);
  EXPECT_EQ(svg.find("<?xml"), std::string::npos);
  EXPECT_EQ(inline_svg(dir / "missing.svg", "x"), "");
  fs::remove_all(dir);
}

TEST(Html, PageHoldsEverySectionPlotLinkAndMetadata) {
  const fs::path dir = scratch("page");
  std::ofstream(dir / "a.svg") << kSvg;
  std::ofstream(dir / "a.csv") << "integrator,h,error\nrk4,0.1,1e-5\n\"a,b\",0.05,<3\n";
  HtmlSection a{"osc",
                "Oscillator <k = 1>",
                "Slopes & orders.",
                "| x |\n|---|\n| 1 |\n",
                {dir / "a.svg"},
                dir / "a.csv",
                300,
                {{"convergence.csv", "osc/convergence.csv"}},
                {{"date", "2026-01-01"}}};
  HtmlSection b{"b 2", "Regions", "", "Text.", {dir / "none.svg"}, {}, 300, {}, {}};
  const std::string page =
      html_page("stiffbench <report>", {{"compiler", "g++ \"12\""}}, {a, b}, "Intro with `code`.");
  EXPECT_EQ(page.rfind("<!DOCTYPE html>\n<html lang=\"en\">", 0), 0u);
  EXPECT_NE(page.find("<title>stiffbench &lt;report&gt;</title>"), std::string::npos);
  EXPECT_NE(page.find("<th scope=\"row\">compiler</th><td>g++ &quot;12&quot;</td>"),
            std::string::npos);
  EXPECT_NE(page.find("<p>Intro with <code>code</code>.</p>"), std::string::npos);
  // Both sections, with anchors in the table of contents; "b 2" becomes a valid id.
  EXPECT_NE(page.find("<section class=\"report-section\" id=\"sec-osc\">\n<h2>Oscillator &lt;k = "
                      "1&gt;</h2>\n<p class=\"note\">Slopes &amp; orders.</p>"),
            std::string::npos);
  EXPECT_NE(page.find("<section class=\"report-section\" id=\"sec-b-2\">\n<h2>Regions</h2>"),
            std::string::npos);
  EXPECT_NE(page.find("<li><a href=\"#sec-b-2\">Regions</a></li>"), std::string::npos);
  // One plot (the second section's SVG is missing), its ids prefixed by section and plot.
  EXPECT_EQ(count(page, "<svg"), 1u);
  EXPECT_EQ(count(page, "<figure class=\"plot\"><svg"), 1u);
  EXPECT_NE(page.find("id=\"s0p0-gpPt0\""), std::string::npos);
  // The data table: the quoted CSV field is one cell, "<3" escaped; 2 rows.
  EXPECT_NE(page.find("<summary>Plotted data: a.csv (2 rows)</summary>"), std::string::npos);
  EXPECT_NE(page.find("<tr><td>a,b</td><td>0.05</td><td>&lt;3</td></tr>"), std::string::npos);
  EXPECT_NE(page.find("<p class=\"links\"><a href=\"osc/convergence.csv\">convergence.csv</a></p>"),
            std::string::npos);
  EXPECT_NE(page.find("<th scope=\"row\">date</th><td>2026-01-01</td>"), std::string::npos);
  // Self-contained: the stylesheet and both scripts inline, nothing loaded from elsewhere.
  EXPECT_EQ(count(page, "<script>"), 2u);
  EXPECT_EQ(count(page, "<style>"), 1u);
  EXPECT_NE(page.find("setAttribute(\"data-ready\", \"1\")"), std::string::npos);
  EXPECT_EQ(page.find("<script src"), std::string::npos);
  EXPECT_EQ(page.find("<link"), std::string::npos);
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);
  // Two sortable tables: the section's Markdown table and the data table.
  EXPECT_EQ(count(page, "<table class=\"sortable\"><thead>"), 2u);

  write_html_page(dir / "page.html", "stiffbench <report>", {{"compiler", "g++ \"12\""}}, {a, b},
                  "Intro with `code`.");
  std::ifstream in(dir / "page.html", std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), page);
  fs::remove_all(dir);
}

TEST(Html, DataTableIsCutAtItsRowLimit) {
  const fs::path dir = scratch("rows");
  {
    std::ofstream csv(dir / "big.csv");
    csv << "k\n";
    for (int k = 0; k < 10; ++k) csv << k << "\n";
  }
  HtmlSection s{"s", "S", "", "", {}, dir / "big.csv", 4, {}, {}};
  const std::string page = html_page("t", {}, {s});
  EXPECT_NE(page.find("<summary>Plotted data: big.csv (first 4 of 10 rows)</summary>"),
            std::string::npos);
  EXPECT_NE(page.find("<tr><td>3</td></tr>"), std::string::npos);
  EXPECT_EQ(page.find("<tr><td>4</td></tr>"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Html, MetadataFromJson) {
  const nlohmann::json j = {{"version", "0.1"}, {"threads", 2}, {"spec", {{"suite", "quick"}}}};
  const HtmlMetadata rows = html_metadata(j, 300);
  ASSERT_EQ(rows.size(), 3u);  // nlohmann::json orders keys alphabetically
  EXPECT_EQ(rows[0], (std::pair<std::string, std::string>{"spec", "{\"suite\":\"quick\"}"}));
  EXPECT_EQ(rows[1], (std::pair<std::string, std::string>{"threads", "2"}));
  EXPECT_EQ(rows[2], (std::pair<std::string, std::string>{"version", "0.1"}));
  EXPECT_EQ(html_metadata({{"k", "abcdef"}}, 3)[0].second, "abc...");
}

// Malformed input stays text: unclosed links, marks and fences render literally (the expected
// strings follow the rules in html.hpp), and every '<' of the output opens one of the renderer's
// own tags (an input tag is always escaped).
TEST(Html, MalformedMarkdownStaysEscapedText) {
  EXPECT_EQ(markdown_to_html("[unclosed"), "<p>[unclosed</p>\n");
  EXPECT_EQ(markdown_to_html("[a]("), "<p>[a](</p>\n");
  EXPECT_EQ(markdown_to_html("**bold"), "<p>**bold</p>\n");
  EXPECT_EQ(markdown_to_html("``a`"), "<p>``a`</p>\n");
  EXPECT_EQ(markdown_to_html("a\\"), "<p>a\\</p>\n");
  EXPECT_EQ(markdown_to_html("```\nno end"), "<pre><code>no end\n</code></pre>\n");
  EXPECT_EQ(markdown_to_html("####### seven"), "<p>####### seven</p>\n");
  const std::vector<std::string> own = {"<p>",         "</p>",
                                        "<h1>",        "</h1>",
                                        "<h2>",        "</h2>",
                                        "<code>",      "</code>",
                                        "<em>",        "</em>",
                                        "<strong>",    "</strong>",
                                        "<a href=\"",  "</a>",
                                        "<img src=\"", "<ul>",
                                        "</ul>",       "<ol>",
                                        "</ol>",       "<li>",
                                        "</li>",       "<pre>",
                                        "</pre>",      "<div class=\"table-wrap\">",
                                        "</div>",      "<table class=\"sortable\">",
                                        "</table>",    "<thead>",
                                        "</thead>",    "<tbody>",
                                        "</tbody>",    "<tr>",
                                        "</tr>",       "<th>",
                                        "<th style",   "</th>",
                                        "<td>",        "<td style",
                                        "</td>"};
  for (const std::string md :
       {"[unclosed", "![x](", "*", "`", "| a |\n|---|", "|", "- ", "1.", "\\", "***x***",
        "<img src=x onerror=alert(1)>", "[<b>](<i>)", "| a | b |\n|---|---|\n| <x> | `<y>` |",
        "- <li>\n- [z](javascript:x)", "*<em>*", "# <h1>"}) {
    const std::string html = markdown_to_html(md);
    for (std::size_t p = html.find('<'); p != std::string::npos; p = html.find('<', p + 1)) {
      bool known = false;
      for (const auto& tag : own) known = known || html.compare(p, tag.size(), tag) == 0;
      EXPECT_TRUE(known) << md << " -> " << html;
    }
  }
}
