// The CLI11 checks of option values shared by the verbs (commands.h), and their notes on stderr.
#include <cmath>
#include <cstdlib>
#include <regex>

#include "app/cli/command_line.h"
#include "mapping/io/camera_config.h"
#include "mapping/sequence/sequence.h"

namespace vdmap::app {

std::string shellQuoted(const std::string& text) {
  static const std::regex plain(R"([A-Za-z0-9_./:=,+#@%-]+)");
  if (std::regex_match(text, plain)) return text;
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

namespace {

// The number `text` holds, all of it (std::invalid_argument otherwise).
double number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') throw std::invalid_argument("expected a number, got '" + text + "'");
  return v;
}

}  // namespace

CLI::Validator cameraPresetCheck() {
  return parsedBy([](const std::string& name) { cameraPreset(name); }, "PRESET");
}

CLI::Validator frameRangeCheck() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          parseFrameRange(text);
          return "";
        } catch (const std::invalid_argument& e) {
          // CLI11 names the option itself ("--frames: ...").
          const std::string what = e.what();
          return what.rfind("--frames ", 0) == 0 ? what.substr(9) : what;
        }
      },
      "A:B");
}

CLI::Validator positiveFiniteCheck() {
  return parsedBy(
      [](const std::string& text) {
        const double v = number(text);
        if (!(v > 0.0 && std::isfinite(v))) throw std::invalid_argument("must be a number > 0, got " + text);
      },
      "> 0");
}

CLI::Validator finiteCheck() {
  return parsedBy(
      [](const std::string& text) {
        if (!std::isfinite(number(text))) throw std::invalid_argument("must be a finite number, got " + text);
      },
      "NUMBER");
}

}  // namespace vdmap::app
