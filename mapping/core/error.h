#pragma once
#include <stdexcept>
#include <string>

namespace vdmap {

/// An expected failure at an input boundary (a missing file, a malformed line, a bad image).
/// what() is one line: "<file>[:<line>]: <what was wrong / what was expected>".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& message)
      : std::runtime_error(file + ": " + message) {}
  InputError(const std::string& file, int line, const std::string& message)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + message) {}
};

}  // namespace vdmap
