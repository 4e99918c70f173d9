#pragma once
#include <stdexcept>
#include <string>
#include <utility>

namespace vitreo::core {

// Thrown when a model is built or configured with invalid data (non-finite numbers, values out of
// their documented range, broken references). Building happens before the real-time loop, so an
// exception with a precise message is the clearest way to refuse it.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Result of an operation the rig may call while the simulation runs. It never throws: a bad value
// from a device must be refused without unwinding through the physics thread.
class [[nodiscard]] Status {
 public:
  static Status ok() { return Status{}; }
  static Status error(std::string message) { return Status{std::move(message)}; }

  bool is_ok() const { return message_.empty(); }
  explicit operator bool() const { return is_ok(); }
  const std::string& message() const { return message_; }

 private:
  Status() = default;
  explicit Status(std::string message) : message_(std::move(message)) {
    if (message_.empty()) message_ = "unspecified error";
  }
  std::string message_;
};

}  // namespace vitreo::core
