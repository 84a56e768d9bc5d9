// Why: a bake touches a few hundred MB of fresh memory in large vectors (positions, weight sets, the
// skinning batches, the glTF's buffers), which glibc's malloc maps and unmaps per allocation, so the
// kernel zeroes and maps it again 4 KiB at a time. On the 2-core virtual machines rigbake is measured
// on, a page fault costs about 8 µs: a re-bake of the 100k-vertex sample took 35,000 faults, and
// loading and writing the file were mostly faults. glibc (2.35 on) can ask for transparent huge pages
// on what it maps (madvise, so it works where the kernel's THP mode is "madvise", Debian's default):
// measured on that re-bake, 35,000 -> 3,300-4,000 faults and 0.94-1.32 s -> 0.74-0.78 s. Allocation
// order and addresses never reach an output, so the bytes written are the same.
//
// With it, one malloc arena (glibc.malloc.arena_max=1) instead of one per thread: the second thread's
// arena held freed blocks the main one could not reuse, so the 100k-vertex bake's peak resident memory
// was 114 MB with two arenas and 106 MB with one, in the same time (the bake does not allocate per
// frame or per vertex, so the threads hardly meet in malloc).
//
// And blocks of 8 MiB or more mapped on their own (glibc.malloc.mmap_threshold=8388608) and so given
// back when freed: by default glibc raises that threshold each time such a block is freed, and the
// bake's next large vectors then came from the heap, which could not shrink past them. Measured on the
// 100k-vertex bake, six runs each: peak 95-104 MB -> 92-95 MB, for about 6,000 more page faults
// (0.05 s), with 4 MiB. 8 MiB keeps that peak (five runs: 96-105 MB, 98-105 MB at 4 MiB; Cyberpunk
// 22-24 MB either way) and the blocks between 4 and 8 MiB (the file's bytes, a part's positions and
// weight sets at 100k vertices) come from the heap again: a first bake and re-bake in one process
// took 14,100 page faults and 1.40 s at 4 MiB, 2,000 and 1.27 s at 8 MiB (perf stat, six runs).
// 16 MiB raised the peak by 5 MB.
//
// The tunables are read only when a process starts, hence the restart; it costs one exec (about a
// millisecond). Profilers that follow one process (valgrind) should be given the tunable up front.
#include "cli/huge_pages.h"

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

namespace rigbake::cli {

void restartWithMallocTunables(char** argv) {
#if defined(__SANITIZE_ADDRESS__)
  (void)argv;
#else
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.hugetlb") != nullptr) return;
  std::string value = "glibc.malloc.hugetlb=1";
  if (tunables == nullptr || std::strstr(tunables, "glibc.malloc.arena_max") == nullptr) value += ":glibc.malloc.arena_max=1";
  if (tunables == nullptr || std::strstr(tunables, "glibc.malloc.mmap_threshold") == nullptr)
    value += ":glibc.malloc.mmap_threshold=8388608";
  if (tunables != nullptr && *tunables != '\0') value = std::string(tunables) + ":" + value;
  if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // The exec failed (no /proc, say): carry on as we are, and keep the children from trying again.
#endif
}

}  // namespace rigbake::cli
