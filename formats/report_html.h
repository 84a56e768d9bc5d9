// report.html of `rigbake validate`: one self-contained page (inline CSS and SVG; no script, no
// network, no external font) that a technical artist reads at a glance: the verdict, front and side
// views of skeleton, landmarks and muscles over the body silhouette, each clip's muscle length ratios
// against their [compression, stretch] band, the influence-count histogram, the packed weights'
// deformation error per clip, the skin memory table and the checks table. Deterministic: every number
// is printed with a fixed format, so equal reports give identical bytes.
#pragma once

#include <string>

#include "pipeline/check_report.h"

namespace rigbake {

// The pictures are encoded as PNG on `threads` threads (pipeline/parallel.h); the page is the same at
// any count.
std::string reportHtml(const Report& report, int threads = 1);

}  // namespace rigbake
