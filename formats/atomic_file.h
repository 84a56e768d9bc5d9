// Outputs appear whole or not at all: bytes go to a temporary file beside the target, which is
// renamed over it only once everything was written. A failed run leaves no partial file behind, and a
// command with several outputs commits them together (OutputBatch), so a failure leaves none of them.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rigbake {

// Suffix of the temporary files outputs are written to; `rigbake build` removes leftovers of killed
// runs by it.
inline constexpr const char* kTempFileMarker = ".rigbake-tmp-";

// The output path that means standard output (docs/output-contract.md): allowed only where a command
// writes JSON or a report (cli/common.h checks which); written last, once every file is in place.
inline constexpr const char* kStandardOutput = "-";

// The file an output path writes ("-" stays "-": standard output): a symbolic link is followed to its target (as a shell's `>` does), so
// the link stays and the file it names is replaced. Throws Error IO_OUTPUT_NOT_REGULAR when the path
// exists and is not a regular file (a device, FIFO, socket or directory), so that /dev/null stays a
// device; IO_WRITE_FAILED for a link loop. Commands call it on every output before any work.
std::string checkOutputPath(const std::string& path);

// Throws Error IO_WRITE_FAILED naming `path` when it cannot write or rename; IO_OUTPUT_NOT_REGULAR as
// checkOutputPath.
void writeFileAtomically(const std::string& path, const std::string& bytes);

// Several outputs of one command, committed together: commit() checks every path, writes every
// temporary file, and renames them into place only once all are written. On any failure it removes
// its temporary files (and any output it had already renamed, so a failed run leaves no mix of new
// and old files) and throws the Error.
class OutputBatch {
 public:
  void add(std::string path, std::string bytes);
  void commit();

 private:
  std::vector<std::pair<std::string, std::string>> files_;
};

// mkdir -p; throws Error IO_WRITE_FAILED naming `path` (an empty one, one under a regular file, a name
// too long, a read-only file system) instead of std::filesystem's exception, which reached users as
// INTERNAL.
void createDirectories(const std::string& path);

// An advisory lock (flock(2)) on DIRECTORY/.rigbake-lock, held until destruction: one writer
// (exclusive) or several that write disjoint files in it (shared). The kernel drops it when the process
// dies, so a killed run never leaves a stale lock.
class FolderLock {
 public:
  FolderLock() = default;
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  ~FolderLock();
  // False when another process holds a conflicting lock; IO_WRITE_FAILED when the lock file cannot be
  // opened. Does not wait.
  bool tryLock(const std::string& directory, bool exclusive);

 private:
  int fd_ = -1;
};

// Removes the temporary files a killed run left beside any of `outputs` (OUTPUT.rigbake-tmp-XXXXXX);
// returns how many. Only the temporaries of these outputs: another program's (a `rigbake bake` into the
// same folder) are not touched. Only safe while no other run writes these outputs (hold an exclusive
// FolderLock).
int removeTemporaryLeftovers(const std::vector<std::string>& outputs);

// The most rigbake reads of one input (docs/errors.md, INPUT_TOO_LARGE): a glTF, GLB or VRM (or any
// binary input), and a JSON file (preset, map, muscle file, manifest, config, hits).
inline constexpr std::uint64_t kMaxModelBytes = std::uint64_t{2} << 30;  // 2 GiB
inline constexpr std::uint64_t kMaxJsonBytes = std::uint64_t{64} << 20;  // 64 MiB

// Reads a whole file: a regular file, or a FIFO or pipe (`<(...)`), read up to `max_bytes`. Throws Error
// IO_FILE_NOT_FOUND naming `path` when it cannot be opened, IO_INPUT_NOT_REGULAR for a device (/dev/zero
// would be read until memory runs out), socket or directory, INPUT_TOO_LARGE past `max_bytes`.
std::string readFile(const std::string& path, std::uint64_t max_bytes = kMaxModelBytes);

}  // namespace rigbake
