#include "formats/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <vector>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"

namespace rigbake {

namespace {

// Writes `bytes` to a new temporary file beside `target` and returns its path; removes it and throws
// IO_WRITE_FAILED (naming `path`, as the user gave it) when it cannot.
std::string writeTemporary(const std::string& path, const std::string& target, const std::string& bytes) {
  std::string temp_path = target + kTempFileMarker + "XXXXXX";
  int fd = mkstemp(temp_path.data());
  if (fd < 0) fail(errc::IO_WRITE_FAILED, path, std::string("cannot create a temporary file: ") + std::strerror(errno));
  size_t written = 0;
  while (written < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      std::string reason = std::strerror(errno);
      ::close(fd);
      std::remove(temp_path.c_str());
      fail(errc::IO_WRITE_FAILED, path, "cannot write: " + reason);
    }
    written += static_cast<size_t>(n);
  }
  // mkstemp creates 0600; outputs are ordinary files others may read.
  fchmod(fd, 0644);
  // close() is where NFS and a full disk may report a failed write-back.
  if (::close(fd) != 0) {
    std::string reason = std::strerror(errno);
    std::remove(temp_path.c_str());
    fail(errc::IO_WRITE_FAILED, path, "cannot write: " + reason);
  }
  return temp_path;
}

// Writes `bytes` to standard output, all of it or IO_WRITE_FAILED naming "-" (a closed pipe, /dev/full).
// Through stdio, which std::cout is synchronised with, so it lands after what was printed before.
void writeStandardOutput(const std::string& bytes) {
  if ((!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), stdout) != bytes.size()) || std::fflush(stdout) != 0) {
    std::string reason = std::strerror(errno);
    std::clearerr(stdout);
    fail(errc::IO_WRITE_FAILED, kStandardOutput, "cannot write to standard output: " + reason);
  }
}

// RIGBAKE_KEEP_OUTPUTS=DIR (docs/output-contract.md): every glTF, GLB or VRM a run commits is also
// copied into DIR, as PID-N-NAME, so that the test suite can run the Khronos validator over every model
// any of its cases wrote (tests/CMakeLists.txt), however briefly the case kept it. A copy that cannot be
// written is skipped: the run's own outputs are what counts, and the suite's check counts the copies.
void keepCopyOfModel(const std::string& target, const std::string& bytes) {
  const char* folder = std::getenv("RIGBAKE_KEEP_OUTPUTS");
  if (folder == nullptr || *folder == '\0') return;
  const std::string extension = std::filesystem::path(target).extension().string();
  if (extension != ".glb" && extension != ".gltf" && extension != ".vrm") return;
  static std::atomic<int> kept{0};  // `build` commits from several threads
  const std::string name = std::to_string(::getpid()) + "-" + std::to_string(kept++) + "-" +
                           std::filesystem::path(target).filename().string();
  std::ofstream(std::filesystem::path(folder) / name, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

std::string checkOutputPath(const std::string& path) {
  if (path == kStandardOutput) return path;
  // Following the path as the kernel does first: /proc/self/fd/1 is a link whose text ("pipe:[7]") names
  // nothing, but what it reaches is not a regular file either.
  struct stat reached {};
  if (::stat(path.c_str(), &reached) == 0 && !S_ISREG(reached.st_mode)) {
    const char* kind = S_ISDIR(reached.st_mode)   ? "a directory"
                       : S_ISCHR(reached.st_mode) ? "a character device"
                       : S_ISBLK(reached.st_mode) ? "a block device"
                       : S_ISFIFO(reached.st_mode) ? "a FIFO"
                       : S_ISSOCK(reached.st_mode) ? "a socket"
                                                   : "not a regular file";
    fail(errc::IO_OUTPUT_NOT_REGULAR, path, std::string("exists and is ") + kind +
                                            "; rigbake replaces only regular files (name a file to write)");
  }
  // A symbolic link: the temporary file goes beside the file it names, and the rename replaces that file,
  // not the link (a dangling link creates its target, as `>` would).
  std::string target = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat link {};
    if (::lstat(target.c_str(), &link) != 0 || !S_ISLNK(link.st_mode)) return target;
    std::string text(static_cast<size_t>(link.st_size > 0 ? link.st_size : 4096) + 1, '\0');
    ssize_t n = ::readlink(target.c_str(), text.data(), text.size());
    if (n < 0) fail(errc::IO_WRITE_FAILED, path, std::string("cannot read the symbolic link: ") + std::strerror(errno));
    text.resize(static_cast<size_t>(n));
    const size_t slash = target.find_last_of('/');
    target = text[0] == '/' || slash == std::string::npos ? text : target.substr(0, slash + 1) + text;
  }
  fail(errc::IO_WRITE_FAILED, path, "too many levels of symbolic links");
}

void writeFileAtomically(const std::string& path, const std::string& bytes) {
  OutputBatch batch;
  batch.add(path, bytes);
  batch.commit();
}

void OutputBatch::add(std::string path, std::string bytes) { files_.emplace_back(std::move(path), std::move(bytes)); }

void OutputBatch::commit() {
  std::vector<std::string> targets, temps, renamed;
  auto removeAll = [&](const std::vector<std::string>& paths) {
    for (const std::string& p : paths) std::remove(p.c_str());
  };
  std::vector<std::string> to_stdout;
  std::vector<std::pair<std::string, std::string>> files;
  for (auto& file : files_) {
    if (file.first == kStandardOutput) to_stdout.push_back(std::move(file.second));
    else files.push_back(std::move(file));
  }
  files_ = std::move(files);
  try {
    for (const auto& [path, bytes] : files_) targets.push_back(checkOutputPath(path));
    for (size_t i = 0; i < files_.size(); ++i) temps.push_back(writeTemporary(files_[i].first, targets[i], files_[i].second));
  } catch (...) {
    removeAll(temps);
    throw;
  }
  // Every byte is on disk: only the renames are left, which within one directory fail only for what
  // checkOutputPath has ruled out (or a race with another program).
  for (size_t i = 0; i < temps.size(); ++i) {
    if (std::rename(temps[i].c_str(), targets[i].c_str()) == 0) {
      renamed.push_back(targets[i]);
      continue;
    }
    std::string reason = std::strerror(errno);
    removeAll(std::vector<std::string>(temps.begin() + static_cast<long>(i), temps.end()));
    removeAll(renamed);
    fail(errc::IO_WRITE_FAILED, files_[i].first, "cannot move the finished file into place: " + reason);
  }
  // Standard output last: it cannot be taken back, so it is written only once every file is in place,
  // and a failed write to it removes them as any other failed output would.
  try {
    for (const std::string& bytes : to_stdout) writeStandardOutput(bytes);
  } catch (...) {
    removeAll(renamed);
    throw;
  }
  for (size_t i = 0; i < files_.size(); ++i) keepCopyOfModel(targets[i], files_[i].second);
  files_.clear();
}

void createDirectories(const std::string& path) {
  if (path.empty()) fail(errc::IO_WRITE_FAILED, "\"\"", "an empty path names no directory");
  std::error_code error;
  std::filesystem::create_directories(path, error);
  if (error) fail(errc::IO_WRITE_FAILED, path, "cannot create the directory: " + error.message());
  if (!std::filesystem::is_directory(path, error)) fail(errc::IO_WRITE_FAILED, path, "exists and is not a directory");
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the flock
}

bool FolderLock::tryLock(const std::string& directory, bool exclusive) {
  const std::string path = directory + "/.rigbake-lock";
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) fail(errc::IO_WRITE_FAILED, path, std::string("cannot open the lock file: ") + std::strerror(errno));
  while (::flock(fd_, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
    if (errno == EINTR) continue;
    if (errno == EWOULDBLOCK) return false;
    fail(errc::IO_WRITE_FAILED, path, std::string("cannot lock: ") + std::strerror(errno));
  }
  return true;
}

int removeTemporaryLeftovers(const std::vector<std::string>& outputs) {
  namespace fs = std::filesystem;
  int removed = 0;
  for (const std::string& output : outputs) {
    const fs::path path(output);
    const std::string prefix = path.filename().string() + kTempFileMarker;
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code error;
    for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
      const std::string name = it->path().filename().string();
      // mkstemp's six characters follow the marker: OUTPUT.rigbake-tmp-XXXXXX and nothing else.
      if (name.size() != prefix.size() + 6 || name.compare(0, prefix.size(), prefix) != 0) continue;
      std::error_code type_error, remove_error;
      if (it->is_regular_file(type_error) && fs::remove(it->path(), remove_error)) ++removed;
    }
  }
  return removed;
}

namespace {

const char* fileKind(mode_t mode) {
  return S_ISDIR(mode) ? "a directory" : S_ISCHR(mode) ? "a character device" : S_ISBLK(mode) ? "a block device"
         : S_ISSOCK(mode) ? "a socket" : "not a regular file";
}

[[noreturn]] void tooLarge(const std::string& path, std::uint64_t size, std::uint64_t max_bytes, bool at_least) {
  fail(errc::INPUT_TOO_LARGE, path, std::string("is ") + (at_least ? "more than " : "") + std::to_string(size) +
                                    " bytes; rigbake reads at most " + std::to_string(max_bytes) + " bytes of such a file");
}

}  // namespace

std::string readFile(const std::string& path, std::uint64_t max_bytes) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) fail(errc::IO_FILE_NOT_FOUND, path, "no such file or it cannot be opened");
  if (!S_ISREG(status.st_mode) && !S_ISFIFO(status.st_mode))
    fail(errc::IO_INPUT_NOT_REGULAR, path, std::string("is ") + fileKind(status.st_mode) + ", not a file to read");
  if (S_ISREG(status.st_mode) && static_cast<std::uint64_t>(status.st_size) > max_bytes)
    tooLarge(path, static_cast<std::uint64_t>(status.st_size), max_bytes, false);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(errc::IO_FILE_NOT_FOUND, path, "no such file or it cannot be opened");
  // Read at the size the file has (one allocation, one copy): through an ostringstream the bytes were
  // copied twice and the buffer grew by doubling, most of the time of loading a 10 MB GLB.
  std::string bytes;
  if (S_ISREG(status.st_mode) && status.st_size > 0) {
    bytes.resize(static_cast<size_t>(status.st_size));
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    bytes.resize(static_cast<size_t>(in.gcount()));
    if (in.bad()) fail(errc::IO_FILE_NOT_FOUND, path, "read error");
    if (in.eof()) return bytes;  // the file shrank while being read
  }
  // Whatever is left (or all of it, for a pipe or a file that grew), never more than max_bytes.
  in.clear();
  std::vector<char> chunk(1 << 16);
  while (true) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    bytes.append(chunk.data(), static_cast<size_t>(in.gcount()));
    if (bytes.size() > max_bytes) tooLarge(path, max_bytes, max_bytes, true);
    if (!in) break;
  }
  if (in.bad()) fail(errc::IO_FILE_NOT_FOUND, path, "read error");
  return bytes;
}

}  // namespace rigbake
