#include "rig/files/toml_guard.hpp"

#include <cstddef>

namespace vitreo::files {

namespace {

bool bare_key_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

}  // namespace

TomlProblem toml_guard(std::string_view t) {
  enum class Mode { Normal, Comment, Basic, Literal, MultiBasic, MultiLiteral };
  Mode mode = Mode::Normal;
  int line = 1, column = 0;
  int depth = 0;                // open [ and { of values (arrays may span lines)
  bool statement_start = true;  // only whitespace so far on this line, outside any value
  auto where = [&](std::string why) { return TomlProblem{line, column, std::move(why)}; };
  std::size_t i = 0;
  if (t.substr(0, 3) == "\xEF\xBB\xBF") i = 3;  // a UTF-8 byte-order mark, which toml++ skips
  for (; i < t.size(); ++i) {
    const char c = t[i];
    ++column;
    if (c == '\n') {
      ++line;
      column = 0;
      if (mode == Mode::Comment || mode == Mode::Basic || mode == Mode::Literal) mode = Mode::Normal;  // a single-line one ends (or is toml++'s error)
      if (mode == Mode::Normal) statement_start = depth == 0;
      continue;
    }
    switch (mode) {
      case Mode::Comment: continue;
      case Mode::Basic:
        if (c == '\\') {
          if (i + 1 < t.size() && t[i + 1] != '\n') ++i, ++column;
        } else if (c == '"') {
          mode = Mode::Normal;
        }
        continue;
      case Mode::Literal:
        if (c == '\'') mode = Mode::Normal;
        continue;
      case Mode::MultiBasic:
        if (c == '\\') {
          if (i + 1 < t.size() && t[i + 1] != '\n') ++i, ++column;
        } else if (t.substr(i, 3) == "\"\"\"") {
          i += 2;
          column += 2;
          mode = Mode::Normal;
        }
        continue;
      case Mode::MultiLiteral:
        if (t.substr(i, 3) == "'''") {
          i += 2;
          column += 2;
          mode = Mode::Normal;
        }
        continue;
      case Mode::Normal: break;
    }
    if (static_cast<unsigned char>(c) >= 0x80) {
      return where("a non-ASCII character outside a string or comment (TOML keys and values outside quotes are ASCII)");
    }
    if (c == ' ' || c == '\t' || c == '\r') continue;
    if (statement_start && c == '[') {
      // A table header: [key] or [[key]]; its key must start like one.
      std::size_t k = i + 1;
      if (k < t.size() && t[k] == '[') ++k;
      while (k < t.size() && (t[k] == ' ' || t[k] == '\t')) ++k;
      if (k >= t.size() || !(bare_key_char(t[k]) || t[k] == '"' || t[k] == '\'')) {
        return where("a table header must start with a key ([name], [[name]], [\"quoted\"])");
      }
      statement_start = false;
      continue;
    }
    statement_start = false;
    switch (c) {
      case '#': mode = Mode::Comment; break;
      case '"':
        if (t.substr(i, 3) == "\"\"\"") {
          mode = Mode::MultiBasic;
          i += 2;
          column += 2;
        } else {
          mode = Mode::Basic;
        }
        break;
      case '\'':
        if (t.substr(i, 3) == "'''") {
          mode = Mode::MultiLiteral;
          i += 2;
          column += 2;
        } else {
          mode = Mode::Literal;
        }
        break;
      case '[':
      case '{': ++depth; break;
      case ']':
      case '}':
        if (depth > 0) --depth;
        break;
      default: break;
    }
  }
  return {};
}

}  // namespace vitreo::files
