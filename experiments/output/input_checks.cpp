// The checks of input files and text fields (declared in experiments/output/output.hpp), in a file
// of their own so the spec-file parser's fuzz target links them without the rest of the library.
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "core/types.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

std::string read_input_file(const std::filesystem::path& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // follows a symlink
  const std::string p = path.string();
  // The path goes into the run's JSON record and messages: a name that is not UTF-8 (found in a
  // --methods or suite folder; the command line's own arguments are checked when it starts) is
  // refused before anything runs, not after the computation.
  if (!valid_utf8(p))
    throw BadInput(printable(p) + ": the " + what +
                   "'s path is not valid UTF-8; rename the file (bytes shown as \\xNN)");
  if (ec || !fs::exists(st)) throw BadInput(p + ": cannot read the " + what + " (no such file)");
  if (fs::is_directory(st)) throw BadInput(p + ": a folder, not a " + what);
  if (!fs::is_regular_file(st))
    throw BadInput(p + ": not a regular file (a FIFO, device or socket), not a " + what);
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw BadInput(p + ": cannot read the " + what + ": " + ec.message());
  if (size > kMaxInputFileBytes)
    throw BadInput(p + ": " + std::to_string(size) + " bytes, more than a " + what + " may hold (" +
                   std::to_string(kMaxInputFileBytes >> 20) + " MiB)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw BadInput(p + ": cannot read the " + what + ": " + std::strerror(errno));
  // The size read above (+1 to see growth), whatever the file grew to since.
  std::string text(static_cast<std::size_t>(size) + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > size)
    throw BadInput(p + ": changed while it was read (" + std::to_string(size) +
                   " bytes, then more)");
  return text;
}

void require_printable(const std::string& text, const std::string& where, const std::string& key,
                       bool multiline) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if ((c < 0x20 || c == 0x7f) && !(multiline && (c == '\n' || c == '\t' || c == '\r')))
      throw BadInput(where + ": key '" + key + "': holds a control character (code " +
                     std::to_string(c) + " at character " + std::to_string(i + 1) +
                     "); text fields take printable characters" +
                     (multiline ? ", newlines and tabs" : ""));
  }
}

std::string printable(const std::string& text) {
  std::string out;
  const bool utf8 = valid_utf8(text);  // else bytes >= 0x80 are shown as \xNN too
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c < 0x20 || c == 0x7f || (!utf8 && c >= 0x80)) {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

bool valid_utf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    int extra = 0;
    std::uint32_t cp = 0, min = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xe0) == 0xc0) {
      extra = 1, cp = c & 0x1f, min = 0x80;
    } else if ((c & 0xf0) == 0xe0) {
      extra = 2, cp = c & 0x0f, min = 0x800;
    } else if ((c & 0xf8) == 0xf0) {
      extra = 3, cp = c & 0x07, min = 0x10000;
    } else {
      return false;
    }
    if (i + static_cast<std::size_t>(extra) >= text.size()) return false;  // cut short
    for (int k = 1; k <= extra; ++k) {
      const auto d = static_cast<unsigned char>(text[i + static_cast<std::size_t>(k)]);
      if ((d & 0xc0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3f);
    }
    if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return false;
    i += static_cast<std::size_t>(extra) + 1;
  }
  return true;
}

}  // namespace stiffbench
