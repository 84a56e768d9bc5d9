// `rigbake validate` as CI runs it: sample -> place -> bake -> validate writes the three reports and
// exits 0; a muscle file with a locator 1 m off makes it exit 1 with LOCATOR_NEAR_SURFACE failed in
// every report; a bad config is exit 3 and writes nothing; the report is byte-identical across runs,
// and Chromium renders it.
#include <sys/stat.h>

#include <map>

#include "validate_fixture.h"

using namespace rigbake;
namespace ext = rigbake::test::external;
using rigbake::test::countOccurrences;
using rigbake::test::runCli;
using rigbake::test::slurp;

namespace {

// The sample placed and baked by the CLI once per test process.
struct CliBake {
  std::string dir, glb, muscles;
};

const CliBake& cliBake() {
  static const CliBake bake = [] {
    CliBake b;
    b.dir = test::validateScratchDir() + "/cli";
    std::filesystem::create_directories(b.dir);
    b.glb = b.dir + "/baked.glb";
    b.muscles = b.dir + "/muscles.json";
    const std::string sample = test::sampleGlbPathForCli();
    REQUIRE(runCli("place " + ext::shellQuote(sample) + " -o " + ext::shellQuote(b.muscles)).exit_code == 0);
    REQUIRE(runCli("bake " + ext::shellQuote(sample) + " --muscles " + ext::shellQuote(b.muscles) +
                   " --influences 7 -o " + ext::shellQuote(b.glb))
                .exit_code == 0);
    return b;
  }();
  return bake;
}

nlohmann::json checkIn(const nlohmann::json& report, const std::string& code) {
  for (const nlohmann::json& check : report["checks"]) {
    if (check["code"] == code) return check;
  }
  FAIL("no " << code);
  return {};
}

}  // namespace

TEST_CASE("cli validate: a good bake passes, exit 0, with report.json, report.junit.xml and report.html") {
  const CliBake& bake = cliBake();
  test::TempDir out;
  const std::string dir = out / "reports";
  test::CliResult run = runCli("validate " + ext::shellQuote(bake.glb) + " --muscles " + ext::shellQuote(bake.muscles) +
                               " --report " + ext::shellQuote(dir) + " --json");
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(slurp(dir + "/report.json"));
  CHECK(nlohmann::json::parse(run.out) == report);
  CHECK(report["passed"] == true);
  CHECK(report["character"] == "baked.glb");
  CHECK(report["character_stats"]["packed_influences"] == 7);
  CHECK(checkIn(report, "WEIGHTS_SUM")["measured"].get<double>() <= 0.001);
  CHECK(checkIn(report, "MUSCLE_RATIO_IN_RANGE")["status"] == "pass");
  CHECK(checkIn(report, "MUSCLE_RATIO_IN_RANGE")["measured"].get<double>() >= 0.0);
  CHECK(checkIn(report, "INFLUENCE_COUNT")["measured"].get<double>() <= 7.0);
  CHECK(checkIn(report, "KHRONOS_VALIDATOR")["status"] == "skipped");
  // The report says what happened, the same from `build`, which has no such flag; the command line
  // names the flag that asks for it.
  CHECK(checkIn(report, "KHRONOS_VALIDATOR")["message"] == "not requested");
  CHECK(run.err.find("KHRONOS_VALIDATOR baked.glb: skipped: not requested (pass --khronos)\n") != std::string::npos);
  const std::string junit = slurp(dir + "/report.junit.xml");
  CHECK(countOccurrences(junit, "<testcase ") == static_cast<int>(checkDefinitions().size()));
  CHECK(countOccurrences(junit, "<failure ") == 0);
  CHECK(slurp(dir + "/report.html").find("<span class=\"verdict pass\">PASS</span>") != std::string::npos);
  CHECK(run.err.find("validated baked.glb: " + std::to_string(checkDefinitions().size()) + " checks, 0 errors") != std::string::npos);
  // The sample is one welded surface: no two skinned vertices share a place, so no seam to measure.
  CHECK(checkIn(report, "SKIN_SEAM_OPEN")["status"] == "skipped");
  // Only the three reports, no temporary files left beside them.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) files += entry.is_regular_file();
  CHECK(files == 3);
}

TEST_CASE("cli validate: a muscle locator 1 m off fails LOCATOR_NEAR_SURFACE with exit code 1") {
  const CliBake& bake = cliBake();
  test::TempDir out;
  nlohmann::json muscles = nlohmann::json::parse(slurp(bake.muscles));
  const std::string moved = muscles["rigbake"]["muscles"].begin().key();
  // The sample's joint frames are unscaled, so 1.0 in the attach joint's frame is 1 m.
  muscles["rigbake"]["muscles"][moved]["origin"]["local"][1] =
      muscles["rigbake"]["muscles"][moved]["origin"]["local"][1].get<double>() + 1.0;
  const std::string edited = out / "edited.json";
  std::ofstream(edited) << muscles.dump(2);
  const std::string dir = out / "reports";
  test::CliResult run =
      runCli("validate " + ext::shellQuote(bake.glb) + " --muscles " + ext::shellQuote(edited) + " --report " + ext::shellQuote(dir));
  INFO(run.err);
  CHECK(run.exit_code == 4);
  CHECK(run.err.find("LOCATOR_NEAR_SURFACE " + moved + "/origin: error:") != std::string::npos);
  const nlohmann::json report = nlohmann::json::parse(slurp(dir + "/report.json"));
  CHECK(report["passed"] == false);
  const nlohmann::json surface = checkIn(report, "LOCATOR_NEAR_SURFACE");
  CHECK(surface["status"] == "fail");
  CHECK(surface["location"] == moved + "/origin");
  CHECK(surface["measured"].get<double>() > surface["threshold"].get<double>());
  const std::string junit = slurp(dir + "/report.junit.xml");
  CHECK(countOccurrences(junit, "<failure ") == 1);
  CHECK(junit.find("<failure type=\"LOCATOR_NEAR_SURFACE\"") != std::string::npos);
  CHECK(slurp(dir + "/report.html").find("<span class=\"verdict fail\">FAIL</span>") != std::string::npos);
}

TEST_CASE("cli validate: without --muscles the muscle checks are skipped and the rest still run") {
  const CliBake& bake = cliBake();
  test::TempDir out;
  test::CliResult run = runCli("validate " + ext::shellQuote(bake.glb) + " --report " + ext::shellQuote(out / "r"));
  INFO(run.err);
  CHECK(run.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "r/report.json"));
  CHECK(checkIn(report, "MUSCLE_RATIO_IN_RANGE")["status"] == "skipped");
  CHECK(checkIn(report, "LOCATOR_NEAR_SURFACE")["status"] == "skipped");
  CHECK(checkIn(report, "PACKED_DEFORMATION_ERROR")["status"] == "pass");
  CHECK(checkIn(report, "GLTF_STRUCTURE")["status"] == "pass");
  // The report says what is missing in its own words; the command line adds the flag that gives it.
  CHECK(checkIn(report, "MUSCLE_RATIO_IN_RANGE")["message"] == "no muscle file given");
  for (const char* code : {"LOCATOR_SYMMETRY", "LOCATOR_NEAR_SURFACE", "MUSCLE_RATIO_IN_RANGE"})
    CHECK(run.err.find(std::string(code) + " baked.glb: skipped: no muscle file given (pass --muscles)\n") != std::string::npos);
  const std::string html = slurp(out / "r/report.html");
  CHECK(html.find("No muscle file was given, so muscle ratios were not evaluated.") != std::string::npos);
  CHECK(html.find("--muscles") == std::string::npos);
}

TEST_CASE("cli validate: --config overrides a threshold, a malformed config is exit 3 and writes nothing") {
  const CliBake& bake = cliBake();
  test::TempDir out;
  const std::string config = out / "config.json";
  std::ofstream(config) << R"({"checks": {"PACKED_DEFORMATION_ERROR": {"threshold": 0.0}}})";
  test::CliResult strict = runCli("validate " + ext::shellQuote(bake.glb) + " --config " + ext::shellQuote(config) +
                                  " --report " + ext::shellQuote(out / "strict"));
  INFO(strict.err);
  // 16-bit WEIGHTS_n and 0.001 packed weights differ by rounding, so a zero tolerance fails.
  CHECK(strict.exit_code == 4);
  CHECK(checkIn(nlohmann::json::parse(slurp(out / "strict/report.json")), "PACKED_DEFORMATION_ERROR")["status"] == "fail");

  std::ofstream(config) << R"({"checks": {"PACKED_DEFORMATION_ERROR": {"limit": 0.0}}})";
  test::CliResult bad = runCli("validate " + ext::shellQuote(bake.glb) + " --config " + ext::shellQuote(config) +
                               " --report " + ext::shellQuote(out / "bad"));
  CHECK(bad.exit_code == 3);
  CHECK(bad.err.rfind("VALIDATE_CONFIG_INVALID " + config + "#/checks/PACKED_DEFORMATION_ERROR/limit: unknown key", 0) == 0);
  CHECK(!std::filesystem::exists(out / "bad"));

  test::CliResult missing = runCli("validate " + ext::shellQuote(out / "nope.glb") + " --report " + ext::shellQuote(out / "none"));
  CHECK(missing.exit_code == 2);
  CHECK(!std::filesystem::exists(out / "none"));
}

TEST_CASE("cli validate: two runs write byte-identical reports, on one thread and on two showing progress") {
  const CliBake& bake = cliBake();
  test::TempDir out;
  std::map<std::string, test::CliResult> runs;
  for (const char* name : {"a", "b"}) {
    runs[name] = runCli("validate " + ext::shellQuote(bake.glb) + " --muscles " + ext::shellQuote(bake.muscles) + " --report " +
                        ext::shellQuote(out / name) + (std::string(name) == "b" ? " --threads 2 --progress always" : " --threads 1"));
    INFO(runs[name].err);
    REQUIRE(runs[name].exit_code == 0);
  }
  for (const char* file : {"report.json", "report.junit.xml", "report.html"}) {
    INFO(file);
    CHECK(slurp(out / (std::string("a/") + file)) == slurp(out / (std::string("b/") + file)));
  }
  // Not a terminal: the default shows nothing; `always` one line per stage, in order.
  CHECK(runs["a"].err.find("rigbake validate:") == std::string::npos);
  size_t at = 0;
  for (const char* stage : {"loading the character", "measuring every frame and drawing the pictures", "checking",
                            "writing the reports"}) {
    INFO(stage);
    const size_t found = runs["b"].err.find(std::string("rigbake validate: ") + stage + " (", at);
    REQUIRE(found != std::string::npos);
    at = found;
  }
}

TEST_CASE("cli validate: --khronos includes the Khronos glTF-Validator's verdict") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  const CliBake& bake = cliBake();
  test::TempDir out;
  test::CliResult run = runCli("validate " + ext::shellQuote(bake.glb) + " --khronos --report " + ext::shellQuote(out / "r"));
  INFO(run.err);
  CHECK(run.exit_code == 0);
  const nlohmann::json khronos = checkIn(nlohmann::json::parse(slurp(out / "r/report.json")), "KHRONOS_VALIDATOR");
  CHECK(khronos["status"] == "pass");
  CHECK(khronos["measured"] == 0.0);
  CHECK(khronos["message"].get<std::string>().rfind("0 errors, ", 0) == 0);
}

TEST_CASE("cli validate: Chromium renders the CLI's report.html with its plots and no errors") {
  if (!ext::requireTool(!test::chromiumBinary().empty(), "chromium (apt-get install chromium)")) return;
  const CliBake& bake = cliBake();
  test::TempDir out;
  REQUIRE(runCli("validate " + ext::shellQuote(bake.glb) + " --muscles " + ext::shellQuote(bake.muscles) +
                 " --report " + ext::shellQuote(out / "r"))
              .exit_code == 0);
  const test::ChromiumRun run = test::renderInChromium(out / "r/report.html");
  INFO(run.log);
  CHECK(run.exit_code == 0);
  CHECK(countOccurrences(run.dom, "<svg class=\"view\"") == 2);
  CHECK(countOccurrences(run.dom, "<svg class=\"chart ratio\"") >= 1);
  CHECK(countOccurrences(run.dom, "<svg class=\"chart histogram\"") == 1);
  CHECK(countOccurrences(run.dom, "<svg class=\"chart deformation\"") == 1);
  CHECK(run.log.find("Uncaught") == std::string::npos);
  CHECK(run.log.find("ERROR:CONSOLE") == std::string::npos);
}

TEST_CASE("cli validate: a report that cannot be written leaves none of the three") {
  test::TempDir dir;
  const std::string reports = dir / "reports";
  std::filesystem::create_directories(reports);
  std::ofstream(dir / "block") << "a regular file";
  std::string code;
  SECTION("report.html a link into a regular file: its temporary file cannot be created") {
    std::filesystem::create_symlink("../block/report.html", reports + "/report.html");
    code = "IO_WRITE_FAILED";
  }
  SECTION("report.html a directory") {
    std::filesystem::create_directories(reports + "/report.html");
    code = "IO_OUTPUT_NOT_REGULAR";
  }
  const test::CliResult run = runCli("validate " + ext::shellQuote(cliBake().glb) + " --no-pictures --report " + ext::shellQuote(reports));
  INFO(run.err);
  CHECK(run.exit_code == 2);
  CHECK(test::lineCount(run.err) == 1);
  CHECK(run.err.rfind(code + " " + reports + "/report.html:", 0) == 0);
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(reports)) left.push_back(entry.path().filename().string());
  CHECK(left == std::vector<std::string>{"report.html"});
}

TEST_CASE("cli validate: a report path that is a FIFO is refused before any work and stays a FIFO") {
  test::TempDir dir;
  const std::string reports = dir / "reports";
  std::filesystem::create_directories(reports);
  REQUIRE(::mkfifo((reports + "/report.json").c_str(), 0644) == 0);
  const test::CliResult run = runCli("validate " + ext::shellQuote(cliBake().glb) + " --report " + ext::shellQuote(reports));
  INFO(run.err);
  CHECK(run.exit_code == 2);
  CHECK(test::lineCount(run.err) == 1);
  CHECK(run.err.rfind("IO_OUTPUT_NOT_REGULAR " + reports + "/report.json:", 0) == 0);
  CHECK(std::filesystem::is_fifo(reports + "/report.json"));
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(reports)) left.push_back(entry.path().filename().string());
  CHECK(left == std::vector<std::string>{"report.json"});
  // An empty --report names no folder.
  const test::CliResult empty = runCli("validate " + ext::shellQuote(cliBake().glb) + " --report ''");
  CHECK(empty.exit_code == 1);
  CHECK(empty.err.rfind("USAGE --report:", 0) == 0);
}

TEST_CASE("cli validate: a report folder the run created is gone again when its reports cannot be written") {
  // A full disk, played by a file size limit: write() fails with EFBIG (SIGXFSZ ignored, or it kills).
  test::TempDir dir;
  const std::string reports = dir / "new/reports";
  const ext::CommandResult run = ext::runCommand("ulimit -f 8 && trap '' XFSZ && " + std::string(rigbake::test::kRigbakeCli) + " validate " +
                                                 ext::shellQuote(cliBake().glb) + " --no-pictures --report " +
                                                 ext::shellQuote(reports) + " 2>&1");
  INFO(run.output);
  CHECK(run.exit_code == 2);
  CHECK(run.output.rfind("IO_WRITE_FAILED " + reports + "/report.", 0) == 0);
  CHECK(run.output.find("File too large") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir / "new"));
}

TEST_CASE("cli validate: --input naming another character than the one baked is VALIDATE_INPUT_MISMATCH, no report") {
  const std::string other = test::requireAsset("CesiumMan.glb");
  if (other.empty()) return;
  const std::string reports = test::validateScratchDir() + "/mismatch";
  const test::CliResult run = runCli("validate " + ext::shellQuote(cliBake().glb) + " --input " + ext::shellQuote(other) +
                                     " --no-pictures --report " + ext::shellQuote(reports));
  CHECK(run.exit_code == 3);
  CHECK(run.err.rfind("VALIDATE_INPUT_MISMATCH " + other + ": ", 0) == 0);
  CHECK(run.err.find("not the character baked.glb was baked from") != std::string::npos);
  CHECK(test::lineCount(run.err) == 1);
  CHECK(!std::filesystem::exists(reports + "/report.json"));
  // The sample it was baked from is accepted.
  const test::CliResult own = runCli("validate " + ext::shellQuote(cliBake().glb) + " --input " +
                                     ext::shellQuote(test::sampleGlbPathForCli()) + " --no-pictures --report " + ext::shellQuote(reports));
  INFO(own.err);
  CHECK(own.exit_code == 0);
}

