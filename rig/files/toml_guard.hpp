#pragma once
// A lexical check of TOML text before toml++ parses it, for the two inputs on which toml++ 3.3.0
// (Debian bookworm's) has undefined behaviour:
//
//  1. A table header whose key does not start like a key — `[&x]`, `[=`, `[[[a]]]`: parse_table_header
//     calls parse_key() on a character that is neither a bare-key character nor a quote, breaking
//     parse_key's precondition (TOML_ASSERT_ASSUME: an assertion failure in a debug build, an
//     optimiser assumption that does not hold in the release library).
//  2. A non-ASCII character where the parser looks for whitespace — `fo µ = 1`, `a = 1µ`, and right
//     after a multi-line string's line-ending backslash (`"""\<newline> µ"""`): the generated
//     is_non_ascii_horizontal_whitespace() reaches TOML_UNREACHABLE (__builtin_unreachable) for
//     code points U+00A1..U+049A and several other ranges its bit table leaves out.
//
// These are refused here with a line and column instead, and so are control characters (TOML has
// none but tab outside escapes; a NUL made toml++ and this scan disagree about where a string is).
// None of it can be valid TOML 1.0: a header's key starts with [A-Za-z0-9_-] or a quote, outside
// strings and comments TOML is ASCII, and a line-ending backslash's whitespace ends at a character
// that starts the string's next content, which is fine to require ASCII of. The
// fuzz target tests/fuzz (toml) runs toml++ header-only with its assertions on and UBSan behind this
// guard. Upstream: marzer/tomlplusplus PR #301 fixes the `[[[` form of (1) after 3.3.0.
#include <string>
#include <string_view>

namespace vitreo::files {

struct TomlProblem {
  int line = 0, column = 0;  // 1-based
  std::string why;           // empty: none
  explicit operator bool() const { return !why.empty(); }
};

// No problem when toml++ may be given `text`; else where and why not.
TomlProblem toml_guard(std::string_view text);

}  // namespace vitreo::files
