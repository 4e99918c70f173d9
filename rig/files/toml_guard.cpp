#include "rig/files/toml_guard.hpp"

#include <cstddef>
#include <cstdio>
#include <vector>

namespace vitreo::files {

namespace {

bool bare_key_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}
bool space(char c) { return c == ' ' || c == '\t' || c == '\r'; }
// What may start a value: a string, a number, true/false/inf/nan (and dates, which start with a
// digit), an array or an inline table.
bool value_start(char c) {
  return c == '"' || c == '\'' || (c >= '0' && c <= '9') || c == '+' || c == '-' || c == 't' || c == 'f' || c == 'i' ||
         c == 'n' || c == '[' || c == '{';
}

}  // namespace

TomlProblem toml_guard(std::string_view t) {
  enum class Mode { Normal, Comment, Basic, Literal, MultiBasic, MultiLiteral };
  // What the next significant character must be, where toml++ would otherwise call parse_value()
  // or parse_key() on a character their preconditions exclude.
  enum class Expect { Anything, Value, ValueOrEnd, Key, KeyOrEnd };
  enum class Open { Array, InlineTable };
  Mode mode = Mode::Normal;
  Expect expect = Expect::Key;
  std::vector<Open> open;       // arrays and inline tables of values (arrays may span lines)
  bool statement_start = true;  // only whitespace so far on this line, outside any value
  bool in_value = false;        // inside a bare value (number, date, boolean): toml++ reads it whole
  char previous = '\n';         // last character seen outside strings and comments
  int line = 1, column = 0;
  auto where = [&](std::string why) { return TomlProblem{line, column, std::move(why)}; };
  // After a multi-line basic string's line-ending backslash toml++ skips whitespace with the same
  // is_whitespace() that has the undefined case: the first other character must be ASCII.
  auto after_line_ending_backslash = [&](std::size_t k) -> bool {
    while (k < t.size() && (t[k] == ' ' || t[k] == '\t' || t[k] == '\n' || t[k] == '\r')) ++k;
    return k >= t.size() || static_cast<unsigned char>(t[k]) < 0x80;
  };
  std::size_t i = 0;
  if (t.substr(0, 3) == "\xEF\xBB\xBF") i = 3;  // a UTF-8 byte-order mark, which toml++ skips
  for (; i < t.size(); ++i) {
    const char c = t[i];
    ++column;
    // TOML allows no control character but tab in strings and comments, and none outside (CR only
    // before LF); a NUL in particular left toml++ and this scan disagreeing about what is a string.
    if ((static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      return where(std::string("a control character (") + hex + ")");
    }
    if (c == '\n') {
      ++line;
      column = 0;
      if (mode == Mode::Comment || mode == Mode::Basic || mode == Mode::Literal) mode = Mode::Normal;  // a single-line one ends (or is toml++'s error)
      if (mode == Mode::Normal) {
        in_value = false;  // a newline ends a bare value
        statement_start = open.empty();
        if (statement_start) expect = Expect::Key;
        previous = '\n';
      }
      continue;
    }
    switch (mode) {
      case Mode::Comment: continue;
      case Mode::Basic:
        if (c == '\\') {
          // Escapes are ASCII letters; toml++ tests what follows a backslash with is_whitespace().
          if (i + 1 < t.size() && static_cast<unsigned char>(t[i + 1]) >= 0x80)
            return where("a non-ASCII character after a backslash (not an escape)");
          if (i + 1 < t.size() && t[i + 1] != '\n') ++i, ++column;
        } else if (c == '"') {
          mode = Mode::Normal;
          previous = c;
        }
        continue;
      case Mode::Literal:
        if (c == '\'') {
          mode = Mode::Normal;
          previous = c;
        }
        continue;
      case Mode::MultiBasic:
        if (c == '\\') {
          if (i + 1 < t.size() && static_cast<unsigned char>(t[i + 1]) >= 0x80)
            return where("a non-ASCII character after a backslash (not an escape)");
          if (i + 1 < t.size() && (t[i + 1] == ' ' || t[i + 1] == '\t' || t[i + 1] == '\n' || t[i + 1] == '\r') &&
              !after_line_ending_backslash(i + 1))
            return where("a non-ASCII character right after a line-ending backslash");
          if (i + 1 < t.size() && t[i + 1] != '\n') ++i, ++column;
        } else if (t.substr(i, 3) == "\"\"\"") {
          // Up to two more quotes right before the closing three belong to the string ("""a"""").
          std::size_t q = 3;
          while (q < 5 && i + q < t.size() && t[i + q] == '"') ++q;
          i += q - 1;
          column += static_cast<int>(q) - 1;
          mode = Mode::Normal;
          previous = '"';
        }
        continue;
      case Mode::MultiLiteral:
        if (t.substr(i, 3) == "'''") {
          std::size_t q = 3;
          while (q < 5 && i + q < t.size() && t[i + q] == '\'') ++q;
          i += q - 1;
          column += static_cast<int>(q) - 1;
          mode = Mode::Normal;
          previous = '\'';
        }
        continue;
      case Mode::Normal: break;
    }
    if (static_cast<unsigned char>(c) >= 0x80) {
      return where("a non-ASCII character outside a string or comment (TOML keys and values outside quotes are ASCII)");
    }
    if (in_value) {
      // toml++ takes everything up to a value terminator as the token ('=' and '[' included) and
      // judges it after; a quote in it is where this scan and toml++ would part ways.
      if (c == '"' || c == '\'') return where("a quote in the middle of a bare value");
      if (!(space(c) || c == ',' || c == ']' || c == '}' || c == '#')) {
        previous = c;
        continue;
      }
      in_value = false;
    }
    if (space(c)) {
      previous = c;
      continue;
    }
    if (c == '#') {
      mode = Mode::Comment;
      continue;
    }
    if (statement_start && c == '[') {
      // A table header: [key] or [[key]]; its key must start like one.
      std::size_t k = i + 1;
      if (k < t.size() && t[k] == '[') {
        ++k;
        ++i;  // [[: an array of tables, not an array
        ++column;
      }
      while (k < t.size() && (t[k] == ' ' || t[k] == '\t')) ++k;
      if (k >= t.size() || !(bare_key_char(t[k]) || t[k] == '"' || t[k] == '\'')) {
        return where("a table header must start with a key ([name], [[name]], [\"quoted\"])");
      }
      statement_start = false;
      expect = Expect::Key;
      previous = '[';
      continue;
    }
    statement_start = false;
    // Where a key or a value must begin, only what can begin one.
    switch (expect) {
      case Expect::Value:
        if (!value_start(c)) return where(std::string("a value was expected, not '") + c + "'");
        in_value = c != '"' && c != '\'' && c != '[' && c != '{';
        break;
      case Expect::ValueOrEnd:
        if (!value_start(c) && c != ']') return where(std::string("a value or ']' was expected, not '") + c + "'");
        in_value = c != '"' && c != '\'' && c != '[' && c != '{' && c != ']';
        break;
      case Expect::Key:
        if (!bare_key_char(c) && c != '"' && c != '\'') return where(std::string("a key was expected, not '") + c + "'");
        break;
      case Expect::KeyOrEnd:
        if (!bare_key_char(c) && c != '"' && c != '\'' && c != '}')
          return where(std::string("a key or '}' was expected, not '") + c + "'");
        break;
      case Expect::Anything: break;
    }
    expect = Expect::Anything;
    if (in_value) {
      previous = c;
      continue;
    }
    switch (c) {
      case '"':
      case '\'':
        // A quote opens a string only where a key or a value begins; inside a bare token (0'x) toml++
        // reads on through it, so this scan must not take it for a string.
        if (!(space(previous) || previous == '\n' || previous == '=' || previous == '[' || previous == '{' ||
              previous == ',' || previous == '.')) {
          return where("a quote in the middle of a bare key or value");
        }
        if (t.substr(i, 3) == std::string(3, c)) {
          mode = c == '"' ? Mode::MultiBasic : Mode::MultiLiteral;
          i += 2;
          column += 2;
        } else {
          mode = c == '"' ? Mode::Basic : Mode::Literal;
        }
        continue;
      case '=': expect = Expect::Value; break;
      case '[':
        open.push_back(Open::Array);
        expect = Expect::ValueOrEnd;
        break;
      case '{':
        open.push_back(Open::InlineTable);
        expect = Expect::KeyOrEnd;
        break;
      case ']':
      case '}':
        if (!open.empty()) open.pop_back();
        break;
      case ',':
        if (!open.empty()) expect = open.back() == Open::Array ? Expect::ValueOrEnd : Expect::Key;
        break;
      case '.': expect = Expect::Key; break;  // a dotted key's next part
      default: break;
    }
    previous = c;
  }
  return {};
}

}  // namespace vitreo::files
