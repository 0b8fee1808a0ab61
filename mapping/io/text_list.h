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

/// Throws InputError unless t > *previous; then sets *previous = t.
void checkIncreasing(double t, double* previous, const std::filesystem::path& file, int line);

}  // namespace vdmap
