#pragma once
// JUnit XML for a suite of rendered views (`vdmap render --suite`), the report format CI systems
// (GitLab, Jenkins, GitHub test reporters) read: one <testcase> per view, a <failure> for each
// view whose image differs from its golden.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vdmap::app {

/// One view of a suite and its verdict.
struct SuiteCase {
  std::string map{};   ///< the suite's name of the map or session it shows (classname vdmap.render.MAP)
  std::string view{};  ///< the view's name (the testcase's name)
  double seconds = 0;  ///< wall time spent rendering and comparing it
  bool passed = true;
  std::string message{};  ///< a failure's one line (ImageComparison::summary()); empty when passed
  std::string details{};  ///< a failure's body, e.g. where its actual and diff images were written
};

/// A whole suite run.
struct SuiteReport {
  std::string name{};  ///< the suite file's name, e.g. "views.yaml"
  double seconds = 0;  ///< wall time of the whole run
  std::vector<SuiteCase> cases{};
};

/// `text` fit for XML 1.0 character data and attribute values: & < > " ' as entities, tab,
/// newline and carriage return as character references (so attribute values keep them), other
/// control characters (which XML 1.0 cannot carry at all) as '?'. Other bytes pass unchanged
/// (names are UTF-8).
std::string escapeXml(std::string_view text);

/// The report as a JUnit XML document: <testsuites> holding one <testsuite name tests failures
/// errors="0" time>, with <testcase classname="vdmap.render.MAP" name="VIEW" time> per case and,
/// for a failed one, <failure message="MESSAGE">DETAILS</failure>. Times in seconds with three
/// decimals, independent of the locale.
std::string junitXml(const SuiteReport& report);

/// Writes junitXml(report) to `file` atomically (writeFileAtomically): a CI system reading the
/// report never sees half of it. Throws std::runtime_error naming the file when it cannot.
void writeJUnit(const std::filesystem::path& file, const SuiteReport& report);

}  // namespace vdmap::app
