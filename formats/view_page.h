// The page `rigbake view` writes (docs/view.md): a directory that plays a baked glTF in the rigbake
// player (player/, three.js) straight from file://, with no server and no network:
//   index.html          the page: controls and viewport, filled in by the player
//   rigbake-player.js   the player and three.js bundled into one classic script (scripts/install-player.sh)
//   model.js            the GLB as base64: window.RIGBAKE_MODEL = "..."
//   rigbake-draco.js    (a Draco-compressed GLB only) three's Draco decoder files as one script
// Classic scripts, because Chromium refuses ES module imports and fetch() on file:// pages; base64 in
// a script, because a page from file:// cannot read a binary file beside it any other way.
// The same inputs give the same bytes.
#pragma once

#include <map>
#include <string>

namespace rigbake {

inline constexpr const char* kViewPageFile = "index.html";
inline constexpr const char* kViewPlayerFile = "rigbake-player.js";
inline constexpr const char* kViewModelFile = "model.js";
inline constexpr const char* kViewDracoFile = "rigbake-draco.js";
// In index.html, so that `rigbake view` recognises a page it wrote before and may replace it.
inline constexpr const char* kViewGenerator = "rigbake view";


// index.html for a page showing `title` (the file name; escaped here); with_draco loads kViewDracoFile.
std::string viewPageHtml(const std::string& title, bool with_draco = false);

// model.js for a GLB.
std::string viewModelScript(const std::string& glb);

// The page's files: index.html, rigbake-player.js (the bundle's bytes as given) and model.js, and
// rigbake-draco.js (draco_script as given) when draco_script is not empty.
std::map<std::string, std::string> viewPageFiles(const std::string& title, const std::string& glb,
                                                 const std::string& player_bundle, const std::string& draco_script = "");

// Writes `files` as the directory `dir`, whole or not at all: into a new temporary directory beside
// it, renamed into place; a directory a previous run wrote (holding nothing but the page's file names) is
// replaced. Throws IO_WRITE_FAILED naming `dir` when the parent does not exist, `dir` is a file or a
// directory holding anything else, or a write or rename fails; a failure leaves `dir` as it was.
void writeViewDirectory(const std::string& dir, const std::map<std::string, std::string>& files);

}  // namespace rigbake
