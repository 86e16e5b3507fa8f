// One self-contained HTML page (experiments/output/html.hpp): a small Markdown renderer, SVG
// inlining and the page writer.
#include "experiments/output/html.hpp"

#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "experiments/output/csv.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

// experiments/output/html/* (page.css, errors.js, page.js), compiled in (cmake/embed_files.cmake).
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_html_assets();

namespace fs = std::filesystem;

namespace {

std::string_view asset(std::string_view name) {
  for (const auto& [file, text] : embedded_html_assets())
    if (file == name) return text;
  throw std::logic_error("no embedded HTML asset " + std::string(name));
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool is_punct(char c) { return std::ispunct(static_cast<unsigned char>(c)) != 0; }
bool is_space(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

// A link or image address, or "" when its scheme is not http, https or mailto (a relative
// address has no scheme: no ':' before the first '/', '?' or '#').
std::string safe_url(std::string_view url) {
  url = trim(url);
  const std::size_t colon = url.find(':');
  const std::size_t stop = url.find_first_of("/?#");
  if (colon != std::string_view::npos && (stop == std::string_view::npos || colon < stop)) {
    std::string scheme(url.substr(0, colon));
    for (auto& c : scheme) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (scheme != "http" && scheme != "https" && scheme != "mailto") return "";
  }
  return std::string(url);
}

// An address the browser would fetch from another host: with a scheme, or scheme-relative
// ("//host/...").
bool is_remote(std::string_view url) {
  url = trim(url);
  if (url.substr(0, 2) == "//") return true;
  const std::size_t colon = url.find(':');
  const std::size_t stop = url.find_first_of("/?#");
  return colon != std::string_view::npos && (stop == std::string_view::npos || colon < stop);
}

std::string render_inline(std::string_view s);

// [text](url) starting at s[i] == '['; on success sets text, url and the index after ')'.
bool parse_link(std::string_view s, std::size_t i, std::string_view& text, std::string_view& url,
                std::size_t& end) {
  int depth = 0;
  std::size_t j = i;
  for (; j < s.size(); ++j) {
    if (s[j] == '\\') {
      ++j;
      continue;
    }
    if (s[j] == '[') ++depth;
    if (s[j] == ']' && --depth == 0) break;
  }
  if (j >= s.size() || j + 1 >= s.size() || s[j + 1] != '(') return false;
  const std::size_t close = s.find(')', j + 2);
  if (close == std::string_view::npos) return false;
  text = s.substr(i + 1, j - i - 1);
  url = s.substr(j + 2, close - j - 2);
  end = close + 1;
  return true;
}

// `code` starting at s[i] == '`': the closing run of as many backticks; appends <code>.
bool code_span(std::string_view s, std::size_t& i, std::string& out) {
  std::size_t n = 0;
  while (i + n < s.size() && s[i + n] == '`') ++n;
  const std::string fence(n, '`');
  std::size_t close = s.find(fence, i + n);
  while (close != std::string_view::npos && close + n < s.size() && s[close + n] == '`')
    close = s.find(fence, close + n + 1);
  if (close == std::string_view::npos) {
    out += fence;
    i += n;
    return true;
  }
  std::string_view body = s.substr(i + n, close - i - n);
  if (body.size() >= 2 && body.front() == ' ' && body.back() == ' ')
    body = body.substr(1, body.size() - 2);
  out += "<code>" + html_escape(body) + "</code>";
  i = close + n;
  return true;
}

// **strong** or *emphasis* starting at s[i] == '*': the opening run is followed by a non-space
// and the closing one preceded by a non-space; appends the element.
bool emphasis(std::string_view s, std::size_t& i, std::string& out) {
  const std::size_t n = (i + 1 < s.size() && s[i + 1] == '*') ? 2 : 1;
  if (i + n >= s.size() || is_space(s[i + n])) return false;
  const std::string mark(n, '*');
  for (std::size_t close = s.find(mark, i + n + 1); close != std::string_view::npos;
       close = s.find(mark, close + 1)) {
    const bool longer = n == 1 && close + 1 < s.size() && s[close + 1] == '*';
    if (is_space(s[close - 1]) || longer) {
      if (longer) ++close;
      continue;
    }
    const char* tag = n == 2 ? "strong" : "em";
    out += std::string("<") + tag + ">" + render_inline(s.substr(i + n, close - i - n)) + "</" +
           tag + ">";
    i = close + n;
    return true;
  }
  return false;
}

std::string render_inline(std::string_view s) {
  std::string out;
  std::size_t i = 0;
  while (i < s.size()) {
    const char c = s[i];
    std::string_view text, url;
    std::size_t end = 0;
    if (c == '\\' && i + 1 < s.size() && is_punct(s[i + 1])) {
      out += html_escape(s.substr(i + 1, 1));
      i += 2;
    } else if (c == '`') {
      code_span(s, i, out);
    } else if (c == '!' && i + 1 < s.size() && s[i + 1] == '[' &&
               parse_link(s, i + 1, text, url, end)) {
      // The page is self-contained: it loads no image from elsewhere. A remote image becomes a
      // link to it (followed only when clicked); a relative one (beside the page) is shown.
      const std::string src = safe_url(url);
      if (src.empty())
        out += html_escape(text);
      else if (is_remote(src))
        out += "<a href=\"" + html_escape(src) + "\">" + html_escape(text) + " (remote image)</a>";
      else
        out += "<img src=\"" + html_escape(src) + "\" alt=\"" + html_escape(text) + "\">";
      i = end;
    } else if (c == '[' && parse_link(s, i, text, url, end)) {
      const std::string href = safe_url(url);
      out += href.empty() ? render_inline(text)
                          : "<a href=\"" + html_escape(href) + "\">" + render_inline(text) + "</a>";
      i = end;
    } else if (c == '*' && emphasis(s, i, out)) {
    } else {
      out += html_escape(s.substr(i, 1));
      ++i;
    }
  }
  return out;
}

// The cells of a pipe-table line: '|' separates except escaped (\|) or inside a code span;
// one leading and one trailing '|' are dropped.
std::vector<std::string> table_cells(std::string_view line) {
  line = trim(line);
  if (!line.empty() && line.front() == '|') line.remove_prefix(1);
  std::vector<std::string> cells;
  std::string cell;
  bool in_code = false, ended_with_pipe = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    ended_with_pipe = false;
    if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
      cell += in_code ? "|" : "\\|";
      ++i;
    } else if (line[i] == '`') {
      in_code = !in_code;
      cell += '`';
    } else if (line[i] == '|' && !in_code) {
      cells.emplace_back(trim(cell));
      cell.clear();
      ended_with_pipe = true;
    } else {
      cell += line[i];
    }
  }
  if (!ended_with_pipe) cells.emplace_back(trim(cell));
  return cells;
}

// A table's separator line (|---|:---:|): the alignment of each column ("" left by default,
// "left", "center", "right"); empty when the line is not one.
std::vector<std::string> table_alignment(std::string_view line) {
  if (line.find('-') == std::string_view::npos || line.find('|') == std::string_view::npos)
    return {};
  std::vector<std::string> align;
  for (const auto& cell : table_cells(line)) {
    std::string_view c = cell;
    if (c.empty()) return {};
    const bool left = c.front() == ':', right = c.back() == ':';
    for (std::size_t k = left ? 1 : 0; k < c.size() - (right ? 1 : 0); ++k)
      if (c[k] != '-') return {};
    align.push_back(left && right ? "center" : right ? "right" : left ? "left" : "");
  }
  return align;
}

std::string table_html(const std::vector<std::string>& header,
                       const std::vector<std::vector<std::string>>& rows,
                       const std::vector<std::string>& align, bool markdown_cells) {
  auto style = [&](std::size_t k) {
    return k < align.size() && !align[k].empty() ? " style=\"text-align:" + align[k] + "\"" : "";
  };
  auto cell = [&](const std::string& s) {
    return markdown_cells ? render_inline(s) : html_escape(s);
  };
  std::string out = "<div class=\"table-wrap\"><table class=\"sortable\"><thead><tr>";
  for (std::size_t k = 0; k < header.size(); ++k)
    out += "<th" + style(k) + ">" + cell(header[k]) + "</th>";
  out += "</tr></thead><tbody>\n";
  for (const auto& row : rows) {
    out += "<tr>";
    for (std::size_t k = 0; k < header.size(); ++k)
      out += "<td" + style(k) + ">" + (k < row.size() ? cell(row[k]) : "") + "</td>";
    out += "</tr>\n";
  }
  return out + "</tbody></table></div>\n";
}

// The marker of a list item ("- ", "* ", "+ ", "1. ", "1) ") after up to three spaces: its
// length including the space, 0 when the line is not an item; `ordered` tells which kind.
std::size_t list_marker(std::string_view line, bool& ordered) {
  std::size_t i = 0;
  while (i < line.size() && i < 3 && line[i] == ' ') ++i;
  if (i < line.size() && (line[i] == '-' || line[i] == '*' || line[i] == '+')) {
    ordered = false;
    return i + 1 < line.size() && line[i + 1] == ' ' ? i + 2 : 0;
  }
  std::size_t d = i;
  while (d < line.size() && std::isdigit(static_cast<unsigned char>(line[d]))) ++d;
  if (d == i || d - i > 9 || d + 1 >= line.size() || (line[d] != '.' && line[d] != ')') ||
      line[d + 1] != ' ')
    return 0;
  ordered = true;
  return d + 2;
}

std::size_t heading_level(std::string_view line) {
  std::size_t n = 0;
  while (n < line.size() && line[n] == '#') ++n;
  return n >= 1 && n <= 6 && (n == line.size() || line[n] == ' ') ? n : 0;
}

bool is_fence(std::string_view line) { return trim(line).substr(0, 3) == "```"; }

bool starts_table(const std::vector<std::string_view>& lines, std::size_t i) {
  return lines[i].find('|') != std::string_view::npos && i + 1 < lines.size() &&
         table_alignment(lines[i + 1]).size() == table_cells(lines[i]).size();
}

bool starts_block(const std::vector<std::string_view>& lines, std::size_t i) {
  bool ordered = false;
  return heading_level(lines[i]) > 0 || is_fence(lines[i]) || list_marker(lines[i], ordered) > 0 ||
         starts_table(lines, i);
}

// A list starting at lines[i]: its items (with their continuation lines) until a blank line
// not followed by another item of the same kind, or a line starting another block.
std::string list_html(const std::vector<std::string_view>& lines, std::size_t& i) {
  bool ordered = false;
  list_marker(lines[i], ordered);
  std::vector<std::string> items;
  while (i < lines.size()) {
    bool kind = false;
    const std::size_t m = list_marker(lines[i], kind);
    if (trim(lines[i]).empty()) {
      bool next_kind = false;
      if (i + 1 < lines.size() && list_marker(lines[i + 1], next_kind) > 0 &&
          next_kind == ordered) {
        ++i;
        continue;
      }
      break;
    }
    if (m > 0) {
      if (kind != ordered) break;
      items.emplace_back(trim(lines[i].substr(m)));
    } else if (starts_block(lines, i)) {
      break;
    } else {
      items.back() += "\n" + std::string(trim(lines[i]));
    }
    ++i;
  }
  std::string out = ordered ? "<ol>\n" : "<ul>\n";
  for (const auto& item : items) out += "<li>" + render_inline(item) + "</li>\n";
  return out + (ordered ? "</ol>\n" : "</ul>\n");
}

std::string table_block(const std::vector<std::string_view>& lines, std::size_t& i) {
  const std::vector<std::string> header = table_cells(lines[i]);
  const std::vector<std::string> align = table_alignment(lines[i + 1]);
  std::vector<std::vector<std::string>> rows;
  for (i += 2;
       i < lines.size() && !trim(lines[i]).empty() && lines[i].find('|') != std::string_view::npos;
       ++i)
    rows.push_back(table_cells(lines[i]));
  return table_html(header, rows, align, true);
}

std::string csv_table(const fs::path& csv, std::size_t max_rows, std::size_t& total) {
  std::ifstream in(csv);
  std::string line;
  total = 0;
  if (!std::getline(in, line)) return "";
  const std::vector<std::string> header = parse_csv_line(line);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (++total <= max_rows) rows.push_back(parse_csv_line(line));
  }
  return table_html(header, rows, {}, false);
}

std::string anchor(std::string_view id) {
  std::string out = "sec-";
  for (char c : id)
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '-';
  return out;
}

std::string metadata_table(const HtmlMetadata& metadata) {
  std::string out = "<table class=\"meta\"><tbody>\n";
  for (const auto& [key, value] : metadata)
    out += "<tr><th scope=\"row\">" + html_escape(key) + "</th><td>" + html_escape(value) +
           "</td></tr>\n";
  return out + "</tbody></table>\n";
}

std::string section_html(const HtmlSection& s, std::size_t index) {
  const std::string id = anchor(s.id);
  std::ostringstream out;
  out << "<section class=\"report-section\" id=\"" << html_escape(id) << "\">\n<h2>"
      << html_escape(s.title) << "</h2>\n";
  if (!s.note.empty()) out << "<p class=\"note\">" << html_escape(s.note) << "</p>\n";
  if (!s.links.empty()) {
    out << "<p class=\"links\">";
    for (std::size_t k = 0; k < s.links.size(); ++k)
      out << (k ? " · " : "") << "<a href=\"" << html_escape(s.links[k].href) << "\">"
          << html_escape(s.links[k].label) << "</a>";
    out << "</p>\n";
  }
  for (std::size_t k = 0; k < s.svgs.size(); ++k) {
    const std::string svg =
        inline_svg(s.svgs[k], "s" + std::to_string(index) + "p" + std::to_string(k));
    if (svg.empty()) continue;
    out << "<figure class=\"plot\">" << svg << "<figcaption>" << html_escape(s.title)
        << (s.data_csv.empty() ? " (hover a curve for its name)"
                               : " (hover a curve for its name; the values are in the table below)")
        << "</figcaption></figure>\n";
  }
  std::size_t total = 0;
  const std::string data = s.data_csv.empty() ? "" : csv_table(s.data_csv, s.data_max_rows, total);
  if (!data.empty()) {
    const std::string name = html_escape(s.data_csv.filename().string());
    out << "<details class=\"data\"><summary>Plotted data: " << name << " ("
        << (total > s.data_max_rows ? "first " + std::to_string(s.data_max_rows) + " of " : "")
        << total << " rows)</summary>\n"
        << data << "</details>\n";
  }
  out << "<div class=\"md\">\n" << markdown_to_html(s.markdown) << "</div>\n";
  if (!s.metadata.empty())
    out << "<details class=\"meta\"><summary>Run metadata</summary>\n"
        << metadata_table(s.metadata) << "</details>\n";
  out << "</section>\n";
  return out.str();
}

}  // namespace

std::string html_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

HtmlMetadata html_metadata(const nlohmann::json& object, std::size_t max_chars) {
  HtmlMetadata rows;
  if (!object.is_object()) return rows;
  for (const auto& [key, value] : object.items()) {
    std::string text = value.is_string()
                           ? value.get<std::string>()
                           : value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (text.size() > max_chars) {
      std::size_t cut = max_chars;  // not inside a UTF-8 sequence
      while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
      text = text.substr(0, cut) + "...";
    }
    rows.emplace_back(key, text);
  }
  return rows;
}

std::string markdown_to_html(std::string_view markdown) {
  std::vector<std::string_view> lines;
  for (std::size_t start = 0; start <= markdown.size();) {
    std::size_t nl = markdown.find('\n', start);
    if (nl == std::string_view::npos) nl = markdown.size();
    std::string_view line = markdown.substr(start, nl - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = nl + 1;
  }
  std::string out;
  std::size_t i = 0;
  bool ordered = false;
  while (i < lines.size()) {
    const std::string_view line = lines[i];
    if (trim(line).empty()) {
      ++i;
    } else if (const std::size_t level = heading_level(line)) {
      std::string_view text = trim(line.substr(level));
      while (!text.empty() && text.back() == '#') text.remove_suffix(1);
      const std::string h = "h" + std::to_string(level);
      out += "<" + h + ">" + render_inline(trim(text)) + "</" + h + ">\n";
      ++i;
    } else if (is_fence(line)) {
      std::string code;
      for (++i; i < lines.size() && !is_fence(lines[i]); ++i) code += std::string(lines[i]) + "\n";
      out += "<pre><code>" + html_escape(code) + "</code></pre>\n";
      ++i;
    } else if (starts_table(lines, i)) {
      out += table_block(lines, i);
    } else if (list_marker(line, ordered) > 0) {
      out += list_html(lines, i);
    } else {
      std::string text(trim(line));
      for (++i; i < lines.size() && !trim(lines[i]).empty() && !starts_block(lines, i); ++i)
        text += "\n" + std::string(trim(lines[i]));
      out += "<p>" + render_inline(text) + "</p>\n";
    }
  }
  return out;
}

std::string inline_svg(const fs::path& svg, const std::string& prefix) {
  std::ifstream in(svg, std::ios::binary);
  if (!in) return "";
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const std::size_t begin = text.find("<svg");
  if (begin == std::string::npos) return "";
  const std::size_t close = text.rfind("</svg>");
  const std::string body = text.substr(
      begin, close == std::string::npos || close < begin ? std::string::npos : close + 6 - begin);
  std::string out;
  out.reserve(body.size() + body.size() / 20);
  for (std::size_t i = 0; i < body.size(); ++i) {
    out += body[i];
    const std::string_view rest = std::string_view(body).substr(i + 1);
    if (is_space(body[i]) && rest.substr(0, 4) == "id=\"") {
      out += "id=\"" + prefix + "-";
      i += 4;
    } else if (rest.substr(0, 7) == "href=\"#") {
      out += "href=\"#" + prefix + "-";
      i += 7;
    } else if (rest.substr(0, 5) == "url(#") {
      out += "url(#" + prefix + "-";
      i += 5;
    }
  }
  return out;
}

std::string html_page(const std::string& title, const HtmlMetadata& metadata,
                      const std::vector<HtmlSection>& sections, const std::string& intro_markdown) {
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      << "<meta name=\"generator\" content=\"stiffbench\">\n<title>" << html_escape(title)
      << "</title>\n<script>\n"
      << asset("errors.js") << "</script>\n<style>\n"
      << asset("page.css") << "</style>\n</head>\n<body>\n<header class=\"page\">\n<h1>"
      << html_escape(title) << "</h1>\n"
      << metadata_table(metadata);
  if (!sections.empty()) {
    out << "<nav class=\"toc\"><ol>\n";
    for (const auto& s : sections)
      out << "<li><a href=\"#" << html_escape(anchor(s.id)) << "\">" << html_escape(s.title)
          << "</a></li>\n";
    out << "</ol></nav>\n";
  }
  out << "</header>\n<main>\n" << markdown_to_html(intro_markdown);
  for (std::size_t k = 0; k < sections.size(); ++k) out << section_html(sections[k], k);
  out << "</main>\n<script>\n" << asset("page.js") << "</script>\n</body>\n</html>\n";
  return out.str();
}

void write_html_page(const fs::path& path, const std::string& title, const HtmlMetadata& metadata,
                     const std::vector<HtmlSection>& sections, const std::string& intro_markdown) {
  write_file_atomic(path, html_page(title, metadata, sections, intro_markdown));
}

}  // namespace stiffbench
