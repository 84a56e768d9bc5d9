// report.junit.xml of `rigbake validate` (and of a batch build's summary): JUnit XML as CI systems
// read it (Jenkins, GitLab, GitHub test reporters). One <testsuite> per character, one <testcase> per
// check; a failed check at error severity is a <failure>, a skipped one <skipped/>, and a failed
// warning or info passes with the finding in <system-out> so that it shows without failing the build.
#pragma once

#include <string>
#include <vector>

#include "pipeline/check_report.h"

namespace rigbake {

std::string reportJunit(const std::vector<Report>& reports);

// Text for XML character data and attribute values: & < > " ' escaped; control characters XML 1.0
// cannot carry become U+FFFD.
std::string xmlEscape(const std::string& text);

}  // namespace rigbake
