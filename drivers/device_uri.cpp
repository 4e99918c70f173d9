#include "drivers/device_uri.hpp"

#include <charconv>
#include <cstdio>
#include <vector>

namespace vitreo::drivers {

const char* to_string(Transport t) {
  switch (t) {
    case Transport::serial: return "serial";
    case Transport::can: return "can";
    case Transport::usb: return "usb";
  }
  return "?";
}

Transport DeviceUri::transport() const {
  switch (scheme) {
    case Scheme::serial: return Transport::serial;
    case Scheme::can: return Transport::can;
    case Scheme::usb: return Transport::usb;
    case Scheme::sim: return sim_transport;
  }
  return Transport::serial;
}

int default_can_node(std::string_view kind) {
  if (kind == "tracker") return 5;
  if (kind == "pedals") return 17;
  if (kind == "eyeball") return 33;
  return 0;
}

namespace {

bool parse_int(std::string_view s, int base, long& out) {
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out, base);
  return r.ec == std::errc{} && r.ptr == s.data() + s.size();
}

struct Query {
  std::vector<std::pair<std::string_view, std::string_view>> items;
};

// "a=1&b=2" → pairs; false for an item without '=' or a repeated key.
bool split_query(std::string_view q, Query& out, std::string* error) {
  while (!q.empty()) {
    const auto amp = q.find('&');
    const std::string_view item = q.substr(0, amp);
    q = amp == std::string_view::npos ? std::string_view{} : q.substr(amp + 1);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos || eq == 0) {
      if (error) *error = "'" + std::string(item) + "' is not key=value";
      return false;
    }
    const std::string_view key = item.substr(0, eq);
    for (const auto& [k, v] : out.items) {
      if (k == key) {
        if (error) *error = "'" + std::string(key) + "' given twice";
        return false;
      }
    }
    out.items.emplace_back(key, item.substr(eq + 1));
  }
  return true;
}

}  // namespace

bool parse_device_uri(std::string_view text, DeviceUri& out, std::string* error) {
  auto fail = [&](const std::string& why) {
    if (error) *error = "device URI '" + std::string(text) + "': " + why;
    return false;
  };
  const auto colon = text.find(':');
  if (colon == std::string_view::npos) return fail("no scheme (serial:, can:, usb: or sim:)");
  const std::string_view scheme = text.substr(0, colon);
  std::string_view rest = text.substr(colon + 1);
  std::string_view query;
  if (const auto q = rest.find('?'); q != std::string_view::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  Query params;
  std::string why;
  if (!split_query(query, params, &why)) return fail(why);
  DeviceUri u;
  // Each scheme takes the keys it knows; anything else is a typo worth reporting.
  auto take_int = [&](std::string_view key, long lo, long hi, int& target, bool& seen) -> bool {
    for (const auto& [k, v] : params.items) {
      if (k != key) continue;
      long n = 0;
      if (!parse_int(v, 10, n) || n < lo || n > hi) {
        why = std::string(key) + "=" + std::string(v) + " is not an integer in [" + std::to_string(lo) + ", " +
              std::to_string(hi) + "]";
        return false;
      }
      target = static_cast<int>(n);
      seen = true;
    }
    return true;
  };
  auto only_keys = [&](std::initializer_list<std::string_view> allowed) -> bool {
    for (const auto& [k, v] : params.items) {
      bool ok = false;
      for (auto a : allowed) ok = ok || a == k;
      if (!ok) {
        why = "unknown parameter '" + std::string(k) + "'";
        return false;
      }
    }
    return true;
  };
  auto text_param = [&](std::string_view key) -> std::string {
    for (const auto& [k, v] : params.items) {
      if (k == key) return std::string(v);
    }
    return {};
  };
  bool seen = false;
  int fd = 0;

  if (scheme == "serial") {
    u.scheme = DeviceUri::Scheme::serial;
    if (rest.empty()) return fail("no device path (serial:/dev/ttyACM0)");
    u.path = std::string(rest);
    if (!only_keys({"baud"}) || !take_int("baud", 9600, 3'000'000, u.baud, seen)) return fail(why);
  } else if (scheme == "can") {
    u.scheme = DeviceUri::Scheme::can;
    if (rest.empty() || rest.size() > 15) return fail("no CAN interface name (can:can0?node=5)");
    u.interface = std::string(rest);
    if (!only_keys({"node", "fd"}) || !take_int("node", 1, 127, u.node, seen)) return fail(why);
    if (!seen) return fail("no node id (can:" + u.interface + "?node=N, N in 1..127)");
    bool fd_seen = false;
    if (!take_int("fd", 0, 1, fd, fd_seen)) return fail(why);
    u.fd = fd != 0;
  } else if (scheme == "usb") {
    u.scheme = DeviceUri::Scheme::usb;
    if (!only_keys({})) return fail(why);
    std::string_view ids = rest;
    if (const auto slash = rest.find('/'); slash != std::string_view::npos) {
      ids = rest.substr(0, slash);
      u.serial_number = std::string(rest.substr(slash + 1));
      if (u.serial_number.empty()) return fail("empty serial number after '/'");
    }
    const auto c = ids.find(':');
    long vid = 0, pid = 0;
    if (c == std::string_view::npos || c != 4 || ids.size() != 9 || !parse_int(ids.substr(0, 4), 16, vid) ||
        !parse_int(ids.substr(5), 16, pid)) {
      return fail("expected usb:VVVV:PPPP[/SERIAL] with hexadecimal vendor and product ids");
    }
    u.vid = static_cast<std::uint16_t>(vid);
    u.pid = static_cast<std::uint16_t>(pid);
  } else if (scheme == "sim") {
    u.scheme = DeviceUri::Scheme::sim;
    if (rest != "tracker" && rest != "pedals" && rest != "eyeball") return fail("sim: kind must be tracker, pedals or eyeball");
    u.sim_kind = std::string(rest);
    if (!only_keys({"transport", "link", "if", "node", "fd"})) return fail(why);
    const std::string transport = text_param("transport");
    if (transport == "pty" || transport.empty()) {
      u.sim_transport = Transport::serial;
      u.path = text_param("link");
    } else if (transport == "usb") {
      u.sim_transport = Transport::usb;
    } else if (transport == "can") {
      u.sim_transport = Transport::can;
      u.interface = text_param("if");
      if (u.interface.empty()) u.interface = "vcan0";
      u.node = default_can_node(u.sim_kind);
      bool fd_seen = false;
      if (!take_int("node", 1, 127, u.node, seen) || !take_int("fd", 0, 1, fd, fd_seen)) return fail(why);
      u.fd = fd != 0;
    } else {
      return fail("transport=" + transport + ": must be pty, usb or can");
    }
    // parameters of another transport are mistakes, not options to ignore
    if (u.sim_transport != Transport::serial && !text_param("link").empty()) return fail("link= is for transport=pty");
    if (u.sim_transport != Transport::can && (!text_param("if").empty() || !text_param("node").empty() || !text_param("fd").empty()))
      return fail("if=, node= and fd= are for transport=can");
  } else {
    return fail("unknown scheme '" + std::string(scheme) + "' (serial:, can:, usb: or sim:)");
  }
  out = std::move(u);
  return true;
}

std::string to_string(const DeviceUri& u) {
  switch (u.scheme) {
    case DeviceUri::Scheme::serial:
      return "serial:" + u.path + (u.baud != 921600 ? "?baud=" + std::to_string(u.baud) : "");
    case DeviceUri::Scheme::can:
      return "can:" + u.interface + "?node=" + std::to_string(u.node) + (u.fd ? "&fd=1" : "");
    case DeviceUri::Scheme::usb: {
      char b[16];
      std::snprintf(b, sizeof b, "%04x:%04x", u.vid, u.pid);
      return std::string("usb:") + b + (u.serial_number.empty() ? "" : "/" + u.serial_number);
    }
    case DeviceUri::Scheme::sim: {
      std::string s = "sim:" + u.sim_kind + "?transport=";
      switch (u.sim_transport) {
        case Transport::serial: return s + "pty" + (u.path.empty() ? "" : "&link=" + u.path);
        case Transport::usb: return s + "usb";
        case Transport::can:
          return s + "can&if=" + u.interface + "&node=" + std::to_string(u.node) + (u.fd ? "&fd=1" : "");
      }
    }
  }
  return {};
}

}  // namespace vitreo::drivers
