// Outputs appear whole or not at all: bytes go to a temporary file beside the target, which is
// renamed over it only once everything was written. A failed run leaves no partial file behind.
#pragma once

#include <string>

namespace rigbake {

// Throws Error IO_WRITE_FAILED naming `path` when it cannot write or rename.
void writeFileAtomically(const std::string& path, const std::string& bytes);

// Reads a whole file; throws Error IO_FILE_NOT_FOUND naming `path` when it cannot.
std::string readFile(const std::string& path);

}  // namespace rigbake
