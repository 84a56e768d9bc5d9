// Running rigbake with glibc's malloc on transparent huge pages, one arena and large blocks mapped apart
// (cli/huge_pages.cpp says why).
#pragma once

namespace rigbake::cli {

// When the process was started without glibc.malloc.hugetlb in GLIBC_TUNABLES, starts this program
// again in its place (same arguments, the tunable added to the environment, with one malloc arena and
// blocks of 8 MiB mapped apart unless those are set too) and does not return; the tunables are only
// read when a process starts. Returns, changing nothing, when it is already set (so
// GLIBC_TUNABLES=glibc.malloc.hugetlb=0 opts out), when RIGBAKE_SANITIZE builds bring their own
// allocator, or when the exec fails.
void restartWithMallocTunables(char** argv);

}  // namespace rigbake::cli
