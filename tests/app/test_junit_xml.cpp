// app/view/junit_xml.h: the JUnit document of a render suite, its escaping and its atomic write.
#include <gtest/gtest.h>

#include <clocale>
#include <cmath>
#include <stdexcept>
#include <string>

#include "app/view/junit_xml.h"
#include "tests/support/test_util.h"

namespace vdmap::app {
namespace {

using test::TempDir;

SuiteReport twoViewsOneFailing() {
  SuiteReport report;
  report.name = "views & more.yaml";
  report.seconds = 2.5;
  report.cases.push_back({.map = "kitchen", .view = "global", .seconds = 0.25});
  report.cases.push_back({.map = "room",
                          .view = "k3 \"<uncertainty>\"",
                          .seconds = 0.1234,
                          .passed = false,
                          .message = "1532 of 76800 pixels (2%, allowed 0.5%) differ by more than 8 counts",
                          .details = "actual: out/k3.png\ndiff: out/k3.diff.png"});
  return report;
}

TEST(JUnitXml, EscapesNamesAndCountsFailures) {
  EXPECT_EQ(junitXml(twoViewsOneFailing()),
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<testsuites name=\"views &amp; more.yaml\" tests=\"2\" failures=\"1\" errors=\"0\" time=\"2.500\">\n"
            "  <testsuite name=\"views &amp; more.yaml\" tests=\"2\" failures=\"1\" errors=\"0\" time=\"2.500\">\n"
            "    <testcase classname=\"vdmap.render.kitchen\" name=\"global\" time=\"0.250\"/>\n"
            "    <testcase classname=\"vdmap.render.room\" name=\"k3 &quot;&lt;uncertainty&gt;&quot;\" "
            "time=\"0.123\">\n"
            "      <failure message=\"1532 of 76800 pixels (2%, allowed 0.5%) differ by more than 8 counts\" "
            "type=\"image differs\">actual: out/k3.png&#10;diff: out/k3.diff.png</failure>\n"
            "    </testcase>\n"
            "  </testsuite>\n"
            "</testsuites>\n");
}

TEST(JUnitXml, AnEmptySuiteIsAValidDocumentWithNoTests) {
  const std::string xml = junitXml(SuiteReport{.name = "none.yaml"});
  EXPECT_NE(xml.find("<testsuite name=\"none.yaml\" tests=\"0\" failures=\"0\" errors=\"0\" time=\"0.000\">"),
            std::string::npos)
      << xml;
  EXPECT_EQ(xml.find("<testcase"), std::string::npos);
}

TEST(JUnitXml, EscapingKeepsTextAndUtf8AndDropsWhatXmlCannotCarry) {
  EXPECT_EQ(escapeXml("a&b<c>d\"e'f"), "a&amp;b&lt;c&gt;d&quot;e&apos;f");
  EXPECT_EQ(escapeXml("tab\tline\nreturn\r"), "tab&#9;line&#10;return&#13;");
  EXPECT_EQ(escapeXml(std::string("nul\0bell\a", 9)), "nul?bell?");
  EXPECT_EQ(escapeXml("caf\xC3\xA9 \xF0\x9F\x98\x80"), "caf\xC3\xA9 \xF0\x9F\x98\x80");  // é and an emoji
  EXPECT_EQ(escapeXml("cut \xC3"), "cut ?");                                             // a truncated sequence
  EXPECT_EQ(escapeXml("stray \x80 byte"), "stray ? byte");                               // a continuation byte alone
  EXPECT_EQ(escapeXml("over\xE0\x80\x80long"), "over???long");                           // an overlong NUL
  EXPECT_EQ(escapeXml("half\xED\xA0\x80"), "half???");                                   // a UTF-16 surrogate
  EXPECT_EQ(escapeXml("not \xEF\xBF\xBE a char"), "not ? a char");                       // U+FFFE, no XML character
  EXPECT_EQ(escapeXml(""), "");
}

TEST(JUnitXml, TimesAreSecondsWithAPointWhateverTheLocale) {
  // A locale with a decimal comma, where one is installed; to_chars ignores it either way.
  const bool comma = std::setlocale(LC_ALL, "de_DE.UTF-8") != nullptr;
  SuiteReport report{.name = "t.yaml", .seconds = 1234.56789};
  report.cases.push_back({.map = "m", .view = "nan", .seconds = std::nan("")});
  report.cases.push_back({.map = "m", .view = "negative", .seconds = -1.0});
  const std::string xml = junitXml(report);
  std::setlocale(LC_ALL, "C");
  EXPECT_NE(xml.find("time=\"1234.568\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("name=\"nan\" time=\"0.000\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("name=\"negative\" time=\"0.000\""), std::string::npos) << xml;
  if (!comma) std::cout << "de_DE.UTF-8 is not installed: checked in the C locale only\n";
}

TEST(JUnitXml, WritesTheWholeDocumentAndLeavesNoTemporary) {
  TempDir dir;
  const auto file = dir / "junit.xml";
  test::writeText(file, "an older report");
  writeJUnit(file, twoViewsOneFailing());
  EXPECT_EQ(test::readFile(file), junitXml(twoViewsOneFailing()));
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 1);
}

TEST(JUnitXml, AnUnwritableFolderIsAnErrorNamingTheFile) {
  TempDir dir;
  const auto file = dir / "missing" / "junit.xml";
  try {
    writeJUnit(file, twoViewsOneFailing());
    FAIL() << "wrote into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(file));
}

}  // namespace
}  // namespace vdmap::app
