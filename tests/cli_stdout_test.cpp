// `-` for standard output on the JSON outputs (docs/output-contract.md), standard output that cannot be
// written (a private /dev/full), and the special files /dev/null and /dev/full as outputs left as they
// were (issue 34). The runs bake the fuzz corpus's 80-triangle mannequin (tests/fuzz/make_seeds.py), so
// each takes a fraction of a second.
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "cli_support.h"
#include "external_tools.h"

using namespace rigbake::test;
namespace ext = rigbake::test::external;

namespace {

std::string smallMannequin() { return ext::shellQuote(sourceDir() + "/tests/fuzz/character/mannequin.glb"); }

std::set<std::string> filesIn(const TempDir& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path)) names.insert(entry.path().filename().string());
  return names;
}

// A private copy of a memory device (/dev/null is 1 3, /dev/full 1 7): tests run as root, and if rigbake
// replaced it no other program would notice.
std::string privateDevice(const TempDir& dir, const std::string& name, unsigned minor) {
  const std::string path = dir / name;
  REQUIRE(::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, minor)) == 0);
  return path;
}

bool isCharacterDevice(const std::string& path, unsigned minor) {
  struct stat status {};
  return ::lstat(path.c_str(), &status) == 0 && S_ISCHR(status.st_mode) && major(status.st_rdev) == 1 &&
         minor(status.st_rdev) == minor;
}

}  // namespace

TEST_CASE("cli: '-' prints a JSON output on stdout byte for byte as the file holds it") {
  TempDir dir;
  const std::string character = smallMannequin();
  const CliResult to_files = runCli("bake " + character + " -o " + (dir / "a.glb") + " --stats " + (dir / "stats.json") +
                                    " --muscles-out " + (dir / "muscles.json"));
  INFO(to_files.err);
  REQUIRE(to_files.exit_code == 0);
  const std::string stats = slurp(dir / "stats.json"), muscles = slurp(dir / "muscles.json");
  REQUIRE(stats.find("\"deformation_error_mm\"") != std::string::npos);
  REQUIRE(muscles.find("\"rigbake\"") != std::string::npos);

  // The same -o (the stats name it), rewritten with the same bytes.
  const std::string model = slurp(dir / "a.glb");
  const CliResult stats_out = runCli("bake " + character + " -o " + (dir / "a.glb") + " --stats - --muscles-out " + (dir / "m2.json"));
  INFO(stats_out.err);
  CHECK(stats_out.exit_code == 0);
  CHECK(stats_out.out == stats);
  CHECK(slurp(dir / "a.glb") == model);
  CHECK(slurp(dir / "m2.json") == muscles);
  const CliResult muscles_out = runCli("bake " + character + " -o " + (dir / "a.glb") + " --muscles-out -");
  INFO(muscles_out.err);
  CHECK(muscles_out.exit_code == 0);
  CHECK(muscles_out.out == muscles);

  REQUIRE(runCli("place " + character + " -o " + (dir / "placed.json")).exit_code == 0);
  const CliResult placed = runCli("place " + character + " -o -");
  CHECK(placed.exit_code == 0);
  CHECK(placed.out == slurp(dir / "placed.json"));
  // Onto the VRM 1.0 mannequin, whose joints are bone_NN: the muscles really move to other names.
  const std::string vrm = ext::shellQuote(sourceDir() + "/tests/fuzz/character/vrm1.vrm");
  const std::string retarget = "retarget " + (dir / "placed.json") + " --from " + character + " --to " + vrm + " -o ";
  REQUIRE(runCli(retarget + (dir / "moved.json")).exit_code == 0);
  const CliResult moved = runCli(retarget + "-");
  CHECK(moved.exit_code == 0);
  CHECK(moved.out == slurp(dir / "moved.json"));
  CHECK(moved.out.find("bone_") != std::string::npos);
  CHECK(filesIn(dir) == std::set<std::string>{"a.glb", "stats.json", "muscles.json", "m2.json", "placed.json", "moved.json"});
}

TEST_CASE("cli: '-' where it is not JSON, twice, or beside --json is USAGE before any work") {
  TempDir dir;
  const std::string character = smallMannequin();
  struct Case {
    std::string args, usage;
  };
  const std::vector<Case> cases = {
      {"sample -o -", "USAGE -o:"},
      {"bake " + character + " -o -", "USAGE -o:"},
      {"bake " + character + " -o " + (dir / "a.glb") + " --packed-out -", "USAGE --packed-out:"},
      {"rom " + character + " -o -", "USAGE -o:"},
      {"bake " + character + " -o " + (dir / "a.glb") + " --stats - --muscles-out -", "USAGE --muscles-out:"},
      {"bake " + character + " -o " + (dir / "a.glb") + " --stats - --json", "USAGE --stats:"},
      {"place " + character + " -o - --json", "USAGE -o:"},
  };
  for (const Case& c : cases) {
    const CliResult run = runCli(c.args);
    INFO(c.args << "\n" << run.err);
    CHECK(run.exit_code == 1);
    CHECK(lineCount(run.err) == 1);
    CHECK(run.err.rfind(c.usage, 0) == 0);
    CHECK(run.out.empty());
    CHECK(filesIn(dir).empty());
  }
}

TEST_CASE("cli: a standard output that cannot be written fails the run and leaves no output behind") {
  TempDir dir;
  const std::string character = smallMannequin();
  const std::string full = privateDevice(dir, "full", 7);
  struct Case {
    std::string args;
    std::set<std::string> left;
  };
  const std::vector<Case> cases = {
      {"place " + character + " -o -", {"full"}},
      // The model and stats files were written: they are removed when stdout fails.
      {"bake " + character + " -o " + (dir / "a.glb") + " --stats " + (dir / "s.json") + " --muscles-out -", {"full"}},
      // --json: the file is the run's product and stays; the exit status says stdout was lost.
      {"landmarks " + character + " --json", {"full"}},
  };
  TempDir capture;  // stderr goes here, not into /dev/full
  for (const Case& c : cases) {
    const ext::CommandResult run =
        ext::runCommand(std::string(rigbake::test::kRigbakeCli) + " " + c.args + " >" + full + " 2>" + (capture / "err"));
    const std::string err = slurp(capture / "err");
    INFO(c.args << "\n" << err);
    CHECK(run.exit_code == 2);
    CHECK(lineCount(err) == 1);
    CHECK(err.rfind("IO_WRITE_FAILED -: cannot write to standard output: ", 0) == 0);
    CHECK(filesIn(dir) == c.left);
    CHECK(isCharacterDevice(full, 7));
  }
}

TEST_CASE("cli: /dev/null and /dev/full as outputs are refused and stay devices (private mknod copies)") {
  TempDir dir, elsewhere;
  const std::string character = smallMannequin();
  // view and validate read a bake first: one made in another folder.
  const std::string baked = elsewhere / "baked.glb";
  REQUIRE(runCli("bake " + character + " -o " + baked).exit_code == 0);
  const std::string null = privateDevice(dir, "null", 3), full = privateDevice(dir, "full", 7);
  for (const std::string& device : {null, full}) {
    for (const std::string& args :
         {"sample -o " + device, "place " + character + " -o " + device,
          "bake " + character + " -o " + device,
          "bake " + character + " -o " + (dir / "a.glb") + " --stats " + device,
          "bake " + character + " -o " + (dir / "a.glb") + " --muscles-out " + device,
          "bake " + character + " -o " + (dir / "a.glb") + " --packed-out " + device,
          "rom " + character + " -o " + device,
          "retarget " + (dir / "none.json") + " --from " + character + " --to " + character + " -o " + device,
          "view " + baked + " -o " + device,
          "validate " + baked + " --report " + device}) {
      const CliResult run = runCli(args);
      INFO(args << "\n" << run.err);
      CHECK(run.exit_code == 2);
      CHECK(lineCount(run.err) == 1);
      CHECK(run.err.find(device) != std::string::npos);
      CHECK(isCharacterDevice(null, 3));
      CHECK(isCharacterDevice(full, 7));
      CHECK(filesIn(dir) == std::set<std::string>{"null", "full"});
    }
  }
}
