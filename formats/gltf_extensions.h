// The glTF extensions rigbake honours, and what it does with each (docs/extensions.md mirrors this
// table). glTF 2.0 specification, "Specifying Extensions": a client must not load an asset whose
// extensionsRequired names an extension it does not support, so the loader refuses such a file with
// GLTF_EXTENSION_UNSUPPORTED. Extensions that are only used (extensionsUsed) never stop a load: their
// objects are kept and written back as they were.
#pragma once

#include <string>
#include <vector>

namespace rigbake {

enum class ExtensionHandling {
  kRead,           // rigbake reads it and keeps it in its outputs
  kDecoded,        // decoded on load; outputs are written without it
  kPassedThrough,  // rigbake's results do not depend on it; kept in outputs exactly as it was
};

struct HonouredExtension {
  const char* name;
  ExtensionHandling handling;
  const char* what;  // what rigbake does with it
};

// Every extension a file may require, in the order of docs/extensions.md.
const std::vector<HonouredExtension>& honouredExtensions();

bool honoursExtension(const std::string& name);

// Of `required` (a file's extensionsRequired), the names rigbake cannot honour, in file order.
std::vector<std::string> unhonouredExtensions(const std::vector<std::string>& required);

// Throws GLTF_EXTENSION_UNSUPPORTED naming `file` and every unhonoured extension when there is any.
void requireHonouredExtensions(const std::vector<std::string>& required, const std::string& file);

}  // namespace rigbake
