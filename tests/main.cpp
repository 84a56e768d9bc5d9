// Catch's main, and where this build tree's programs are (tests/test_support.h). Each build tree compiles
// this file itself; the cases come from the release tree's archive (tests/CMakeLists.txt).
#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>

#include "test_support.h"

namespace rigbake::test {
const char* const kRigbakeCli = RIGBAKE_CLI;
const char* const kRuntimeLibrary = RIGBAKE_RUNTIME_LIBRARY;
const char* const kRuntimeCCheck = RIGBAKE_RUNTIME_C_CHECK;
}  // namespace rigbake::test
