// Raw packed-influence file, layout version 1 (docs/packed-influences.md, "The --packed-out file").
// The arrays are the talk's GPU buffers unchanged (God of War Ragnarök, "Increase Bone Influences per
// Vertex"); the header only says how to slice them.
#include "formats/packed_file.h"

#include "core/error.h"
#include "formats/atomic_file.h"

namespace rigbake {

namespace {

void putLe32(std::string& out, std::uint32_t value) {
  for (int b = 0; b < 4; ++b) out.push_back(static_cast<char>((value >> (8 * b)) & 0xffu));
}

void putLe16(std::string& out, std::uint32_t value) {
  for (int b = 0; b < 2; ++b) out.push_back(static_cast<char>((value >> (8 * b)) & 0xffu));
}

std::uint32_t getLe(const std::string& bytes, size_t offset, int size) {
  std::uint32_t value = 0;
  for (int b = 0; b < size; ++b)
    value |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[offset + b])) << (8 * b);
  return value;
}

[[noreturn]] void invalid(const std::string& where, const std::string& message) {
  fail(errc::PACKED_FILE_INVALID, where, message);
}

}  // namespace

std::string encodePackedFile(const std::vector<PackedInfluences>& parts) {
  if (parts.empty()) fail(errc::INTERNAL, "", "a packed influence file needs at least one mesh part");
  const PackedInfluences& first = parts.front();
  std::uint64_t vertices = 0;
  for (size_t p = 0; p < parts.size(); ++p) {
    const PackedInfluences& part = parts[p];
    std::string problem = packedInfluencesProblem(part);
    if (!problem.empty()) fail(errc::INTERNAL, "", "packed part " + std::to_string(p) + ": " + problem);
    if (part.influences != first.influences || part.index_bytes != first.index_bytes ||
        part.joint_count != first.joint_count)
      fail(errc::INTERNAL, "", "packed part " + std::to_string(p) + " differs in layout from part 0");
    vertices += static_cast<std::uint64_t>(part.vertex_count);
  }
  if (vertices > 0xffffffffu) fail(errc::INTERNAL, "", "more vertices than a packed file header can count");
  const int words = packedWeightWords(first.influences);
  const int stride = packedIndexStride(first.influences, first.index_bytes);
  std::string out;
  out.reserve(kPackedFileHeaderBytes + 4 * parts.size() + vertices * (4 * words + stride));
  putLe32(out, kPackedFileMagic);
  putLe16(out, kPackedLayoutVersion);
  out.push_back(static_cast<char>(first.influences));
  out.push_back(static_cast<char>(first.index_bytes));
  putLe32(out, static_cast<std::uint32_t>(first.joint_count));
  putLe32(out, static_cast<std::uint32_t>(parts.size()));
  putLe32(out, static_cast<std::uint32_t>(vertices));
  putLe32(out, static_cast<std::uint32_t>(words));
  putLe32(out, static_cast<std::uint32_t>(stride));
  putLe32(out, 0u);  // reserved
  for (const PackedInfluences& part : parts) putLe32(out, static_cast<std::uint32_t>(part.vertex_count));
  for (const PackedInfluences& part : parts) {
    for (std::uint32_t word : part.weight_words) putLe32(out, word);
  }
  for (const PackedInfluences& part : parts) out.append(part.indices.begin(), part.indices.end());
  return out;
}

std::vector<PackedInfluences> decodePackedFile(const std::string& bytes, const std::string& where) {
  if (bytes.size() < static_cast<size_t>(kPackedFileHeaderBytes))
    invalid(where, "the file is " + std::to_string(bytes.size()) + " bytes, shorter than the 32-byte header");
  if (getLe(bytes, 0, 4) != kPackedFileMagic) invalid(where, "byte 0: not a rigbake packed influence file");
  const std::uint32_t version = getLe(bytes, 4, 2);
  if (version != static_cast<std::uint32_t>(kPackedLayoutVersion))
    invalid(where, "byte 4: layout version " + std::to_string(version) + " is not supported (this build reads 1)");
  const int influences = static_cast<unsigned char>(bytes[6]);
  const int index_bytes = static_cast<unsigned char>(bytes[7]);
  if (!isPackedInfluenceCount(influences))
    invalid(where, "byte 6: influence count " + std::to_string(influences) + " is not 4, 7 or 10");
  if (index_bytes != 1 && index_bytes != 2)
    invalid(where, "byte 7: index width " + std::to_string(index_bytes) + " is not 1 or 2 bytes");
  const std::uint32_t joint_count = getLe(bytes, 8, 4);
  const std::uint32_t part_count = getLe(bytes, 12, 4);
  const std::uint32_t vertex_count = getLe(bytes, 16, 4);
  const int words = packedWeightWords(influences);
  const int stride = packedIndexStride(influences, index_bytes);
  if (joint_count < 1 || joint_count > (index_bytes == 1 ? 256u : 65536u))
    invalid(where, "byte 8: joint count " + std::to_string(joint_count) + " does not fit " +
                       std::to_string(8 * index_bytes) + "-bit indices");
  if (part_count < 1) invalid(where, "byte 12: the file lists no mesh part");
  if (getLe(bytes, 20, 4) != static_cast<std::uint32_t>(words))
    invalid(where, "byte 20: " + std::to_string(getLe(bytes, 20, 4)) + " weight words per vertex, layout 1 has " +
                       std::to_string(words) + " for " + std::to_string(influences) + " influences");
  if (getLe(bytes, 24, 4) != static_cast<std::uint32_t>(stride))
    invalid(where, "byte 24: index stride " + std::to_string(getLe(bytes, 24, 4)) + ", layout 1 has " +
                       std::to_string(stride));
  if (getLe(bytes, 28, 4) != 0u) invalid(where, "byte 28: the reserved header field is not 0");
  const std::uint64_t expected = static_cast<std::uint64_t>(kPackedFileHeaderBytes) + 4ull * part_count +
                                 static_cast<std::uint64_t>(vertex_count) * (4ull * words + stride);
  if (bytes.size() != expected)
    invalid(where, "the file is " + std::to_string(bytes.size()) + " bytes; its header describes " +
                       std::to_string(expected));
  std::vector<PackedInfluences> parts(part_count);
  std::uint64_t listed = 0;
  for (std::uint32_t p = 0; p < part_count; ++p) {
    std::uint32_t count = getLe(bytes, kPackedFileHeaderBytes + 4 * static_cast<size_t>(p), 4);
    if (count > 0x7fffffffu)
      invalid(where, "byte " + std::to_string(kPackedFileHeaderBytes + 4 * static_cast<size_t>(p)) +
                         ": part vertex count too large");
    parts[p].vertex_count = static_cast<int>(count);
    listed += count;
  }
  if (listed != vertex_count)
    invalid(where, "the part table lists " + std::to_string(listed) + " vertices, the header " +
                       std::to_string(vertex_count));
  size_t weights_offset = kPackedFileHeaderBytes + 4 * static_cast<size_t>(part_count);
  size_t indices_offset = weights_offset + static_cast<size_t>(vertex_count) * 4 * words;
  for (std::uint32_t p = 0; p < part_count; ++p) {
    PackedInfluences& part = parts[p];
    part.influences = influences;
    part.index_bytes = index_bytes;
    part.joint_count = static_cast<int>(joint_count);
    part.weight_words.resize(static_cast<size_t>(part.vertex_count) * words);
    for (std::uint32_t& word : part.weight_words) {
      word = getLe(bytes, weights_offset, 4);
      weights_offset += 4;
    }
    size_t index_size = static_cast<size_t>(part.vertex_count) * stride;
    part.indices.assign(bytes.begin() + static_cast<std::ptrdiff_t>(indices_offset),
                        bytes.begin() + static_cast<std::ptrdiff_t>(indices_offset + index_size));
    indices_offset += index_size;
    std::string problem = packedInfluencesProblem(part);
    if (!problem.empty()) invalid(where, "part " + std::to_string(p) + " " + problem);
  }
  return parts;
}

void writePackedFile(const std::string& path, const std::vector<PackedInfluences>& parts) {
  writeFileAtomically(path, encodePackedFile(parts));
}

std::vector<PackedInfluences> readPackedFile(const std::string& path) {
  return decodePackedFile(readFile(path), path);
}

}  // namespace rigbake
