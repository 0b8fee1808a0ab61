// The CLI11 checks of option values shared by the verbs (commands.h), and their notes on stderr.
#include <cmath>
#include <cstdlib>
#include <regex>
#include <sstream>

#include "app/cli/command_line.h"
#include "mapping/core/message_text.h"
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

std::string WrappingFormatter::make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const {
  std::istringstream lines(CLI::Formatter::make_help(app, std::move(name), mode));
  std::string out;
  for (std::string line; std::getline(lines, line);) {
    if (line.size() > width_) {
      // An option's line goes on under its description's column; any other under its own start.
      const std::size_t column = get_column_width();
      const bool option = line[column - 1] == ' ' && line[column] != ' ';
      const std::string indent(option ? column : std::min(line.find_first_not_of(' '), width_ / 2), ' ');
      for (std::size_t cut; line.size() > width_ && (cut = line.rfind(' ', width_)) != std::string::npos &&
                            cut > indent.size();) {  // a word longer than a line stays whole
        out += line.substr(0, line.find_last_not_of(' ', cut) + 1) + "\n";
        line = indent + line.substr(cut + 1);
      }
    }
    out += line + "\n";
  }
  return out;
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

CLI::Validator positiveFiniteCheck(std::optional<double> most) {
  const std::string rule = most ? "> 0 and at most " + shortNumber(*most) : "> 0";
  return parsedBy(
      [most, rule](const std::string& text) {
        const double v = number(text);
        if (!(v > 0.0 && std::isfinite(v) && v <= most.value_or(v)))
          throw std::invalid_argument("must be a number " + rule + ", got " + text);
      },
      rule);
}

CLI::Validator finiteCheck() {
  return parsedBy(
      [](const std::string& text) {
        if (!std::isfinite(number(text))) throw std::invalid_argument("must be a finite number, got " + text);
      },
      "NUMBER");
}

}  // namespace vdmap::app
