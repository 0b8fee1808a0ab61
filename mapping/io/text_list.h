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

/// The whitespace-separated words of one list line up to a comment: a word starting with '#'
/// ends the line ("1 2 3  # a note" is 1 2 3). None for a blank or comment line.
std::vector<std::string> listWords(const std::string& line);

/// Throws InputError ("FILE: is a folder, not a file") when `file` is a folder: read as a file, a
/// folder gives no lines on some systems and a raw library error on others.
void checkNotAFolder(const std::filesystem::path& file);

/// The whole of `file`. Throws InputError naming the file when it is a folder, does not exist or
/// cannot be read (with the system's reason).
std::string readWholeFile(const std::filesystem::path& file);

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
