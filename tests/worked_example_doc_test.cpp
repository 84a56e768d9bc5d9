// docs/extensions/RIGBAKE_muscle_rig.md's "Example" regenerated: the doc's two commands are run, and every
// number the section prints (the extension's JSON for LeftBicep and its jiggle, the part and jiggle
// counts, the node names, and the worked evaluation at ElbowFlexion 1.0 s) is computed from that bake
// and must equal the printed one to the precision printed. A bake that fits other curves fails here
// until the doc is updated, so the example an engine programmer checks an evaluator against cannot go
// stale.
#include <nlohmann/json.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "glb_support.h"
#include "pipeline/checks.h"
#include "pipeline/pose.h"
#include "runtime/muscle_rig.h"

namespace rigbake {
namespace worked_example_doc_test {

using test::runCli;
using test::slurp;

constexpr double kPi = 3.14159265358979323846;

// The doc's "## Example" section, up to the next "## " heading.
std::string exampleSection() {
  const std::string doc = slurp(test::sourceDir() + "/docs/extensions/RIGBAKE_muscle_rig.md");
  const size_t begin = doc.find("\n## Example\n");
  REQUIRE(begin != std::string::npos);
  const size_t end = doc.find("\n## ", begin + 1);
  return doc.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

// The body of the first fenced block of `language` in `text`.
std::string fencedBlock(const std::string& text, const std::string& language) {
  const std::string open = "```" + language + "\n";
  const size_t begin = text.find(open);
  REQUIRE(begin != std::string::npos);
  const size_t end = text.find("\n```", begin + open.size());
  REQUIRE(end != std::string::npos);
  return text.substr(begin + open.size(), end - begin - open.size() + 1);
}

// A printed number holds the value it stands for when the value, rounded to the printed decimals,
// prints the same: |value - printed| <= half a unit of the last printed digit (plus rounding slack).
double printedTolerance(const std::string& token) {
  const size_t dot = token.find('.');
  const int decimals = dot == std::string::npos ? 0 : static_cast<int>(token.size() - dot - 1);
  return 0.5 * std::pow(10.0, -decimals) + 1e-12;
}

// Every number of the doc's JSON against the bake's, walking both. The doc's JSON is parsed as text
// first to keep each number's printed digits (nlohmann would keep only the double).
void compareJson(const nlohmann::json& doc, const nlohmann::json& baked, const std::string& where, int* numbers) {
  INFO(where);
  if (doc.is_object()) {
    REQUIRE(baked.is_object());
    // The same members: a property the bake writes that the doc leaves out is a stale example too.
    std::vector<std::string> doc_keys, baked_keys;
    for (auto it = doc.begin(); it != doc.end(); ++it) doc_keys.push_back(it.key());
    for (auto it = baked.begin(); it != baked.end(); ++it) baked_keys.push_back(it.key());
    CHECK(doc_keys == baked_keys);
    for (auto it = doc.begin(); it != doc.end(); ++it)
      if (baked.contains(it.key())) compareJson(it.value(), baked[it.key()], where + "/" + it.key(), numbers);
  } else if (doc.is_array()) {
    REQUIRE(baked.is_array());
    REQUIRE(doc.size() == baked.size());
    for (size_t k = 0; k < doc.size(); ++k) compareJson(doc[k], baked[k], where + "/" + std::to_string(k), numbers);
  } else if (doc.is_number_integer() && baked.is_number_integer()) {
    CHECK(doc.get<long long>() == baked.get<long long>());
    ++*numbers;
  } else if (doc.is_number()) {
    REQUIRE(baked.is_number());
    // The doc prints 4 decimals and drops trailing zeros (0.02 for 0.0200): hold it to 4 decimals.
    const double printed = doc.get<double>(), value = baked.get<double>();
    CHECK(std::abs(value - printed) <= 0.5e-4 + 1e-12);
    CHECK(std::abs(printed * 1e4 - std::round(printed * 1e4)) < 1e-6);  // no more than 4 decimals
    ++*numbers;
  } else {
    CHECK(doc == baked);
  }
}

// The worked evaluation's block: lines "name: token token ...".
std::map<std::string, std::vector<std::string>> workedLines(const std::string& block) {
  std::map<std::string, std::vector<std::string>> lines;
  std::istringstream in(block);
  std::string line;
  while (std::getline(in, line)) {
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::istringstream tokens(line.substr(colon + 1));
    std::vector<std::string>& out = lines[line.substr(0, colon)];
    for (std::string token; tokens >> token;) out.push_back(token);
  }
  return lines;
}

const nlohmann::json& named(const nlohmann::json& array, const std::string& name) {
  for (const nlohmann::json& item : array)
    if (item["name"] == name) return item;
  FAIL("no " << name);
  return array;
}

TEST_CASE("extension doc: the example's JSON, counts, nodes and worked evaluation are those of a bake by the doc's commands") {
  test::TempDir dir;
  const std::string section = exampleSection();
  // The commands as the doc prints them, with the temporary directory's paths.
  const std::string commands = fencedBlock(section, "sh");
  REQUIRE(commands.find("rigbake sample -o mannequin.glb\n") != std::string::npos);
  const std::string bake_flags = "--helper-joints --jiggle biceps";
  REQUIRE(commands.find("rigbake bake mannequin.glb " + bake_flags + " -o baked.glb\n") != std::string::npos);
  const std::string mannequin = dir / "mannequin.glb", baked = dir / "baked.glb";
  REQUIRE(runCli("sample -o " + mannequin).exit_code == 0);
  const test::CliResult bake = runCli("bake " + mannequin + " " + bake_flags + " -o " + baked);
  INFO(bake.err);
  REQUIRE(bake.exit_code == 0);

  // The extension's JSON: every number of LeftBicep and its jiggle.
  const nlohmann::json gltf = test::glbJson(slurp(baked));
  const nlohmann::json& extension = gltf["extensions"]["RIGBAKE_muscle_rig"];
  const nlohmann::json doc = nlohmann::json::parse(fencedBlock(section, "json"));
  REQUIRE(doc["muscles"].size() == 1);
  REQUIRE(doc["jiggles"].size() == 1);
  nlohmann::json expected = extension;
  expected["muscles"] = nlohmann::json::array({named(extension["muscles"], doc["muscles"][0]["name"].get<std::string>())});
  expected["jiggles"] = nlohmann::json::array({named(extension["jiggles"], doc["jiggles"][0]["name"].get<std::string>())});
  int numbers = 0;
  compareJson(doc, expected, "", &numbers);

  // "the file has 38 parts, the 28 muscles and 10 armpit correctives, and 2 jiggles in all"
  std::smatch counts;
  const std::string flat = std::regex_replace(section, std::regex("\\s+"), " ");
  REQUIRE(std::regex_search(flat, counts, std::regex("the file has (\\d+) parts, the (\\d+) muscles and (\\d+) armpit correctives, and (\\d+) jiggles")));
  int correctives = 0;
  for (const nlohmann::json& m : extension["muscles"]) correctives += m.value("kind", "muscle") == "corrective";
  CHECK(std::stoi(counts[1]) == static_cast<int>(extension["muscles"].size()));
  CHECK(std::stoi(counts[2]) == static_cast<int>(extension["muscles"].size()) - correctives);
  CHECK(std::stoi(counts[3]) == correctives);
  CHECK(std::stoi(counts[4]) == static_cast<int>(extension["jiggles"].size()));
  // "`LeftUpperArm1Twist0` (node 10)": each named node is that node of the file.
  int nodes_named = 0;
  const std::regex node_named("`(\\w+)` \\(node (\\d+)\\)");
  for (std::sregex_iterator it(flat.cbegin(), flat.cend(), node_named), end; it != end; ++it, ++nodes_named)
    CHECK(gltf["nodes"][std::stoi((*it)[2])]["name"] == (*it)[1].str());
  CHECK(nodes_named == 2);

  // The worked evaluation, from the file's own channels through the double runtime.
  const LoadedCharacter loaded = loadCharacter(baked);
  const BakedFileData file = readBakedFileData(loaded);
  REQUIRE(file.rig.present);
  REQUIRE(file.rig.problems.empty());
  const std::map<std::string, std::vector<std::string>> printed = workedLines(fencedBlock(section, "text"));
  REQUIRE(printed.count("clip"));
  REQUIRE(printed.count("muscle"));
  const std::vector<std::string>& clip_line = printed.at("clip");
  REQUIRE(clip_line.size() == 2);
  const Skeleton& skeleton = loaded.character.skeleton;
  const auto clip = std::find_if(loaded.character.clips.begin(), loaded.character.clips.end(),
                                 [&](const Clip& c) { return c.name == clip_line[0]; });
  REQUIRE(clip != loaded.character.clips.end());
  const double time = std::stod(clip_line[1]);
  const auto name = std::find(file.rig.names.begin(), file.rig.names.end(), printed.at("muscle").at(0));
  REQUIRE(name != file.rig.names.end());
  const size_t muscle = static_cast<size_t>(name - file.rig.names.begin());
  const runtime::MuscleRig<double>& rig = file.rig.rig;

  // The drivers and skinned matrices of every muscle at one time of the clip.
  struct Evaluated {
    std::vector<runtime::MuscleDrivers<double>> drivers;
    std::vector<double> skinned, joints;
  };
  auto evaluate = [&](double t) {
    const Pose pose = sampleClip(skeleton, *clip, t);
    Evaluated e;
    e.joints.resize(16 * static_cast<size_t>(skeleton.size()));
    for (int j = 0; j < skeleton.size(); ++j) {
      const Eigen::Matrix4d m = pose.world[j].matrix();
      std::copy(m.data(), m.data() + 16, e.joints.begin() + 16 * j);
    }
    e.drivers.resize(rig.muscles.size());
    e.skinned.resize(16 * rig.muscles.size());
    runtime::MuscleRigJob<double> job;
    job.rig = &rig;
    job.joint_matrices = runtime::Span<const double>(e.joints.data(), e.joints.size());
    job.skinned_matrices = e.skinned;
    job.drivers = e.drivers;
    REQUIRE(job.Run());
    return e;
  };
  const Evaluated at = evaluate(time);
  const runtime::MuscleDrivers<double>& drivers = at.drivers[muscle];
  // "where LeftBicep is shortest": no key time of the clip gives a smaller ratio.
  const std::vector<double> keys = sampleTimes(*clip, 0.0);
  for (double t : keys) CHECK(evaluate(t).drivers[muscle].ratio >= drivers.ratio);
  // "(key 30 of its 61, 30 keys/s)"
  std::smatch key_line;
  REQUIRE(std::regex_search(flat, key_line, std::regex("\\(key (\\d+) of its (\\d+), (\\d+) keys/s\\)")));
  REQUIRE(keys.size() == std::stoul(key_line[2]));
  CHECK(std::abs(keys[std::stoul(key_line[1])] - time) < kSampleTimeTolerance);
  CHECK(std::abs(keys[1] - keys[0] - 1.0 / std::stod(key_line[3])) < kSampleTimeTolerance);
  const runtime::ResponseKey<double> response = runtime::evaluateResponse(rig, rig.muscles[muscle], drivers);
  // Equation 7 as the doc writes it: K'_3 = K_3 + up K_1 + side K_2, K'_1 = s K_1, K'_2 = s K_2.
  Eigen::Matrix4d k = Eigen::Map<const Eigen::Matrix4d>(rig.muscles[muscle].skinned_in_carrier);
  k.col(3).head<3>() += response.up * k.col(1).head<3>() + response.side * k.col(2).head<3>();
  k.col(1) *= response.scale;
  k.col(2) *= response.scale;
  // Equation 8: M = W_c K', which is what the job computed.
  const Eigen::Matrix4d carrier = Eigen::Map<const Eigen::Matrix4d>(at.joints.data() + 16 * rig.muscles[muscle].carrier_joint);
  const Eigen::Matrix4d m = carrier * k;
  const Eigen::Matrix4d job_m = Eigen::Map<const Eigen::Matrix4d>(at.skinned.data() + 16 * muscle);
  CHECK((m - job_m).cwiseAbs().maxCoeff() < 1e-12);

  const std::map<std::string, std::vector<double>> computed = {
      {"r", {drivers.ratio}},
      {"r_c", {drivers.clamped_ratio}},
      {"theta", {drivers.twist}},
      {"up", {response.up}},
      {"side", {response.side}},
      {"s", {response.scale}},
      {"K'_3", {k(0, 3), k(1, 3), k(2, 3)}},
      {"M translation", {m(0, 3), m(1, 3), m(2, 3)}},
      {"M column 0", {m(0, 0), m(1, 0), m(2, 0)}},
      {"M column 1", {m(0, 1), m(1, 1), m(2, 1)}},
      {"M column 2", {m(0, 2), m(1, 2), m(2, 2)}},
  };
  for (const auto& [key, values] : computed) {
    INFO(key);
    REQUIRE(printed.count(key));
    const std::vector<std::string>& tokens = printed.at(key);
    REQUIRE(tokens.size() == values.size());
    for (size_t c = 0; c < values.size(); ++c) {
      INFO(tokens[c] << " printed, " << values[c] << " computed");
      CHECK(tokens[c].find('.') != std::string::npos);  // every number with its decimals, 0 as 0.0000
      CHECK(std::abs(values[c] - std::stod(tokens[c])) <= printedTolerance(tokens[c]));
      ++numbers;
    }
  }
  CHECK(printed.size() == computed.size() + 2);  // clip and muscle besides: no line the test skips
  // The ratio key the doc names sits at this very ratio: the fit put its deepest key where the clips are.
  const runtime::ResponseKey<double>& second = rig.keys[rig.muscles[muscle].ratio_key_begin + 1];
  CHECK(std::abs(second.at - drivers.clamped_ratio) < 1e-8);
  // The prose reading of the curves: "at ratio 0.7862, ... moves 2.0 cm ... and scales by 1.553 ..., and at the
  // compression limit (ratio 0.5 ...) it holds 1.5 cm and 1.414 ... flat within ±0.6975 rad ... swells it
  // by 11 % at −π/2 and 12 % at +π/2".
  std::smatch curve;
  REQUIRE(std::regex_search(flat, curve, std::regex("at ratio ([0-9.]+), the deepest compression the clips reach, the skinned joint "
                                                    "moves ([0-9.]+) cm along its up axis and scales by ([0-9.]+) across the fibre, "
                                                    "less on the way there, and at the compression limit \\(ratio ([0-9.]+), .*?\\) "
                                                    "it holds ([0-9.]+) cm and ([0-9.]+),.*? flat within ±([0-9.]+) rad .*? swells "
                                                    "it by ([0-9]+) % at −π/2 and ([0-9]+) % at \\+π/2")));
  const runtime::RigMuscle<double>& part = rig.muscles[muscle];
  REQUIRE(part.ratio_key_count >= 2);
  REQUIRE(part.twist_key_count == 5);
  const runtime::ResponseKey<double>* ratio_keys = &rig.keys[part.ratio_key_begin];
  const runtime::ResponseKey<double>* twist_keys = &rig.keys[part.twist_key_begin];
  const std::vector<std::pair<double, std::string>> prose = {
      {ratio_keys[1].at, curve[1]}, {100 * ratio_keys[1].up, curve[2]}, {ratio_keys[1].scale, curve[3]},
      {ratio_keys[0].at, curve[4]}, {100 * ratio_keys[0].up, curve[5]}, {ratio_keys[0].scale, curve[6]},
      {twist_keys[3].at, curve[7]}, {-twist_keys[1].at, curve[7]},
      {100 * (twist_keys[0].scale - 1), curve[8]}, {100 * (twist_keys[4].scale - 1), curve[9]}};
  for (const auto& [value, token] : prose) {
    INFO(token << " printed, " << value << " computed");
    CHECK(std::abs(value - std::stod(token)) <= printedTolerance(token));
    ++numbers;
  }
  CHECK(ratio_keys[0].at == part.compression);  // "the compression limit"
  CHECK(std::abs(twist_keys[0].at + kPi / 2) < 1e-4);
  CHECK(std::abs(twist_keys[4].at - kPi / 2) < 1e-4);
  for (int k = 1; k <= 3; ++k) CHECK((twist_keys[k].up == 0 && twist_keys[k].side == 0 && twist_keys[k].scale == 1));  // "flat"

  // "The same bake with `--muscle-motion both` writes the same extension and ... K' as a TRS channel:
  // translation `(0.0286, 0, 0.0475)` ... and scale `(1, 1.5527, 1.5527)`."
  const std::string both = dir / "both.glb";
  REQUIRE(runCli("bake " + mannequin + " " + bake_flags + " --muscle-motion both -o " + both).exit_code == 0);
  CHECK(test::glbJson(slurp(both))["extensions"]["RIGBAKE_muscle_rig"] == extension);
  std::smatch trs;
  REQUIRE(std::regex_search(flat, trs, std::regex("for `(\\w+)` at that time, `K'` as a TRS channel: translation `\\(([^)]*)\\)`.*?scale `\\(([^)]*)\\)`")));
  const LoadedCharacter both_loaded = loadCharacter(both);
  const int skinned = both_loaded.character.skeleton.find(trs[1]);
  REQUIRE(skinned >= 0);
  const auto both_clip = std::find_if(both_loaded.character.clips.begin(), both_loaded.character.clips.end(),
                                      [&](const Clip& c) { return c.name == clip->name; });
  REQUIRE(both_clip != both_loaded.character.clips.end());
  const Trs channel = sampleClip(both_loaded.character.skeleton, *both_clip, time).local[skinned];
  for (const auto& [text, values] : {std::pair<std::string, Eigen::Vector3d>{trs[2], channel.translation}, {trs[3], channel.scale}}) {
    std::vector<std::string> tokens;
    std::istringstream in(std::regex_replace(text, std::regex(","), " "));
    for (std::string token; in >> token;) tokens.push_back(token);
    REQUIRE(tokens.size() == 3);
    for (int c = 0; c < 3; ++c, ++numbers) {
      INFO(tokens[c] << " printed, " << values[c] << " computed");
      CHECK(tokens[c].find('.') != std::string::npos);
      CHECK(std::abs(values[c] - std::stod(tokens[c])) <= printedTolerance(tokens[c]));
    }
  }
  // The channel is K' of equation 7, to float (glTF stores the TRS as floats).
  CHECK((channel.translation - k.col(3).head<3>()).norm() < 1e-6);
  CHECK(std::abs(channel.scale.y() - response.scale) < 1e-6);

  std::printf("extension doc example: %d printed numbers checked against a fresh bake (%s at %s %.3f s: r %.6f, up %.4f, s %.4f)\n",
              numbers, name->c_str(), clip->name.c_str(), time, drivers.ratio, response.up, response.scale);
}

}  // namespace worked_example_doc_test
}  // namespace rigbake
