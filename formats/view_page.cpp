#include "formats/view_page.h"


#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <system_error>

#include "core/error.h"
#include "formats/base64.h"
#include "formats/atomic_file.h"

namespace rigbake {
namespace {

std::string htmlEscaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// A JavaScript string literal that is also safe inside <script> (no "</" and no line breaks).
std::string scriptString(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c == '<') {
      out += "\\u003c";
    } else if (c < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
      out += escaped;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

const char* kViewPageStyle = R"css(
  html, body { margin: 0; height: 100%; background: #1f2227; color: #e6e6e6; font: 14px/1.4 system-ui, sans-serif; }
  #rigbake-player { display: flex; height: 100%; }
  .panel { width: 320px; flex: none; padding: 12px 16px; overflow-y: auto; background: #262a31; box-sizing: border-box; }
  .panel h1 { font-size: 15px; margin: 0 0 10px; word-break: break-all; }
  .viewport { flex: 1; min-width: 0; position: relative; }
  .viewport canvas { display: block; }
  .row { display: flex; gap: 8px; align-items: center; margin: 8px 0; flex-wrap: wrap; }
  select, button { font: inherit; background: #353a43; color: inherit; border: 1px solid #4a505b; border-radius: 4px; padding: 3px 8px; }
  button:disabled, input:disabled + * { opacity: 0.5; }
  #rb-clip { max-width: 100%; }
  #rb-joint { max-width: 210px; }
  .scrub { flex: 1; min-width: 0; margin: 0; }
  .group { border: 1px solid #3a3f48; border-radius: 6px; margin: 10px 0; padding: 6px 10px; }
  .group legend { padding: 0 4px; color: #aab; }
  .group label { margin-right: 12px; white-space: nowrap; }
  .time { font-variant-numeric: tabular-nums; color: #aab; }
  .note, .info, .legend { color: #99a; font-size: 12px; }
  .status.error { color: #ff8a80; }
)css";

}  // namespace

std::string viewPageHtml(const std::string& title, bool with_draco) {
  std::string html;
  html += "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"generator\" content=\"" + std::string(kViewGenerator) + "\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>" + htmlEscaped(title) + " - rigbake view</title>\n";
  html += "<style>" + std::string(kViewPageStyle) + "</style>\n</head>\n<body>\n";
  html += "<div id=\"rigbake-player\"></div>\n";
  html += "<noscript><p>The rigbake player needs JavaScript and WebGL 2.</p></noscript>\n";
  // Classic scripts only: file:// pages may not import modules or fetch() in Chromium (docs/view.md).
  html += "<script src=\"" + std::string(kViewModelFile) + "\"></script>\n";
  if (with_draco) html += "<script src=\"" + std::string(kViewDracoFile) + "\"></script>\n";
  html += "<script src=\"" + std::string(kViewPlayerFile) + "\"></script>\n";
  html += "<script>RigbakePlayer.startPage(document.getElementById(\"rigbake-player\"), {title: " + scriptString(title) +
          "});</script>\n";
  html += "</body>\n</html>\n";
  return html;
}

std::string viewModelScript(const std::string& glb) {
  return "// The GLB rigbake view was given, as base64 (a file:// page cannot read a binary file beside it).\n"
         "window.RIGBAKE_MODEL = \"" + base64Encode(glb) + "\";\n";
}

std::map<std::string, std::string> viewPageFiles(const std::string& title, const std::string& glb,
                                                 const std::string& player_bundle, const std::string& draco_script) {
  std::map<std::string, std::string> files = {{kViewPageFile, viewPageHtml(title, !draco_script.empty())},
                                              {kViewPlayerFile, player_bundle},
                                              {kViewModelFile, viewModelScript(glb)}};
  if (!draco_script.empty()) files[kViewDracoFile] = draco_script;
  return files;
}

void writeViewDirectory(const std::string& dir, const std::map<std::string, std::string>& files) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::path target = fs::path(dir);
  if (target.filename().empty()) target = target.parent_path();  // "out/" -> "out"
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(parent, error)) fail(errc::IO_WRITE_FAILED, dir, "the parent directory " + parent.string() + " does not exist");
  const bool exists = fs::exists(target, error);
  if (exists) {
    if (!fs::is_directory(target, error)) fail(errc::IO_WRITE_FAILED, dir, "exists and is not a directory");
    for (const fs::directory_entry& entry : fs::directory_iterator(target, error)) {
      const std::string name = entry.path().filename().string();
      const bool ours = files.count(name) || name == kViewDracoFile;  // a page for a Draco file had it
      if (!ours || !entry.is_regular_file())
        fail(errc::IO_WRITE_FAILED, dir,
             "exists and holds '" + name + "', which rigbake view did not write: remove the directory or choose another -o");
    }
  }
  std::string temp = target.string() + ".rigbake-tmp-XXXXXX";
  if (!mkdtemp(temp.data())) fail(errc::IO_WRITE_FAILED, dir, std::string("cannot create a temporary directory: ") + std::strerror(errno));
  try {
    fs::permissions(temp, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec | fs::perms::others_read |
                              fs::perms::others_exec);
    for (const auto& [name, bytes] : files) {
      try {
        writeFileAtomically(temp + "/" + name, bytes);
      } catch (const Error& error) {
        // The page is put together in a hidden folder beside `dir`; the user named `dir`, so the line
        // names the page's file there (a full disk named the temporary folder, gone by then).
        const std::string prefix = error.code() + " " + error.where() + ": ";
        const std::string what = error.what();
        fail(error.errorCode(), dir + "/" + name, what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
      }
    }
    if (exists) {
      // rename() cannot replace a non-empty directory: move the old one aside, put the new one in
      // place, then delete the old. Between the two renames `dir` is absent for an instant, never partial.
      std::string old = target.string() + ".rigbake-tmp-XXXXXX";
      if (!mkdtemp(old.data())) fail(errc::IO_WRITE_FAILED, dir, std::string("cannot create a temporary directory: ") + std::strerror(errno));
      fs::remove(old);
      if (std::rename(target.c_str(), old.c_str()) != 0)
        fail(errc::IO_WRITE_FAILED, dir, std::string("cannot move the previous page aside: ") + std::strerror(errno));
      if (std::rename(temp.c_str(), target.c_str()) != 0) {
        const std::string reason = std::strerror(errno);
        std::rename(old.c_str(), target.c_str());
        fail(errc::IO_WRITE_FAILED, dir, "cannot move the finished page into place: " + reason);
      }
      fs::remove_all(old, error);
    } else if (std::rename(temp.c_str(), target.c_str()) != 0) {
      fail(errc::IO_WRITE_FAILED, dir, std::string("cannot move the finished page into place: ") + std::strerror(errno));
    }
  } catch (...) {
    fs::remove_all(temp, error);
    throw;
  }
}

}  // namespace rigbake
