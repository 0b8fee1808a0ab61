#include "app/view/json_file.h"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <vector>

#include "mapping/core/error.h"

namespace vdmap::app {
using nlohmann::json;

namespace {

// The offsets in `text` where each object key starts, in document order: every string literal
// followed (after blanks) by ':'.
std::vector<std::size_t> keyOffsets(const std::string& text) {
  std::vector<std::size_t> keys;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '"') continue;
    const std::size_t start = i;
    for (++i; i < text.size() && text[i] != '"'; ++i)
      if (text[i] == '\\') ++i;
    std::size_t next = i + 1;
    while (next < text.size() && std::isspace(static_cast<unsigned char>(text[next]))) ++next;
    if (next < text.size() && text[next] == ':') keys.push_back(start);
  }
  return keys;
}

}  // namespace

json parseJsonStrictly(const std::string& text, const std::string& file) {
  std::vector<std::set<std::string>> open;  // the keys seen in each object being read
  std::size_t key_index = 0;                // keys so far, in document order
  std::string duplicate;
  std::size_t duplicate_index = 0;
  const json::parser_callback_t check = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) open.emplace_back();
    if (event == json::parse_event_t::object_end && !open.empty()) open.pop_back();
    if (event == json::parse_event_t::key) {
      if (!open.empty() && !open.back().insert(parsed.get<std::string>()).second && duplicate.empty()) {
        duplicate = parsed.get<std::string>();
        duplicate_index = key_index;
      }
      ++key_index;
    }
    return true;
  };
  json j;
  try {
    j = json::parse(text, check);
  } catch (const json::parse_error& e) {
    std::string what = e.what();
    what = what.substr(what.find(' ') + 1);  // "[json.exception.parse_error.101] parse error at ..."
    throw InputError(file, "not valid JSON (" + what + ")");
  }
  if (!duplicate.empty()) {
    const std::vector<std::size_t> keys = keyOffsets(text);
    const std::size_t at = duplicate_index < keys.size() ? keys[duplicate_index] : 0;
    const long line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(at), '\n');
    throw InputError(file + ":" + std::to_string(line), "key '" + duplicate + "' is given twice in one object");
  }
  return j;
}

void refuseUnknownKeys(const json& given, const json& known, const std::string& prefix) {
  if (!given.is_object() || !known.is_object()) return;
  for (const auto& [key, value] : given.items()) {
    if (!known.contains(key)) {
      std::string valid;
      for (const auto& [k, v] : known.items()) valid += (valid.empty() ? "" : ", ") + k;
      throw std::invalid_argument("unknown key '" + prefix + key + "' (valid: " + valid + ")");
    }
    refuseUnknownKeys(value, known.at(key), prefix + key + ".");
  }
}

}  // namespace vdmap::app
