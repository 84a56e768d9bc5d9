// The raw file `rigbake bake --packed-out FILE` writes: the packed skin influences of every skinned
// mesh part, in layout version 1 of docs/packed-influences.md, behind a small header. Little endian;
// each section starts 4-byte aligned so a loader can map the arrays straight into GPU buffers.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/pack_influences.h"

namespace rigbake {

// "RBPI" read as a little-endian uint32.
constexpr std::uint32_t kPackedFileMagic = 0x49504252u;
constexpr int kPackedFileHeaderBytes = 32;

// The file's bytes for `parts` in the order given (the bake's mesh-part order). Every part must share
// influences, index_bytes and joint_count, and be valid layout-1 data; otherwise throws INTERNAL.
// Deterministic: equal input gives identical bytes.
std::string encodePackedFile(const std::vector<PackedInfluences>& parts);

// Parses and checks a whole file. Throws Error PACKED_FILE_INVALID naming `where` (the file) and the
// byte offset or vertex of the first problem: wrong magic, unknown version, sizes that disagree with the
// header, reserved bits or padding not 0, stored weights above 1000, an index out of range.
std::vector<PackedInfluences> decodePackedFile(const std::string& bytes, const std::string& where);

// encodePackedFile written with writeFileAtomically (IO_WRITE_FAILED on failure, no partial file).
void writePackedFile(const std::string& path, const std::vector<PackedInfluences>& parts);
// readFile then decodePackedFile (IO_FILE_NOT_FOUND, PACKED_FILE_INVALID).
std::vector<PackedInfluences> readPackedFile(const std::string& path);

}  // namespace rigbake
