// The command line as users meet it: clear one-line errors with stable codes and exit statuses, no
// output left behind by a failed run, deterministic outputs, and the documented --json contract.
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "cli_support.h"
#include "glb_support.h"
#include "external_tools.h"

using namespace rigbake::test;
namespace ext = rigbake::test::external;

namespace {

// A minimal glTF with one triangle and, when `joints` > 0, a skin of that many chained joints.
std::string tinyGltf(int joints) {
  nlohmann::json gltf = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
  std::string bytes;
  auto append_floats = [&](std::initializer_list<float> values) {
    for (float v : values) bytes.append(reinterpret_cast<const char*>(&v), 4);
  };
  append_floats({0, 0, 0, 1, 0, 0, 0, 1, 0});
  nlohmann::json nodes = nlohmann::json::array();
  nodes.push_back({{"mesh", 0}});
  nlohmann::json accessors = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
                               {"min", {0, 0, 0}}, {"max", {1, 1, 0}}}};
  nlohmann::json views = {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}}};
  nlohmann::json primitive = {{"attributes", {{"POSITION", 0}}}};
  if (joints > 0) {
    nodes[0]["skin"] = 0;
    nlohmann::json skin_joints = nlohmann::json::array();
    for (int j = 0; j < joints; ++j) {
      nlohmann::json node = {{"name", "bone" + std::to_string(j)}, {"translation", {0, j == 0 ? 0.0 : 0.5, 0}}};
      if (j + 1 < joints) node["children"] = {j + 2};
      nodes.push_back(node);
      skin_joints.push_back(j + 1);
    }
    gltf["skins"] = {{{"joints", skin_joints}}};
    for (int v = 0; v < 3; ++v) {
      for (uint16_t k : {uint16_t(0), uint16_t(0), uint16_t(0), uint16_t(0)}) bytes.append(reinterpret_cast<const char*>(&k), 2);
    }
    append_floats({1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0});
    views.push_back({{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}});
    views.push_back({{"buffer", 0}, {"byteOffset", 60}, {"byteLength", 48}});
    accessors.push_back({{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "VEC4"}});
    accessors.push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC4"}});
    primitive["attributes"]["JOINTS_0"] = 1;
    primitive["attributes"]["WEIGHTS_0"] = 2;
  }
  std::string base64;
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t chunk = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) chunk |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) chunk |= static_cast<uint8_t>(bytes[i + 2]);
    base64 += kAlphabet[(chunk >> 18) & 63];
    base64 += kAlphabet[(chunk >> 12) & 63];
    base64 += i + 1 < bytes.size() ? kAlphabet[(chunk >> 6) & 63] : '=';
    base64 += i + 2 < bytes.size() ? kAlphabet[chunk & 63] : '=';
  }
  gltf["nodes"] = nodes;
  gltf["scenes"] = {{{"nodes", {0, 1}}}};
  if (joints == 0) gltf["scenes"] = {{{"nodes", {0}}}};
  gltf["meshes"] = {{{"primitives", {primitive}}}};
  gltf["accessors"] = accessors;
  gltf["bufferViews"] = views;
  gltf["buffers"] = {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64}}};
  return gltf.dump();
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Every failure: one line on stderr starting with the code, the given exit status, no output file.
void expectFailure(const CliResult& result, const std::string& code, int exit_code, const std::string& output) {
  INFO("stderr: " << result.err);
  CHECK(result.exit_code == exit_code);
  CHECK(result.err.rfind(code + " ", 0) == 0);
  CHECK(lineCount(result.err) == 1);
  CHECK_FALSE(fileExists(output));
  // Nor a temporary file beside it.
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(output).parent_path()))
    CHECK(entry.path().filename().string().find("rigbake-tmp") == std::string::npos);
}

}  // namespace

TEST_CASE("cli: bad inputs give one clear line, a stable code, an exit status and no output") {
  TempDir dir;
  const std::string out = dir / "muscles.json";

  SECTION("missing file") {
    CliResult r = runCli("place " + (dir / "nope.glb") + " -o " + out);
    expectFailure(r, "IO_FILE_NOT_FOUND", 2, out);
    CHECK(r.err.find("nope.glb") != std::string::npos);
  }
  SECTION("not a glTF") {
    writeText(dir / "notes.glb", "these are not the bytes you are looking for");
    expectFailure(runCli("place " + (dir / "notes.glb") + " -o " + out), "GLTF_PARSE_FAILED", 3, out);
  }
  SECTION("truncated GLB") {
    std::string glb = slurp(sampleGlbPathForCli());
    writeText(dir / "cut.glb", glb.substr(0, glb.size() / 2));
    CliResult r = runCli("place " + (dir / "cut.glb") + " -o " + out);
    expectFailure(r, "GLTF_PARSE_FAILED", 3, out);
    CHECK(r.err.find("cut.glb") != std::string::npos);
    // The lengths are named, not tinygltf's "Invalid glTF binary.".
    CHECK(r.err.find("truncated GLB: its header gives " + std::to_string(glb.size()) + " bytes, the file has " +
                     std::to_string(glb.size() / 2)) != std::string::npos);
  }
  SECTION("GLB container: short header, other version, chunk past the end") {
    const std::string glb = slurp(sampleGlbPathForCli());
    auto withWord = [](std::string bytes, size_t at, uint32_t value) {
      std::memcpy(&bytes[at], &value, sizeof(value));
      return bytes;
    };
    uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, sizeof(json_length));
    const std::vector<std::pair<std::string, std::string>> cases = {
        {glb.substr(0, 10), "truncated GLB: 10 bytes, shorter than its 12-byte header"},
        {withWord(glb, 4, 1), "GLB version 1 (rigbake reads glTF 2.0, GLB version 2)"},
        {withWord(glb, 12, static_cast<uint32_t>(glb.size())),
         "truncated GLB: its JSON chunk ends at byte " + std::to_string(20 + glb.size()) + " of " + std::to_string(glb.size())},
        {withWord(glb, 20 + json_length, static_cast<uint32_t>(glb.size())), "truncated GLB: its second chunk ends at byte"},
    };
    for (const auto& [bytes, message] : cases) {
      INFO(message);
      writeText(dir / "bad.glb", bytes);
      CliResult r = runCli("bake " + (dir / "bad.glb") + " -o " + (dir / "bad_out.glb"));
      expectFailure(r, "GLTF_PARSE_FAILED", 3, dir / "bad_out.glb");
      CHECK(r.err.find("bad.glb: " + message) != std::string::npos);
    }
  }
  SECTION("glTF without a skin") {
    writeText(dir / "static.gltf", tinyGltf(0));
    expectFailure(runCli("place " + (dir / "static.gltf") + " -o " + out), "GLTF_NO_SKIN", 3, out);
  }
  SECTION("skeleton without the needed joints names the landmark and the names tried") {
    writeText(dir / "stick.gltf", tinyGltf(3));
    CliResult r = runCli("place " + (dir / "stick.gltf") + " -o " + out);
    expectFailure(r, "LANDMARK_UNRESOLVED", 3, out);
    CHECK(r.err.find("landmark '") != std::string::npos);
    CHECK(r.err.find("tried") != std::string::npos);
  }
  SECTION("malformed preset names the JSON pointer") {
    std::string preset = slurp(sourceDir() + "/presets/muscles/gow_biped.json");
    size_t at = preset.find("\"compression\": 0.5", preset.find("\"name\": \"LatissimusDorsi\""));
    REQUIRE(at != std::string::npos);
    preset.replace(at, std::string("\"compression\": 0.5").size(), "\"compresion\": 0.5");
    writeText(dir / "typo.json", preset);
    CliResult r = runCli("place " + sampleGlbPathForCli() + " --preset " + (dir / "typo.json") + " -o " + out);
    expectFailure(r, "PRESET_INVALID", 3, out);
    CHECK(r.err.find("typo.json#/muscles/3/compresion") != std::string::npos);
  }
  SECTION("a corrective without carriers, and a muscle with them, name the JSON pointer") {
    std::string preset = slurp(sourceDir() + "/presets/muscles/gow_biped.json");
    const std::string carriers = "\"carriers\": [\"chest\", \"spine_t12\", \"clavicle\", \"scapula\", \"upper_arm\"],";
    size_t at = preset.find(carriers);
    REQUIRE(at != std::string::npos);
    std::string without = preset;
    without.erase(at, carriers.size());
    writeText(dir / "carrierless.json", without);
    CliResult r = runCli("place " + sampleGlbPathForCli() + " --preset " + (dir / "carrierless.json") + " -o " + out);
    expectFailure(r, "PRESET_INVALID", 3, out);
    CHECK(r.err.find("carrierless.json#/muscles/14: missing required key 'carriers'") != std::string::npos);
    std::string muscle = preset;
    const std::string bicep = "\"name\": \"Bicep\",";
    size_t b = muscle.find(bicep);
    REQUIRE(b != std::string::npos);
    muscle.insert(b + bicep.size(), " \"carriers\": [\"upper_arm\"],");
    writeText(dir / "carrying.json", muscle);
    r = runCli("place " + sampleGlbPathForCli() + " --preset " + (dir / "carrying.json") + " -o " + out);
    expectFailure(r, "PRESET_INVALID", 3, out);
    CHECK(r.err.find("carrying.json#/muscles/8/carriers") != std::string::npos);
    CHECK(r.err.find("only a corrective names carriers") != std::string::npos);
  }
  SECTION("preset that is not JSON") {
    writeText(dir / "broken.json", "{\"muscles\": [");
    CliResult r = runCli("place " + sampleGlbPathForCli() + " --preset " + (dir / "broken.json") + " -o " + out);
    expectFailure(r, "JSON_PARSE_FAILED", 3, out);
  }
  SECTION("JSON with a number no double holds") {
    // nlohmann reports it as out_of_range, not parse_error: it used to escape as INTERNAL, exit 5.
    writeText(dir / "huge.json", "{\"muscles\": [1e999]}");
    CliResult r = runCli("place " + sampleGlbPathForCli() + " --preset " + (dir / "huge.json") + " -o " + out);
    expectFailure(r, "JSON_PARSE_FAILED", 3, out);
    CHECK(r.err.find("number overflow parsing '1e999'") != std::string::npos);
  }
  SECTION("unknown naming map") {
    CliResult r = runCli("landmarks " + sampleGlbPathForCli() + " --map nosuchmap");
    CHECK(r.exit_code == 3);
    CHECK(r.err.rfind("MAP_NOT_FOUND ", 0) == 0);
  }
  SECTION("usage errors") {
    CliResult r = runCli("place " + sampleGlbPathForCli() + " -o " + out + " --side middle");
    CHECK(r.exit_code == 1);
    CHECK(lineCount(r.err) == 1);
    CHECK_FALSE(fileExists(out));
  }
}

TEST_CASE("cli: place writes byte-identical JSON on every run") {
  TempDir dir;
  for (const std::string& path : {sampleGlbPathForCli(), requireAsset("CesiumMan.glb")}) {
    if (path.empty()) continue;
    CliResult a = runCli("place " + path + " -o " + (dir / "a.json"));
    CliResult b = runCli("place " + path + " -o " + (dir / "b.json"));
    REQUIRE(a.exit_code == 0);
    REQUIRE(b.exit_code == 0);
    CHECK(slurp(dir / "a.json") == slurp(dir / "b.json"));
    CHECK(slurp(dir / "a.json").size() > 10000);
  }
}

// The suite's last ctest validates every model the cases wrote from the copies RIGBAKE_KEEP_OUTPUTS
// makes (tests/validate_suite_outputs.js): the copies must be made, whole, and only of models.
TEST_CASE("cli: RIGBAKE_KEEP_OUTPUTS copies every model a run writes, and nothing else") {
  TempDir dir, kept;
  const std::string environment = "RIGBAKE_KEEP_OUTPUTS=" + ext::shellQuote(kept.path.string());
  REQUIRE(runCli("sample -o " + (dir / "sample.glb"), environment).exit_code == 0);
  REQUIRE(runCli("place " + (dir / "sample.glb") + " -o " + (dir / "muscles.json"), environment).exit_code == 0);
  REQUIRE(runCli("bake " + (dir / "sample.glb") + " --muscles " + (dir / "muscles.json") + " -o " + (dir / "baked.gltf") +
                     " --stats " + (dir / "stats.json"),
                 environment).exit_code == 0);
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(kept.path)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
    return a.substr(a.rfind('-')) < b.substr(b.rfind('-'));
  });
  REQUIRE(names.size() == 2);
  CHECK(names[0].size() > std::string("-0-baked.gltf").size());
  CHECK(names[0].substr(names[0].rfind('-')) == "-baked.gltf");
  CHECK(names[1].substr(names[1].rfind('-')) == "-sample.glb");
  CHECK(slurp(kept / names[0]) == slurp(dir / "baked.gltf"));
  CHECK(slurp(kept / names[1]) == slurp(dir / "sample.glb"));
}

TEST_CASE("cli: landmarks --json follows the documented contract") {
  CliResult r = runCli("landmarks --json " + sampleGlbPathForCli());
  REQUIRE(r.exit_code == 0);
  nlohmann::json j = nlohmann::json::parse(r.out);
  CHECK(j["units"] == "m");
  CHECK(j["character"].get<std::string>().find(".glb") != std::string::npos);
  CHECK(j["body"]["height"].get<double>() == Approx(1.8).margin(1e-9));
  CHECK(j["body"]["up"].size() == 3);
  for (const char* name : {"head", "neck", "chest", "spine_t12", "spine_l5", "pelvis"}) {
    INFO(name);
    REQUIRE(j["landmarks"].contains(name));
    CHECK(j["landmarks"][name]["position"].size() == 3);
  }
  for (const char* base : {"clavicle", "acromion", "scapula", "upper_arm", "upper_arm_twist", "forearm",
                           "forearm_twist", "hand"}) {
    for (const char* side : {"_l", "_r"}) {
      std::string name = std::string(base) + side;
      INFO(name);
      REQUIRE(j["landmarks"].contains(name));
      CHECK(j["landmarks"][name]["joint"].is_string());
      CHECK(j["landmarks"][name]["derived"].is_null());
    }
  }
  std::string cesium = requireAsset("CesiumMan.glb");
  if (!cesium.empty()) {
    nlohmann::json c = nlohmann::json::parse(runCli("landmarks --json " + cesium).out);
    CHECK(c["landmarks"]["acromion_l"]["joint"].is_null());
    CHECK(c["landmarks"]["acromion_l"]["derived"].get<std::string>().find("lerp(clavicle_l") != std::string::npos);
    CHECK(c["landmarks"]["upper_arm_l"]["source"] == "structure");
    CHECK(c["landmarks"]["upper_arm_twist_l"].is_null());
  }
}

TEST_CASE("cli: errors lists every code with its exit status") {
  CliResult r = runCli("errors");
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find("LANDMARK_UNRESOLVED\t3") != std::string::npos);
  CHECK(r.out.find("IO_FILE_NOT_FOUND\t2") != std::string::npos);
  CHECK(r.out.find("BUILD_FAILED\t4") != std::string::npos);
  CHECK(r.out.find("USAGE\t1") != std::string::npos);
  // The docs' table has one row per code of core/error.h's table, in its order, with its exit status.
  std::string doc = slurp(sourceDir() + "/docs/errors.md");
  std::vector<std::string> documented, printed;
  std::istringstream doc_lines(doc.substr(doc.find("\n## Codes\n") + 1));
  for (std::string line; std::getline(doc_lines, line);) {
    if (line.rfind("## ", 0) == 0 && line != "## Codes") break;  // the Blender add-on's codes follow
    if (line.rfind("| `", 0) != 0) continue;
    const size_t code_end = line.find("` | ");
    const size_t exit_end = line.find(" |", code_end + 4);
    documented.push_back(line.substr(3, code_end - 3) + "\t" + line.substr(code_end + 4, exit_end - code_end - 4));
  }
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) printed.push_back(line.substr(0, line.find('\t', line.find('\t') + 1)));
  CHECK(printed.size() == std::size(kErrorCodes));
  CHECK(documented == printed);
}

TEST_CASE("errors: one printable line of valid UTF-8, whatever bytes the input put into the message") {
  using rigbake::printableLine;
  CHECK(printableLine("plain ASCII, kept") == "plain ASCII, kept");
  // Well-formed UTF-8 stays: two-, three- and four-byte sequences.
  CHECK(printableLine("R\xC3\xA9sum\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x92\xAA") == "R\xC3\xA9sum\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x92\xAA");
  // A stray byte, a cut sequence, an overlong form, a surrogate, control characters: escaped.
  CHECK(printableLine("last read: '\"COLLADA\xA3'") == "last read: '\"COLLADA\\xA3'");
  CHECK(printableLine("cut \xE2\x82") == "cut \\xE2\\x82");
  CHECK(printableLine("\xC0\xAF") == "\\xC0\\xAF");
  CHECK(printableLine("\xED\xA0\x80") == "\\xED\\xA0\\x80");
  CHECK(printableLine("two\nlines\tand\x7F") == "two\\x0Alines\\x09and\\x7F");
  const rigbake::Error error(errc::GLTF_PARSE_FAILED, "bad\x85.glb", "read '\xFF'\n");
  CHECK(std::string(error.what()) == "GLTF_PARSE_FAILED bad\\x85.glb: read '\\xFF'\\x0A");
  CHECK(error.where() == "bad\\x85.glb");
  // Through the CLI: the JSON parser quotes the bad byte it read.
  TempDir dir;
  std::string glb = slurp(sampleGlbPathForCli());
  const size_t at = glb.find("\"asset\"");
  REQUIRE(at != std::string::npos);
  glb[at + 1] = '\xA3';
  writeText(dir / "garbled.glb", glb);
  CliResult r = runCli("landmarks " + (dir / "garbled.glb"));
  CHECK(r.exit_code == 3);
  CHECK(r.err.find("GLTF_PARSE_FAILED") == 0);
  CHECK(r.err.find("\\xA3") != std::string::npos);
  CHECK(r.err.find('\xA3') == std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("cli: a file name that is not UTF-8 is echoed into JSON with U+FFFD, not an INTERNAL error") {
  // Linux file names are bytes; rigbake echoes them as "input", "output" and "character", and the JSON
  // writer threw on them after the work was done (exit 5, no stats file).
  TempDir dir;
  const std::string input = dir / "hero\xFF.glb";
  writeText(input, slurp(sampleGlbPathForCli()));
  CliResult landmarks = runCli("landmarks " + input + " --json");
  CHECK(landmarks.exit_code == 0);
  CHECK(nlohmann::json::parse(landmarks.out).is_object());
  CliResult place = runCli("place " + input + " -o " + (dir / "m\xFF.json") + " --json");
  REQUIRE(place.exit_code == 0);
  CHECK(nlohmann::json::parse(place.out)["character"] == "hero\xEF\xBF\xBD.glb");
  CHECK(nlohmann::json::parse(slurp(dir / "m\xFF.json")).is_object());
  CliResult bake = runCli("bake " + input + " --response keep -o " + (dir / "out\xFF.glb") + " --stats " + (dir / "stats\xFF.json"));
  INFO(bake.err);
  CHECK(bake.exit_code == 0);
  CHECK(nlohmann::json::parse(slurp(dir / "stats\xFF.json"))["output"] == "out\xEF\xBF\xBD.glb");
}

TEST_CASE("cli: a preset naming an unknown landmark says which and where") {
  TempDir dir;
  std::string preset = slurp(sourceDir() + "/presets/muscles/gow_biped.json");
  size_t at = preset.find("\"origin_attach\": \"scapula\"");
  REQUIRE(at != std::string::npos);
  preset.replace(at, std::string("\"origin_attach\": \"scapula\"").size(), "\"origin_attach\": \"shoulderblade\"");
  writeText(dir / "unknown.json", preset);
  CliResult r = runCli("place " + sampleGlbPathForCli() + " --preset " + (dir / "unknown.json") + " -o " + (dir / "m.json"));
  expectFailure(r, "PRESET_LANDMARK_UNKNOWN", 3, dir / "m.json");
  CHECK(r.err.find("unknown.json#/muscles/4/origin_attach") != std::string::npos);
  CHECK(r.err.find("shoulderblade") != std::string::npos);
}

namespace {

// Names of the entries of `dir`.
std::set<std::string> namesIn(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) names.insert(entry.path().filename().string());
  return names;
}

bool isCharacterDeviceAt(const std::string& path) {
  struct stat status {};
  return ::lstat(path.c_str(), &status) == 0 && S_ISCHR(status.st_mode);
}

bool isFifoAt(const std::string& path) {
  struct stat status {};
  return ::lstat(path.c_str(), &status) == 0 && S_ISFIFO(status.st_mode);
}

}  // namespace

TEST_CASE("cli: an output that is a device, a FIFO or a directory is refused before any work and stays what it was") {
  TempDir dir;
  // A private /dev/null (tests run as root): if rigbake replaced it, no other program would notice.
  const std::string null = dir / "null", fifo = dir / "fifo", folder = dir / "folder";
  REQUIRE(::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0);
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  std::filesystem::create_directories(folder);
  const std::string sample = ext::shellQuote(sampleGlbPathForCli());
  struct Case {
    std::string args, refused;
  };
  const std::vector<Case> cases = {
      {"sample -o " + ext::shellQuote(null), null},
      {"sample -o " + ext::shellQuote(fifo), fifo},
      {"sample -o " + ext::shellQuote(folder), folder},
      {"place " + sample + " -o " + ext::shellQuote(null), null},
      {"bake " + sample + " -o " + ext::shellQuote(null) + " --stats " + ext::shellQuote(dir / "stats.json"), null},
      {"bake " + sample + " -o " + ext::shellQuote(dir / "a.glb") + " --stats " + ext::shellQuote(fifo), fifo},
      {"bake " + sample + " -o " + ext::shellQuote(dir / "a.glb") + " --packed-out " + ext::shellQuote(null), null},
      {"bake " + sample + " -o " + ext::shellQuote(dir / "a.glb") + " --muscles-out " + ext::shellQuote(folder), folder},
      {"rom " + sample + " -o " + ext::shellQuote(null), null},
  };
  for (const Case& c : cases) {
    const CliResult run = runCli(c.args);
    INFO(c.args << "\n" << run.err);
    CHECK(run.exit_code == 2);
    CHECK(lineCount(run.err) == 1);
    CHECK(run.err.rfind("IO_OUTPUT_NOT_REGULAR " + c.refused + ":", 0) == 0);
    CHECK(isCharacterDeviceAt(null));
    CHECK(isFifoAt(fifo));
    CHECK(std::filesystem::is_directory(folder));
    CHECK(namesIn(dir.path.string()) == std::set<std::string>{"fifo", "folder", "null"});
    CHECK(std::filesystem::is_empty(folder));
  }
  // /proc/self/fd/1 when stdout is a pipe: a link whose text names nothing, to something not a file.
  const ext::CommandResult piped =
      ext::runCommand("cd " + ext::shellQuote(dir.path.string()) + " && " + std::string(rigbake::test::kRigbakeCli) + " sample -o /proc/self/fd/1 2>&1 | cat");
  INFO(piped.output);
  CHECK(piped.output.rfind("IO_OUTPUT_NOT_REGULAR /proc/self/fd/1: exists and is a FIFO", 0) == 0);
  CHECK(namesIn(dir.path.string()) == std::set<std::string>{"fifo", "folder", "null"});
}

TEST_CASE("cli: an output that is a symbolic link writes the file it names and keeps the link") {
  TempDir dir;
  std::filesystem::create_directories(dir / "real");
  std::ofstream(dir / "real/sample.glb") << "old";
  std::filesystem::create_symlink("real/sample.glb", dir / "link.glb");
  const CliResult run = runCli("sample -o " + ext::shellQuote(dir / "link.glb"));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  CHECK(std::filesystem::is_symlink(dir / "link.glb"));
  CHECK(slurp(dir / "real/sample.glb") == slurp(sampleGlbPathForCli()));
  CHECK(namesIn(dir / "real") == std::set<std::string>{"sample.glb"});
}

TEST_CASE("cli: an empty output path is USAGE, not a file with no name") {
  for (const std::string& args : {std::string("sample -o ''"), "place " + ext::shellQuote(sampleGlbPathForCli()) + " -o ''",
                                  "bake " + ext::shellQuote(sampleGlbPathForCli()) + " -o ''"}) {
    const CliResult run = runCli(args);
    INFO(args << "\n" << run.err);
    CHECK(run.exit_code == 1);
    CHECK(lineCount(run.err) == 1);
    CHECK(run.err.rfind("USAGE -o:", 0) == 0);
  }
}

TEST_CASE("cli: a device as an input is one line at once, an input past its limit is INPUT_TOO_LARGE, a pipe is read") {
  // Before issue 34, /dev/zero as any input grew memory until the run was killed or ended INTERNAL.
  TempDir dir;
  const std::string sample = ext::shellQuote(sampleGlbPathForCli());
  const std::vector<std::string> device_inputs = {
      "bake /dev/zero -o " + (dir / "a.glb"),
      "place " + sample + " --preset /dev/zero -o " + (dir / "m.json"),
      "bake " + sample + " --muscles /dev/zero -o " + (dir / "a.glb"),
      "landmarks " + sample + " --map /dev/zero",
  };
  for (const std::string& args : device_inputs) {
    const auto start = std::chrono::steady_clock::now();
    const CliResult run = runCli(args);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    INFO(args << "\n" << run.err);
    // Invalid input (3), as INPUT_TOO_LARGE is: nothing to read, whatever the disk does.
    CHECK(run.exit_code == 3);
    CHECK(lineCount(run.err) == 1);
    CHECK(run.err.rfind("IO_INPUT_NOT_REGULAR /dev/zero: is a character device", 0) == 0);
    // Under a second (the issue's bound); the sanitizer pass's CLI starts several times slower.
    CHECK(seconds < (std::getenv("ASAN_OPTIONS") ? 3.0 : 1.0));
  }
  // A 65 MiB muscle file (sparse: no disk is spent) is past the 64 MiB a JSON input may have.
  { std::ofstream(dir / "huge.json") << "{"; }
  std::filesystem::resize_file(dir / "huge.json", (std::uintmax_t{65} << 20));
  const CliResult huge = runCli("bake " + sample + " --muscles " + (dir / "huge.json") + " -o " + (dir / "a.glb"));
  INFO(huge.err);
  CHECK(huge.exit_code == 3);
  CHECK(lineCount(huge.err) == 1);
  CHECK(huge.err.rfind("INPUT_TOO_LARGE " + (dir / "huge.json") + ": is 68157440 bytes", 0) == 0);
  CHECK(namesIn(dir.path.string()) == std::set<std::string>{"huge.json"});
  // A preset through a pipe is still read, up to the same limit.
  const std::string preset = ext::shellQuote(sourceDir() + "/presets/muscles/gow_biped.json");
  REQUIRE(runCli("place " + sample + " --preset " + preset + " -o " + (dir / "by_path.json")).exit_code == 0);
  const ext::CommandResult piped = ext::runCommand("cat " + preset + " | " + std::string(rigbake::test::kRigbakeCli) + " place " + sample +
                                                   " --preset /dev/stdin -o " + (dir / "by_pipe.json") + " 2>&1");
  INFO(piped.output);
  CHECK(piped.exit_code == 0);
  CHECK(slurp(dir / "by_pipe.json") == slurp(dir / "by_path.json"));
}

namespace {

// `glb` with its JSON chunk replaced by `json` (the binary chunk kept as is).
std::string glbWithJson(const std::string& glb, const nlohmann::json& json) {
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  std::string text = json.dump();
  while (text.size() % 4 != 0) text += ' ';
  auto word = [](std::uint32_t value) { return std::string(reinterpret_cast<const char*>(&value), 4); };
  const std::string rest = glb.substr(20 + json_length);
  const std::string body = word(static_cast<std::uint32_t>(text.size())) + "JSON" + text + rest;
  return "glTF" + word(2) + word(static_cast<std::uint32_t>(12 + body.size())) + body;
}

}  // namespace

// 3ds Max's Biped with Triangle Neck on and Triangle Pelvis off hangs the clavicles from the neck and the
// thighs from the first spine joint. `landmarks` says which joints the muscles re-hang, and from what.
TEST_CASE("cli landmarks: a Biped-style hierarchy names the clavicles and thighs the muscles re-hang") {
  TempDir dir;
  nlohmann::json json = glbJson(slurp(sampleGlbPathForCli()));
  nlohmann::json& nodes = json["nodes"];
  const auto node = [&](const std::string& name) {
    for (size_t n = 0; n < nodes.size(); ++n)
      if (nodes[n]["name"] == name) return static_cast<int>(n);
    FAIL("no node " << name);
    return -1;
  };
  // Moves `child` from its parent's children to `sibling`'s, keeping its world bind pose: the sample's
  // joints carry translations and at most a half turn about +Y (the neck), which is its own inverse.
  const auto rehang = [&](const std::string& child, const std::string& sibling) {
    const int c = node(child), s = node(sibling);
    for (nlohmann::json& n : nodes) {
      if (!n.contains("children")) continue;
      nlohmann::json& children = n["children"];
      children.erase(std::remove(children.begin(), children.end(), c), children.end());
    }
    nodes[s]["children"].push_back(c);
    nlohmann::json& t = nodes[c]["translation"];
    const nlohmann::json& u = nodes[s]["translation"];
    Eigen::Vector3d local(t[0].get<double>() - u[0].get<double>(), t[1].get<double>() - u[1].get<double>(),
                          t[2].get<double>() - u[2].get<double>());
    if (nodes[s].contains("rotation")) {
      REQUIRE(nodes[s]["rotation"] == nlohmann::json::array({0.0, 1.0, 0.0, 0.0}));
      local = Eigen::Vector3d(-local.x(), local.y(), -local.z());
      nodes[c]["rotation"] = {0.0, 1.0, 0.0, 0.0};
    }
    t = {local.x(), local.y(), local.z()};
  };
  rehang("JOLeftClavicle1", "JONeck1");
  rehang("JORightClavicle1", "JONeck1");
  rehang("JOLeftUpLeg1", "JOBack1");
  rehang("JORightUpLeg1", "JOBack1");
  std::ofstream(dir / "biped.glb", std::ios::binary) << glbWithJson(slurp(sampleGlbPathForCli()), json);
  const CliResult run = runCli("landmarks " + (dir / "biped.glb") + " --json");
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json out = nlohmann::json::parse(run.out);
  const nlohmann::json expected = nlohmann::json::parse(R"([
    {"joint": "JOLeftClavicle1", "rig_parent": "JONeck1", "body_parent": "JOBack3"},
    {"joint": "JORightClavicle1", "rig_parent": "JONeck1", "body_parent": "JOBack3"},
    {"joint": "JOLeftUpLeg1", "rig_parent": "JOBack1", "body_parent": "JOPelvis1"},
    {"joint": "JORightUpLeg1", "rig_parent": "JOBack1", "body_parent": "JOPelvis1"}])");
  std::set<std::string> got, want;
  for (const nlohmann::json& entry : out["rehung"]) got.insert(entry.dump());
  for (const nlohmann::json& entry : expected) want.insert(entry.dump());
  CHECK(got == want);
  // The world bind pose is the sample's: the landmarks lie where they did.
  const nlohmann::json sample = nlohmann::json::parse(runCli("landmarks " + sampleGlbPathForCli() + " --json").out);
  CHECK(sample["rehung"].empty());
  for (const char* name : {"clavicle_l", "upper_leg_r", "acromion_l", "hand_r"})
    for (int k = 0; k < 3; ++k)
      CHECK(std::abs(out["landmarks"][name]["position"][k].get<double>() - sample["landmarks"][name]["position"][k].get<double>()) < 1e-6);
  const CliResult text = runCli("landmarks " + (dir / "biped.glb"));
  CHECK(text.out.find("the muscles take JOLeftClavicle1 as hanging from JOBack3, not from the rig's JONeck1") != std::string::npos);
}

TEST_CASE("cli: a skeleton whose root joint has a zero scale is GLTF_SKIN_INVALID, not NaN or an assertion") {
  // The bind transforms then have no axes: the pose code asserted (sanitizer build) or wrote NaN.
  TempDir dir;
  const std::string glb = slurp(sampleGlbPathForCli());
  nlohmann::json json = glbJson(glb);
  std::set<int> children;
  for (const auto& node : json["nodes"])
    if (node.contains("children")) children.insert(node["children"].begin(), node["children"].end());
  int root = -1;
  for (const auto& joint : json["skins"][0]["joints"])
    if (!children.count(joint.get<int>())) root = joint.get<int>();
  REQUIRE(root >= 0);
  json["nodes"][root].erase("matrix");
  json["nodes"][root]["scale"] = {0.0, 0.0, 0.0};
  std::ofstream(dir / "flat.glb", std::ios::binary) << glbWithJson(glb, json);
  const CliResult run = runCli("bake " + (dir / "flat.glb") + " -o " + (dir / "baked.glb"));
  INFO(run.err);
  CHECK(run.exit_code == 3);
  CHECK(lineCount(run.err) == 1);
  CHECK(run.err.rfind("GLTF_SKIN_INVALID " + (dir / "flat.glb") + ":", 0) == 0);
  CHECK(run.err.find("degenerate") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "baked.glb"));
}
