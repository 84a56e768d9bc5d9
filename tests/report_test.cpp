// The three report formats of `rigbake validate`: report.json carries every check with its numbers,
// report.junit.xml is well-formed JUnit whose counts match its test cases, report.html is one
// self-contained page that headless Chromium renders with its plots and without console errors. All
// three are byte-identical for the same inputs.
#include <regex>

#include "formats/report_html.h"
#include "formats/report_json.h"
#include "formats/report_junit.h"
#include "validate_fixture.h"

using namespace rigbake;
namespace ext = rigbake::test::external;
using rigbake::test::checkOf;
using rigbake::test::countOccurrences;

namespace {

const Report& sampleReport() {
  static const Report report = validateBakedCharacter(test::validatedSample().inputs(), {});
  return report;
}

// A report whose LOCATOR_NEAR_SURFACE fails (one insertion moved 1 m forward).
const Report& failingReport() {
  static const Report report = [] {
    const test::ValidatedBake& sample = test::validatedSample();
    static MuscleSet moved = sample.muscles;
    moved.parts[0].insertion.world += sample.landmarks.body.forward;
    ValidationInputs inputs = sample.inputs();
    inputs.muscles = &moved;
    return validateBakedCharacter(inputs, {});
  }();
  return report;
}

int attributeOf(const std::string& tag, const std::string& name) {
  std::smatch match;
  REQUIRE(std::regex_search(tag, match, std::regex(name + "=\"(\\d+)\"")));
  return std::stoi(match[1]);
}

// Parses with Python's XML parser (a real XML 1.0 parser, python3 is a build dependency).
bool parsesAsXml(const std::string& path) {
  return ext::runCommand("python3 -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' " +
                         ext::shellQuote(path) + " 2>&1")
             .exit_code == 0;
}

}  // namespace

TEST_CASE("report json: every check with code, severity, threshold, measured value, status and location", "[shared:validated-bakes]") {
  const std::string text = reportJson(failingReport());
  // Fields in the documented order, not sorted: the version and tool first, then the character.
  CHECK(text.rfind("{\n  \"report_version\": ", 0) == 0);
  CHECK(text.find("\"tool\"") < text.find("\"character\""));
  const nlohmann::json json = nlohmann::json::parse(text);
  CHECK(json["report_version"] == kReportJsonVersion);
  CHECK(json["character"] == test::validatedSample().name);
  CHECK(json["passed"] == false);
  REQUIRE(json["checks"].size() == checkDefinitions().size());
  for (size_t i = 0; i < checkDefinitions().size(); ++i) {
    const nlohmann::json& check = json["checks"][i];
    INFO(check.dump());
    CHECK(check["code"] == checkDefinitions()[i].code);
    for (const char* key : {"severity", "status", "comparison", "threshold", "measured", "unit", "location", "message"})
      CHECK(check.contains(key));
  }
  const nlohmann::json& surface = json["checks"][2];
  CHECK(surface["code"] == "LOCATOR_NEAR_SURFACE");
  CHECK(surface["status"] == "fail");
  CHECK(surface["severity"] == "error");
  CHECK(surface["threshold"] == 0.1);
  CHECK(surface["measured"].get<double>() > 0.4);
  CHECK(surface["location"] == test::validatedSample().muscles.parts[0].fullName() + "/insertion");
  CHECK(json["summary"]["failed_errors"] == 1);
  CHECK(json["checks"][4]["code"] == "WEIGHTS_SUM");
  CHECK(json["checks"][4]["measured"].get<double>() < 1e-6);
  CHECK(json["checks"].back()["status"] == "skipped");
  CHECK(json["plots"]["muscle_ratio"].size() == test::validatedSample().loaded.character.clips.size());
  CHECK(json["plots"]["packed_deformation"][0]["max_m"].get<double>() < 0.0005);
}

TEST_CASE("report junit: well-formed, one testcase per check, counts that match, failures only at error severity", "[shared:validated-bakes]") {
  test::TempDir dir;
  const std::string xml = reportJunit({sampleReport(), failingReport()});
  const std::string path = dir / "report.junit.xml";
  std::ofstream(path, std::ios::binary) << xml;
  if (ext::requireTool(ext::onPath("python3"), "python3")) CHECK(parsesAsXml(path));

  const int testcases = countOccurrences(xml, "<testcase ");
  CHECK(testcases == static_cast<int>(2 * checkDefinitions().size()));
  std::smatch root;
  REQUIRE(std::regex_search(xml, root, std::regex("<testsuites [^>]*>")));
  CHECK(attributeOf(root.str(), "tests") == testcases);
  CHECK(attributeOf(root.str(), "failures") == countOccurrences(xml, "<failure "));
  CHECK(attributeOf(root.str(), "skipped") == countOccurrences(xml, "<skipped "));
  // Each suite's counts match its own cases.
  // Split by hand: libstdc++'s recursive std::regex overflows the stack on a lazy match this long.
  int suites = 0;
  for (size_t start = xml.find("<testsuite "); start != std::string::npos; start = xml.find("<testsuite ", start + 1)) {
    const size_t tag_end = xml.find('>', start) + 1;
    const size_t end = xml.find("</testsuite>", tag_end);
    REQUIRE(end != std::string::npos);
    const std::string tag = xml.substr(start, tag_end - start), body = xml.substr(tag_end, end - tag_end);
    CHECK(attributeOf(tag, "tests") == countOccurrences(body, "<testcase "));
    CHECK(attributeOf(tag, "failures") == countOccurrences(body, "<failure "));
    CHECK(attributeOf(tag, "skipped") == countOccurrences(body, "<skipped "));
    ++suites;
  }
  CHECK(suites == 2);
  // The failing report fails exactly LOCATOR_NEAR_SURFACE; LOCATOR_SYMMETRY is a warning and passes as a case.
  CHECK(countOccurrences(xml, "<failure ") == 1);
  CHECK(xml.find("<failure type=\"LOCATOR_NEAR_SURFACE\"") != std::string::npos);
  CHECK(xml.find("warning (not failing the build)") != std::string::npos);
}

TEST_CASE("report junit: names and messages are escaped", "[shared:validated-bakes]") {
  Report report = sampleReport();
  // A file name is bytes: one that is not UTF-8 (\xFF) must not make the XML ill-formed; valid UTF-8
  // (\xC3\xA9) stays.
  report.character = "a<b>&\"c'\xFF\xC3\xA9.glb";
  report.checks[0].status = CheckStatus::kFail;
  report.checks[0].message = "bad </failure> \x01 & more";
  const std::string xml = reportJunit({report});
  CHECK(xml.find("a&lt;b&gt;&amp;&quot;c&apos;\xEF\xBF\xBD\xC3\xA9.glb") != std::string::npos);
  CHECK(xml.find('\xFF') == std::string::npos);
  CHECK(xml.find("<b>") == std::string::npos);
  CHECK(xml.find("bad &lt;/failure&gt; \xEF\xBF\xBD &amp; more") != std::string::npos);
  CHECK(xml.find('\x01') == std::string::npos);
  test::TempDir dir;
  std::ofstream(dir / "x.xml", std::ios::binary) << xml;
  if (ext::requireTool(ext::onPath("python3"), "python3")) CHECK(parsesAsXml(dir / "x.xml"));
}

TEST_CASE("report: json, junit and html are byte-identical for the same inputs") {
  const Report again = validateBakedCharacter(test::validatedSample().inputs(), {});
  CHECK(reportJson(again) == reportJson(sampleReport()));
  CHECK(reportJunit({again}) == reportJunit({sampleReport()}));
  CHECK(reportHtml(again) == reportHtml(sampleReport()));
}

TEST_CASE("report html: self-contained, with every plot", "[shared:validated-bakes]") {
  const std::string html = reportHtml(failingReport());
  // Nothing to fetch: no script, stylesheet link, external image, font or url().
  for (const char* forbidden : {"<script", "<link", "src=", "url(", "@import", "@font-face", "https://"})
    CHECK(html.find(forbidden) == std::string::npos);
  CHECK(countOccurrences(html, "http://") == countOccurrences(html, "xmlns=\"http://www.w3.org/2000/svg\""));
  CHECK(countOccurrences(html, "<svg class=\"view\"") == 2);
  CHECK(countOccurrences(html, "<svg class=\"chart ratio\"") ==
        static_cast<int>(test::validatedSample().loaded.character.clips.size()));
  CHECK(countOccurrences(html, "<svg class=\"chart histogram\"") == 1);
  CHECK(countOccurrences(html, "<svg class=\"chart deformation\"") == 1);
  CHECK(countOccurrences(html, "<table class=\"memory\"") == 1);
  CHECK(countOccurrences(html, "<table class=\"checks\"") == 1);
  CHECK(countOccurrences(html, "<tr class=\"fail-error\">") == 1);
  CHECK(html.find("class=\"muscle flagged\"") != std::string::npos);
  CHECK(html.find("<span class=\"verdict fail\">FAIL</span>") != std::string::npos);
  // Every muscle is drawn in both views.
  CHECK(countOccurrences(html, "<g class=\"muscle\">") + countOccurrences(html, "<g class=\"muscle flagged\">") ==
        2 * static_cast<int>(test::validatedSample().muscles.parts.size()));
}

TEST_CASE("report html: headless Chromium renders the plots and logs no errors") {
  if (!ext::requireTool(!test::chromiumBinary().empty(), "chromium (apt-get install chromium)")) return;
  test::TempDir dir;
  for (const Report* report : {&sampleReport(), &failingReport()}) {
    const std::string path = dir / "report.html";
    std::ofstream(path, std::ios::binary) << reportHtml(*report);
    const std::string screenshot = dir / "report.png";
    const test::ChromiumRun run = test::renderInChromium(path, screenshot);
    INFO(run.log);
    CHECK(run.exit_code == 0);
    // The rendered DOM holds the plots: both body views, one ratio chart per clip, the histogram and the bars.
    CHECK(countOccurrences(run.dom, "<svg class=\"view\"") == 2);
    CHECK(countOccurrences(run.dom, "<svg class=\"chart ratio\"") == static_cast<int>(report->ratios.size()));
    CHECK(countOccurrences(run.dom, "<svg class=\"chart histogram\"") == 1);
    CHECK(countOccurrences(run.dom, "<svg class=\"chart deformation\"") == 1);
    CHECK(countOccurrences(run.dom, "<polyline") >= static_cast<int>(report->figure.muscles.size()));
    CHECK(run.dom.find("</html>") != std::string::npos);
    CHECK(run.log.find("Uncaught") == std::string::npos);
    CHECK(run.log.find("ERROR:CONSOLE") == std::string::npos);
    CHECK(run.log.find("net::ERR_") == std::string::npos);
    // A screenshot came out and is a real picture, not an empty page.
    REQUIRE(test::fileExists(screenshot));
    CHECK(std::filesystem::file_size(screenshot) > 50000);
    if (const char* keep = std::getenv("RIGBAKE_KEEP_REPORT_SCREENSHOT"))
      std::filesystem::copy_file(screenshot, std::string(keep) + (report == &sampleReport() ? "-pass.png" : "-fail.png"),
                                 std::filesystem::copy_options::overwrite_existing);
  }
}
