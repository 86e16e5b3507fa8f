// One self-contained HTML page from Markdown text, gnuplot SVG files and links: the writer of
// `stiffbench report --html` (experiments/commands/report.cpp), reusable by any command that has
// sections of Markdown and plots. No network at view time: the CSS and JavaScript
// (experiments/output/html/*.css, *.js, written for stiffbench) are compiled in and written inline,
// every SVG is inlined (its ids prefixed per section so that several plots share one page).
//
// The page: a title, a table of run metadata, a table of contents, then per section its
// heading, note, links (e.g. to the section's CSV, Markdown and JSON files), its plots, the
// plotted data as a sortable table in a <details> element, the section's Markdown rendered to
// HTML and its own metadata. The data and Markdown tables are sortable by clicking a header
// (numbers compare by value). The page's scripts record any error in <html data-errors="...">, mark
// the end of their run with data-ready="1", and with the URL hash #selftest sort every numeric
// column and write the outcome to data-selftest (scripts/check-html.sh reads these from the dumped
// DOM).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace stiffbench {

// Text escaped for HTML content and attribute values (& < > " ').
std::string html_escape(std::string_view text);

// The Markdown subset stiffbench writes, as HTML: ATX headings (#...######), paragraphs, pipe
// tables (header, |---| separator with optional :alignment:, rows; rendered with class
// "sortable"), lists (- or * bullets, 1. numbers; one level, indented continuation lines),
// fenced code blocks (```), and inline code spans, **strong**, *emphasis*, [links](url),
// ![images](src) and backslash escapes. Underscores are literal (t_end, e_{k+1}). Everything
// else is escaped text; a link or image address with a scheme other than http, https or
// mailto is dropped (the text stays). An image with a remote address (a scheme, or "//host")
// becomes a link to it: the page loads nothing from outside by itself.
std::string markdown_to_html(std::string_view markdown);

using HtmlMetadata = std::vector<std::pair<std::string, std::string>>;

// The members of a JSON object (e.g. a run's metadata file) as rows: strings as they are, other
// values as compact JSON, cut to `max_chars` characters (with "...").
HtmlMetadata html_metadata(const nlohmann::json& object, std::size_t max_chars = 300);

struct HtmlLink {
  std::string label;
  std::string href;  // relative to the page
};

struct HtmlSection {
  std::string id;        // anchor (letters, digits, '-', '_'; others are replaced)
  std::string title;     // plain text
  std::string note;      // plain text shown under the title (empty: none)
  std::string markdown;  // the section's text (markdown_to_html)
  std::vector<std::filesystem::path> svgs;  // inlined in order; a missing file is skipped
  std::filesystem::path data_csv;           // shown as a table under the plots (empty: none)
  std::size_t data_max_rows = 300;          // rows of data_csv shown (the link has the rest)
  std::vector<HtmlLink> links;
  HtmlMetadata metadata;  // shown in a <details> element
};

// The whole page as text. `intro_markdown` comes after the metadata, before the sections.
std::string html_page(const std::string& title, const HtmlMetadata& metadata,
                      const std::vector<HtmlSection>& sections,
                      const std::string& intro_markdown = "");

// html_page written to `path` (atomically).
void write_html_page(const std::filesystem::path& path, const std::string& title,
                     const HtmlMetadata& metadata, const std::vector<HtmlSection>& sections,
                     const std::string& intro_markdown = "");

// An SVG file's text ready to inline: the XML declaration, doctype and comments before <svg>
// removed and every id="X" (and its references href="#X", xlink:href="#X", url(#X)) renamed
// PREFIX-X. Empty when the file cannot be read or holds no <svg element.
std::string inline_svg(const std::filesystem::path& svg, const std::string& prefix);

}  // namespace stiffbench
