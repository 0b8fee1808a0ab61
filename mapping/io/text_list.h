#pragma once
// Parsing of whitespace-separated list files (TUM lists, trajectories): comments start with '#',
// every error names the file and line.
#include <filesystem>
#include <string>
#include <vector>

namespace vdmap {

struct ListLine {
  int number = 0;  ///< 1-based line number in the file
  std::vector<std::string> tokens;
};

/// Non-comment, non-blank lines, each required to have `columns` tokens ("expected '<expected>'").
/// Throws InputError when the file cannot be opened or a line has another number of fields.
std::vector<ListLine> readListFile(const std::filesystem::path& file, int columns, const char* expected);

/// The number in `token`; throws InputError ("expected a number for <what>") when it is not one
/// or is not finite.
double parseListNumber(const std::string& token, const std::filesystem::path& file, int line, const char* what);

/// The largest timestamp magnitude, s. Doubles keep 15 us steps up to it, fine for the 0.02 s
/// association window and the microseconds written back; Unix time is 1.7e9 s, while timestamps
/// in nanoseconds (1.7e18) are refused instead of matching nothing.
inline constexpr double kMaxTimestampS = 1e11;

/// `s` with its ASCII letters in lower case (file extensions, preset names).
std::string asciiLower(std::string s);

/// Throws InputError unless |t| <= kMaxTimestampS.
void checkTimestamp(double t, const std::filesystem::path& file, int line);

/// Throws InputError unless |t| <= kMaxTimestampS and t > *previous; then sets *previous = t.
void checkIncreasing(double t, double* previous, const std::filesystem::path& file, int line);

}  // namespace vdmap
