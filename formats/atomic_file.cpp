#include "formats/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

#include "anatomy/error.h"

namespace rigbake {

void writeFileAtomically(const std::string& path, const std::string& bytes) {
  std::string temp_path = path + ".rigbake-tmp-XXXXXX";
  int fd = mkstemp(temp_path.data());
  if (fd < 0) fail("IO_WRITE_FAILED", path, std::string("cannot create a temporary file: ") + std::strerror(errno));
  size_t written = 0;
  while (written < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      std::string reason = std::strerror(errno);
      ::close(fd);
      std::remove(temp_path.c_str());
      fail("IO_WRITE_FAILED", path, "cannot write: " + reason);
    }
    written += static_cast<size_t>(n);
  }
  // mkstemp creates 0600; outputs are ordinary files others may read.
  fchmod(fd, 0644);
  if (::close(fd) != 0 || std::rename(temp_path.c_str(), path.c_str()) != 0) {
    std::string reason = std::strerror(errno);
    std::remove(temp_path.c_str());
    fail("IO_WRITE_FAILED", path, "cannot move the finished file into place: " + reason);
  }
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("IO_FILE_NOT_FOUND", path, "no such file or it cannot be opened");
  // Read at the size the file has (one allocation, one copy): through an ostringstream the bytes were
  // copied twice and the buffer grew by doubling, most of the time of loading a 10 MB GLB.
  std::string bytes;
  struct stat status {};
  if (::stat(path.c_str(), &status) == 0 && S_ISREG(status.st_mode) && status.st_size > 0) {
    bytes.resize(static_cast<size_t>(status.st_size));
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    bytes.resize(static_cast<size_t>(in.gcount()));
    if (in.bad()) fail("IO_FILE_NOT_FOUND", path, "read error");
    if (in.eof()) return bytes;  // the file shrank while being read
  }
  // Whatever is left (or all of it, for a pipe or a file that grew).
  std::ostringstream rest;
  in.clear();
  rest << in.rdbuf();
  if (in.bad()) fail("IO_FILE_NOT_FOUND", path, "read error");
  bytes += rest.str();
  return bytes;
}

}  // namespace rigbake
