#include "pipeline/build_plan.h"

#include <algorithm>
#include <map>
#include <set>

#include "core/error.h"

namespace rigbake {

int characterIndex(const BuildManifest& manifest, const std::string& name) {
  for (size_t i = 0; i < manifest.characters.size(); ++i) {
    if (manifest.characters[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

namespace {

// Ninja's escaping for paths in build lines: '$', ' ' and ':' are escaped with '$'.
std::string ninjaPath(const std::string& path) {
  std::string out;
  for (char c : path) {
    if (c == '$' || c == ' ' || c == ':') out += '$';
    out += c;
  }
  return out;
}

}  // namespace

std::string shellWord(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::vector<int> buildOrder(const BuildManifest& manifest) {
  const int count = static_cast<int>(manifest.characters.size());
  std::vector<int> order;
  std::vector<int> state(count, 0);  // 0 new, 1 visiting, 2 done
  for (int start = 0; start < count; ++start) {
    std::vector<int> chain;
    int at = start;
    while (at >= 0 && state[at] == 0) {
      state[at] = 1;
      chain.push_back(at);
      const BuildCharacter& c = manifest.characters[at];
      if (c.muscles_from.empty()) break;
      int source = characterIndex(manifest, c.muscles_from);
      if (source < 0)
        fail(errc::MANIFEST_INVALID, manifest.file + "#" + c.pointer + "/muscles_from",
             "no character named '" + c.muscles_from + "' in the manifest");
      if (state[source] == 1)
        fail(errc::MANIFEST_INVALID, manifest.file + "#" + c.pointer + "/muscles_from",
             "muscles_from makes a cycle through '" + c.muscles_from + "'");
      at = source;
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      state[*it] = 2;
      order.push_back(*it);
    }
  }
  return order;
}

std::string buildGroup(const BuildManifest& manifest, int character) {
  int at = character;
  for (size_t guard = 0; guard <= manifest.characters.size(); ++guard) {
    const std::string& from = manifest.characters[at].muscles_from;
    int source = from.empty() ? -1 : characterIndex(manifest, from);
    if (source < 0) break;
    at = source;
  }
  return manifest.characters[at].name;
}

bool inShard(const BuildManifest& manifest, int character, int index, int count) {
  std::set<std::string> groups;
  for (size_t i = 0; i < manifest.characters.size(); ++i) groups.insert(buildGroup(manifest, static_cast<int>(i)));
  const std::string group = buildGroup(manifest, character);
  int position = static_cast<int>(std::distance(groups.begin(), groups.find(group)));
  return position % count == index;
}

CharacterOutputs characterOutputs(const BuildManifest& manifest, const BuildCharacter& character) {
  CharacterOutputs out;
  out.directory = manifest.out + "/" + character.name;
  out.model = out.directory + "/" + character.name + ".glb";
  out.muscles = out.directory + "/muscles.json";
  out.report_json = out.directory + "/report.json";
  out.report_junit = out.directory + "/report.junit.xml";
  out.report_html = out.directory + "/report.html";
  out.stamp = out.directory + "/.rigbake-inputs";
  if (character.stats) out.stats = out.directory + "/stats.json";
  if (character.packed) out.packed = out.directory + "/" + character.name + ".rbpk";
  return out;
}

std::vector<std::string> CharacterOutputs::files() const {
  std::vector<std::string> files = {model, muscles, report_json, report_junit, report_html};
  for (const std::string& optional : {stats, packed})
    if (!optional.empty()) files.push_back(optional);
  return files;
}

std::string ninjaFile(const BuildManifest& manifest, const std::string& manifest_path, const NinjaCommands& commands) {
  std::string text;
  text += "# Written by `" + commands.written_by + "`: one edge per character. Run with `ninja -f FILE`.\n";
  text += "ninja_required_version = 1.5\n";
  // Ninja's own log goes with the outputs, not into whatever directory ninja is started from.
  text += "builddir = " + ninjaPath(manifest.out) + "\n\n";
  text += "rule rigbake_character\n";
  text += "  command = " + commands.character + "\n";
  text += "  description = rigbake $name\n\n";
  text += "rule rigbake_summary\n";
  text += "  command = " + commands.summary + "\n";
  text += "  description = rigbake summary\n\n";
  std::vector<std::string> all_models;
  for (int index : buildOrder(manifest)) {
    const BuildCharacter& c = manifest.characters[index];
    CharacterOutputs out = characterOutputs(manifest, c);
    text += "build";
    for (const std::string& file : out.files()) text += " " + ninjaPath(file);
    text += ": rigbake_character " + ninjaPath(c.input);
    text += " " + ninjaPath(c.preset);
    if (!c.muscles.empty()) text += " " + ninjaPath(c.muscles);
    for (const std::string* file : {&c.rom, &c.regions, &c.jiggle, &c.hits})
      if (!file->empty()) text += " " + ninjaPath(*file);
    if (!c.muscles_from.empty()) {
      const BuildCharacter& source = manifest.characters[characterIndex(manifest, c.muscles_from)];
      text += " " + ninjaPath(characterOutputs(manifest, source).muscles) + " " + ninjaPath(source.input);
    }
    text += " | " + ninjaPath(manifest_path) + "\n  name = " + c.name + "\n";
    all_models.push_back(ninjaPath(out.report_json));
  }
  text += "\nbuild " + ninjaPath(manifest.out + "/summary.json") + " " + ninjaPath(manifest.out + "/summary.junit.xml") +
          ": rigbake_summary";
  for (const std::string& model : all_models) text += " " + model;
  text += "\n\ndefault " + ninjaPath(manifest.out + "/summary.json") + "\n";
  return text;
}

}  // namespace rigbake
