#pragma once
// A small JSON writer whose output depends on nothing but the values given: numbers in their
// shortest round-trip form (std::to_chars), keys in the order written, no locale, no clock — so one
// session's report is the same bytes every time it is made. Non-finite numbers are written as null.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace vitreo::report {

class JsonWriter {
 public:
  JsonWriter& begin_object() { value_prefix(); out_ += '{'; first_.push_back(true); return *this; }
  JsonWriter& end_object() { first_.pop_back(); newline(); out_ += '}'; return *this; }
  JsonWriter& begin_array() { value_prefix(); out_ += '['; first_.push_back(true); return *this; }
  JsonWriter& end_array() { first_.pop_back(); out_ += ']'; return *this; }
  JsonWriter& key(std::string_view k) {
    if (!first_.back()) out_ += ',';
    first_.back() = false;
    newline();
    string_literal(k);
    out_ += ':';
    after_key_ = true;
    return *this;
  }
  JsonWriter& value(double v) {
    value_prefix();
    if (!std::isfinite(v)) {
      out_ += "null";
      return *this;
    }
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    out_.append(buf, r.ptr);
    return *this;
  }
  JsonWriter& value(std::int64_t v) { value_prefix(); out_ += std::to_string(v); return *this; }
  JsonWriter& value(int v) { return value(static_cast<std::int64_t>(v)); }
  JsonWriter& value(bool v) { value_prefix(); out_ += v ? "true" : "false"; return *this; }
  JsonWriter& value(std::string_view s) { value_prefix(); string_literal(s); return *this; }
  JsonWriter& value(const char* s) { return value(std::string_view(s)); }
  JsonWriter& value(std::nullptr_t) { value_prefix(); out_ += "null"; return *this; }
  // A measured number with its unit: {"value": v, "unit": u}.
  JsonWriter& measure(double v, std::string_view unit) {  // on one line
    value_prefix();
    out_ += "{\"value\":";
    after_key_ = true;
    value(v);
    out_ += ",\"unit\":";
    string_literal(unit);
    out_ += '}';
    return *this;
  }
  JsonWriter& field(std::string_view k, double v, std::string_view unit) { return key(k).measure(v, unit); }
  std::string take() { return std::move(out_); }
  const std::string& text() const { return out_; }

 private:
  void value_prefix() {
    if (after_key_) {
      after_key_ = false;
      return;
    }
    if (first_.empty()) return;
    if (!first_.back()) out_ += ',';
    first_.back() = false;
  }
  // Objects one key a line (a reader can diff two reports); arrays stay on one line.
  void newline() {
    out_ += '\n';
    out_.append(2 * first_.size(), ' ');
  }
  void string_literal(std::string_view s) {
    out_ += '"';
    for (const char c : s) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '"') out_ += "\\\"";
      else if (c == '\\') out_ += "\\\\";
      else if (c == '<') out_ += "\\u003c";  // never closes a <script> it is embedded in
      else if (u < 0x20) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\u%04x", u);
        out_ += buf;
      } else out_ += c;
    }
    out_ += '"';
  }

  std::string out_;
  std::vector<bool> first_;
  bool after_key_ = false;
};

}  // namespace vitreo::report
