// The HTML validation report. Plots are hand-written SVG so that the page needs nothing but a browser:
// no script runs (CI artifact viewers often block scripts), and hover titles (<title>) name each muscle
// and value. Body views follow the usual turnaround sheet: front view with the character's left on the
// viewer's right, side view seen from the character's right so that it faces right.
#include "formats/report_html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "formats/png_write.h"
#include "formats/report_junit.h"
#include "pipeline/parallel.h"

namespace rigbake {
namespace {

std::string num(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  std::string s = text;
  // "-0.0" and "0.0" are the same number; print it one way so output is stable.
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string esc(const std::string& text) { return xmlEscape(text); }

// Stable colours per muscle group (colour-blind safe-ish, distinct on white and on the grey body).
std::string groupColour(const std::string& group) {
  static const std::vector<std::pair<std::string, std::string>> kKnown = {
      {"Trapezius", "#d1495b"},  {"Deltoid", "#e08e0b"},    {"LatissimusDorsi", "#00798c"},
      {"PectoralisMajor", "#8f2d56"}, {"TeresMajor", "#30638e"}, {"Arms", "#3c9d5d"},
  };
  for (const auto& [name, colour] : kKnown) {
    if (name == group) return colour;
  }
  static const char* kSpare[] = {"#6a4c93", "#b5651d", "#1b998b", "#c03221"};
  unsigned sum = 0;
  for (unsigned char c : group) sum += c;
  return kSpare[sum % 4];
}

const CheckResult* findCheck(const Report& report, const std::string& code) {
  for (const CheckResult& check : report.checks) {
    if (check.code == code) return &check;
  }
  return nullptr;
}

std::string formatMeasured(const CheckResult& check) {
  if (!check.has_measured) return "&#8212;";
  const double v = check.measured;
  if (check.unit == "m") return num(v * 1000.0, 4) + " mm";
  if (check.unit == "x body height") return num(v * 100.0, 2) + "% height";
  if (check.unit == "weight" || check.unit == "ratio") return num(v, 6);
  return num(v, 0) + " " + esc(check.unit);
}

std::string formatThreshold(const CheckResult& check) {
  const std::string op = check.comparison == Comparison::kAtMost ? "&#8804; " : "&#8805; ";
  const double v = check.threshold;
  if (check.unit == "m") return op + num(v * 1000.0, 4) + " mm";
  if (check.unit == "x body height") return op + num(v * 100.0, 2) + "% height";
  if (check.unit == "weight" || check.unit == "ratio") return op + num(v, 6);
  return op + num(v, 0) + " " + esc(check.unit);
}

// ---- Body views ----

struct ViewBox {
  double min_u = std::numeric_limits<double>::max(), max_u = std::numeric_limits<double>::lowest();
  double min_v = std::numeric_limits<double>::max(), max_v = std::numeric_limits<double>::lowest();
  double width = 360, height = 500, margin = 18, scale = 1, off_x = 0, off_y = 0;

  void add(double u, double v) {
    min_u = std::min(min_u, u);
    max_u = std::max(max_u, u);
    min_v = std::min(min_v, v);
    max_v = std::max(max_v, v);
  }
  void fit() {
    const double du = std::max(max_u - min_u, 1e-9), dv = std::max(max_v - min_v, 1e-9);
    scale = std::min((width - 2 * margin) / du, (height - 2 * margin - 20) / dv);
    off_x = (width - du * scale) / 2 - min_u * scale;
    off_y = height - margin - (height - 2 * margin - 20 - dv * scale) / 2 + min_v * scale;
  }
  double x(double u) const { return off_x + u * scale; }
  double y(double v) const { return off_y - v * scale; }
};

double projectU(const Eigen::Vector3d& p, bool front) { return front ? p.x() : p.z(); }

std::string bodyView(const Figure& figure, bool front) {
  const Silhouette& s = front ? figure.front : figure.side;
  ViewBox box;
  if (s.columns > 0) {
    box.add(s.min_u, s.min_v);
    box.add(s.min_u + s.columns * s.cell, s.min_v + s.rows * s.cell);
  }
  for (const FigureSegment& bone : figure.bones) {
    box.add(projectU(bone.a, front), bone.a.y());
    box.add(projectU(bone.b, front), bone.b.y());
  }
  for (const FigureMuscle& m : figure.muscles) {
    for (const Eigen::Vector3d* p : {&m.origin, &m.driver, &m.insertion}) box.add(projectU(*p, front), p->y());
  }
  if (box.min_u > box.max_u) return "";
  // Fixed height; the width follows the view's aspect so a T-pose front view is not shrunk.
  box.height = 560;
  const double aspect = (box.max_u - box.min_u) / std::max(box.max_v - box.min_v, 1e-9);
  box.width = std::clamp(aspect * (box.height - 2 * box.margin - 20) + 2 * box.margin, 280.0, 720.0);
  box.fit();
  std::string svg = "<svg class=\"view\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(box.width, 0) +
                    "\" height=\"" + num(box.height, 0) + "\" viewBox=\"0 0 " + num(box.width, 0) + " " +
                    num(box.height, 0) + "\" role=\"img\" aria-label=\"" +
                    (front ? "front view" : "side view") + "\">\n";
  svg += "<text class=\"view-title\" x=\"12\" y=\"20\">" + std::string(front ? "Front" : "Side (from the right, facing right)") +
         "</text>\n";
  // Silhouette: the filled runs of the grid, one sub-path per run.
  std::string path;
  for (const auto& run : s.runs) {
    const double x0 = box.x(s.min_u + run[1] * s.cell), x1 = box.x(s.min_u + run[2] * s.cell);
    const double top = box.y(s.min_v + (run[0] + 1) * s.cell), bottom = box.y(s.min_v + run[0] * s.cell);
    path += "M" + num(x0, 1) + " " + num(top, 1) + "H" + num(x1, 1) + "V" + num(bottom, 1) + "H" + num(x0, 1) + "Z";
  }
  svg += "<path class=\"silhouette\" d=\"" + path + "\"/>\n";
  if (s.columns > 0) {
    const double ground = box.y(s.min_v + s.cell);
    svg += "<line class=\"ground\" x1=\"" + num(box.margin, 1) + "\" y1=\"" + num(ground, 1) + "\" x2=\"" +
           num(box.width - box.margin, 1) + "\" y2=\"" + num(ground, 1) + "\"/>\n";
  }
  svg += "<g class=\"bones\">";
  for (const FigureSegment& bone : figure.bones) {
    svg += "<line x1=\"" + num(box.x(projectU(bone.a, front)), 1) + "\" y1=\"" + num(box.y(bone.a.y()), 1) +
           "\" x2=\"" + num(box.x(projectU(bone.b, front)), 1) + "\" y2=\"" + num(box.y(bone.b.y()), 1) + "\"/>";
  }
  svg += "</g>\n<g class=\"joints\">";
  for (const FigureSegment& bone : figure.bones) {
    svg += "<circle cx=\"" + num(box.x(projectU(bone.b, front)), 1) + "\" cy=\"" + num(box.y(bone.b.y()), 1) +
           "\" r=\"1.8\"/>";
  }
  svg += "</g>\n<g class=\"landmarks\">";
  for (const FigureLandmark& landmark : figure.landmarks) {
    const double x = box.x(projectU(landmark.position, front)), y = box.y(landmark.position.y());
    svg += "<path d=\"M" + num(x, 1) + " " + num(y - 3.5, 1) + "l3.5 3.5l-3.5 3.5l-3.5 -3.5Z\"><title>" +
           esc(landmark.name) + "</title></path>";
  }
  svg += "</g>\n";
  // Far muscles first: the front view is seen from +forward, the side view from the right (-lateral).
  std::vector<const FigureMuscle*> order;
  for (const FigureMuscle& m : figure.muscles) order.push_back(&m);
  std::stable_sort(order.begin(), order.end(), [front](const FigureMuscle* a, const FigureMuscle* b) {
    return front ? a->driver.z() < b->driver.z() : a->driver.x() > b->driver.x();
  });
  svg += "<g class=\"muscles\">";
  for (const FigureMuscle* m : order) {
    const std::string colour = groupColour(m->group);
    const std::string points = num(box.x(projectU(m->origin, front)), 1) + "," + num(box.y(m->origin.y()), 1) + " " +
                               num(box.x(projectU(m->driver, front)), 1) + "," + num(box.y(m->driver.y()), 1) + " " +
                               num(box.x(projectU(m->insertion, front)), 1) + "," + num(box.y(m->insertion.y()), 1);
    svg += "<g class=\"muscle" + std::string(m->flagged ? " flagged" : "") + "\"><title>" + esc(m->name) + " (" +
           esc(m->group) + ")" + (m->flagged ? " - a locator check failed" : "") + "</title>";
    if (m->flagged) svg += "<polyline class=\"halo\" points=\"" + points + "\"/>";
    svg += "<polyline points=\"" + points + "\" stroke=\"" + colour + "\"/>";
    svg += "<circle class=\"origin\" cx=\"" + num(box.x(projectU(m->origin, front)), 1) + "\" cy=\"" +
           num(box.y(m->origin.y()), 1) + "\" r=\"3.2\" fill=\"" + colour + "\"/>";
    svg += "<circle class=\"insertion\" cx=\"" + num(box.x(projectU(m->insertion, front)), 1) + "\" cy=\"" +
           num(box.y(m->insertion.y()), 1) + "\" r=\"3.2\" stroke=\"" + colour + "\"/>";
    svg += "</g>";
  }
  svg += "</g>\n";
  // A scale bar of 10% of the body height.
  if (figure.height > 0.0) {
    const double bar = 0.1 * figure.height * box.scale;
    const double y = box.height - 8;
    svg += "<g class=\"scalebar\"><line x1=\"12\" y1=\"" + num(y, 1) + "\" x2=\"" + num(12 + bar, 1) + "\" y2=\"" +
           num(y, 1) + "\"/><text x=\"" + num(16 + bar, 1) + "\" y=\"" + num(y + 3, 1) + "\">" +
           num(0.1 * figure.height, 3) + " (10% of height " + num(figure.height, 3) + ")</text></g>\n";
  }
  svg += "</svg>\n";
  return svg;
}

std::string groupLegend(const std::vector<std::string>& groups, bool with_sides) {
  std::string html = "<div class=\"legend\">";
  for (const std::string& group : groups) {
    html += "<span><svg width=\"22\" height=\"10\"><line x1=\"1\" y1=\"5\" x2=\"21\" y2=\"5\" stroke=\"" +
            groupColour(group) + "\" stroke-width=\"4\"/></svg>" + esc(group) + "</span>";
  }
  if (with_sides) {
    html += "<span><svg width=\"22\" height=\"10\"><line x1=\"1\" y1=\"5\" x2=\"21\" y2=\"5\" stroke=\"#444\" "
            "stroke-width=\"2\"/></svg>Left</span>";
    html += "<span><svg width=\"22\" height=\"10\"><line x1=\"1\" y1=\"5\" x2=\"21\" y2=\"5\" stroke=\"#444\" "
            "stroke-width=\"2\" stroke-dasharray=\"4 3\"/></svg>Right</span>";
  }
  html += "</div>\n";
  return html;
}

std::vector<std::string> groupsOf(const Report& report) {
  std::vector<std::string> groups;
  auto add = [&](const std::string& g) {
    if (std::find(groups.begin(), groups.end(), g) == groups.end()) groups.push_back(g);
  };
  for (const FigureMuscle& m : report.figure.muscles) add(m.group);
  for (const ClipRatios& clip : report.ratios) {
    for (const MuscleRatioSeries& series : clip.muscles) add(series.group);
  }
  return groups;
}

// ---- Muscle ratio charts ----

std::string ratioChart(const ClipRatios& clip) {
  const double W = 560, H = 230, left = 46, right = 14, top = 26, bottom = 30;
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  double cmin = lo, cmax = hi, smin = lo, smax = hi;
  for (const MuscleRatioSeries& series : clip.muscles) {
    cmin = std::min(cmin, series.compression);
    cmax = std::max(cmax, series.compression);
    smin = std::min(smin, series.stretch);
    smax = std::max(smax, series.stretch);
    for (double r : series.ratio) {
      lo = std::min(lo, r);
      hi = std::max(hi, r);
    }
  }
  if (clip.muscles.empty()) return "";
  lo = std::min(lo, cmin) - 0.05;
  hi = std::max(hi, smax) + 0.05;
  const double t0 = clip.times.empty() ? 0.0 : clip.times.front();
  const double t1 = clip.times.empty() ? 0.0 : clip.times.back();
  auto X = [&](double t) { return t1 > t0 ? left + (t - t0) / (t1 - t0) * (W - left - right) : (W + left - right) / 2; };
  auto Y = [&](double r) { return top + (hi - r) / (hi - lo) * (H - top - bottom); };
  std::string svg = "<svg class=\"chart ratio\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(W, 0) +
                    "\" height=\"" + num(H, 0) + "\" viewBox=\"0 0 " + num(W, 0) + " " + num(H, 0) +
                    "\" role=\"img\" aria-label=\"muscle length ratio over time, clip " + esc(clip.clip) + "\">\n";
  svg += "<text class=\"chart-title\" x=\"" + num(left, 0) + "\" y=\"16\">" + esc(clip.clip) + "</text>\n";
  // Band: dark where every muscle's band overlaps, light where only some muscles' bands reach.
  svg += "<rect class=\"band-outer\" x=\"" + num(left, 1) + "\" y=\"" + num(Y(smax), 1) + "\" width=\"" +
         num(W - left - right, 1) + "\" height=\"" + num(Y(cmin) - Y(smax), 1) + "\"/>\n";
  if (smin > cmax) {
    svg += "<rect class=\"band\" x=\"" + num(left, 1) + "\" y=\"" + num(Y(smin), 1) + "\" width=\"" +
           num(W - left - right, 1) + "\" height=\"" + num(Y(cmax) - Y(smin), 1) + "\"><title>[compression, stretch] = [" +
           num(cmax, 2) + ", " + num(smin, 2) + "]</title></rect>\n";
  }
  // Axes and gridlines every 0.25 of ratio.
  svg += "<g class=\"axis\">";
  for (double g = std::ceil(lo * 4) / 4; g <= hi + 1e-9; g += 0.25) {
    svg += "<line class=\"grid" + std::string(std::abs(g - 1.0) < 1e-9 ? " rest" : "") + "\" x1=\"" + num(left, 1) +
           "\" y1=\"" + num(Y(g), 1) + "\" x2=\"" + num(W - right, 1) + "\" y2=\"" + num(Y(g), 1) + "\"/>";
    svg += "<text x=\"" + num(left - 5, 1) + "\" y=\"" + num(Y(g) + 4, 1) + "\" text-anchor=\"end\">" + num(g, 2) + "</text>";
  }
  svg += "<line x1=\"" + num(left, 1) + "\" y1=\"" + num(H - bottom, 1) + "\" x2=\"" + num(W - right, 1) + "\" y2=\"" +
         num(H - bottom, 1) + "\"/>";
  svg += "<text x=\"" + num(left, 1) + "\" y=\"" + num(H - bottom + 16, 1) + "\">" + num(t0, 2) + " s</text>";
  svg += "<text x=\"" + num(W - right, 1) + "\" y=\"" + num(H - bottom + 16, 1) + "\" text-anchor=\"end\">" + num(t1, 2) +
         " s</text>";
  svg += "<text x=\"" + num((W + left - right) / 2, 1) + "\" y=\"" + num(H - bottom + 16, 1) +
         "\" text-anchor=\"middle\">" + std::to_string(clip.times.size()) + " samples</text>";
  svg += "<text class=\"band-label\" x=\"" + num(W - right - 4, 1) + "\" y=\"" + num(Y(smax) - 3, 1) +
         "\" text-anchor=\"end\">stretch " + num(smax, 2) + "</text>";
  svg += "<text class=\"band-label\" x=\"" + num(W - right - 4, 1) + "\" y=\"" + num(Y(cmin) + 11, 1) +
         "\" text-anchor=\"end\">compression " + num(cmin, 2) + "</text>";
  svg += "</g>\n<g class=\"series\">";
  const MuscleRatioSeries* extreme = nullptr;
  size_t extreme_t = 0;
  double extreme_distance = -1.0;
  for (const MuscleRatioSeries& series : clip.muscles) {
    std::string points;
    for (size_t t = 0; t < series.ratio.size() && t < clip.times.size(); ++t) {
      points += (t ? " " : "") + num(X(clip.times[t]), 1) + "," + num(Y(series.ratio[t]), 1);
      const double distance = std::abs(series.ratio[t] - 1.0);
      if (distance > extreme_distance) {
        extreme_distance = distance;
        extreme = &series;
        extreme_t = t;
      }
    }
    const bool right_side = series.muscle.rfind("Right", 0) == 0;
    svg += "<polyline points=\"" + points + "\" stroke=\"" + groupColour(series.group) + "\"" +
           (right_side ? " stroke-dasharray=\"5 3\"" : "") + "><title>" + esc(series.muscle) + "</title></polyline>";
  }
  svg += "</g>\n";
  // Samples outside the band, and a label on the muscle that moves furthest from rest.
  svg += "<g class=\"outside\">";
  for (const MuscleRatioSeries& series : clip.muscles) {
    for (size_t t = 0; t < series.ratio.size() && t < clip.times.size(); ++t) {
      const double r = series.ratio[t];
      if (r >= series.compression && r <= series.stretch) continue;
      svg += "<circle cx=\"" + num(X(clip.times[t]), 1) + "\" cy=\"" + num(Y(r), 1) + "\" r=\"3\"><title>" +
             esc(series.muscle) + " " + num(r, 3) + " at " + num(clip.times[t], 3) + " s</title></circle>";
    }
  }
  svg += "</g>\n";
  if (extreme && !extreme->ratio.empty()) {
    const double x = X(clip.times[extreme_t]), y = Y(extreme->ratio[extreme_t]);
    const bool anchor_end = x > W * 0.7;
    svg += "<g class=\"callout\"><circle cx=\"" + num(x, 1) + "\" cy=\"" + num(y, 1) + "\" r=\"3\"/><text x=\"" +
           num(anchor_end ? x - 6 : x + 6, 1) + "\" y=\"" + num(y < top + 14 ? y + 14 : y - 6, 1) + "\"" +
           (anchor_end ? " text-anchor=\"end\"" : "") + ">" + esc(extreme->muscle) + " " +
           num(extreme->ratio[extreme_t], 3) + "</text></g>\n";
  }
  svg += "</svg>\n";
  return svg;
}

// ---- Jiggle angle charts ----

// One chart per clip: each jiggle's angle from its animated direction (solid) against its cone's
// half-angle in that direction (dashed, same colour). The clamp holds when no solid line crosses its
// dashed twin.
std::string jiggleChart(const ClipJiggles& clip) {
  if (clip.jiggles.empty() || clip.times.empty()) return "";
  static const char* kColours[] = {"#d1495b", "#00798c", "#e08e0b", "#30638e", "#3c9d5d", "#8f2d56", "#6a4c93", "#b5651d"};
  const double W = 560, H = 230, left = 46, right = 14, top = 26, bottom = 30;
  double largest_angle = 0.0, largest_clamp = 0.0;
  for (const JiggleSeries& series : clip.jiggles) {
    for (double a : series.angle_deg) largest_angle = std::max(largest_angle, a);
    for (double c : series.clamp_deg) largest_clamp = std::max(largest_clamp, c);
  }
  // A 90-degree cone would flatten swings of a few degrees: the axis follows the motion and shows a
  // cone only when it comes near (dashed lines above the top are drawn at the top).
  const double hi = std::min(90.0, 1.1 * std::max({1.0, largest_angle, std::min(largest_clamp, 1.5 * largest_angle + 1.0)}));
  const double t0 = clip.times.front(), t1 = clip.times.back();
  auto X = [&](double t) { return t1 > t0 ? left + (t - t0) / (t1 - t0) * (W - left - right) : (W + left - right) / 2; };
  auto Y = [&](double a) { return top + (hi - std::min(a, hi)) / hi * (H - top - bottom); };
  std::string svg = "<svg class=\"chart jiggle\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(W, 0) +
                    "\" height=\"" + num(H, 0) + "\" viewBox=\"0 0 " + num(W, 0) + " " + num(H, 0) +
                    "\" role=\"img\" aria-label=\"jiggle angle over time, clip " + esc(clip.clip) + "\">\n";
  svg += "<text class=\"chart-title\" x=\"" + num(left, 0) + "\" y=\"16\">" + esc(clip.clip) + "</text>\n<g class=\"axis\">";
  const double step = hi > 40 ? 15 : hi > 12 ? 5 : hi > 4 ? 1 : 0.5;
  for (double g = 0; g <= hi + 1e-9; g += step) {
    svg += "<line class=\"grid\" x1=\"" + num(left, 1) + "\" y1=\"" + num(Y(g), 1) + "\" x2=\"" + num(W - right, 1) +
           "\" y2=\"" + num(Y(g), 1) + "\"/><text x=\"" + num(left - 5, 1) + "\" y=\"" + num(Y(g) + 4, 1) +
           "\" text-anchor=\"end\">" + num(g, step < 1 ? 1 : 0) + "&#176;</text>";
  }
  svg += "<line x1=\"" + num(left, 1) + "\" y1=\"" + num(H - bottom, 1) + "\" x2=\"" + num(W - right, 1) + "\" y2=\"" +
         num(H - bottom, 1) + "\"/>";
  svg += "<text x=\"" + num(left, 1) + "\" y=\"" + num(H - bottom + 16, 1) + "\">" + num(t0, 2) + " s</text>";
  svg += "<text x=\"" + num(W - right, 1) + "\" y=\"" + num(H - bottom + 16, 1) + "\" text-anchor=\"end\">" + num(t1, 2) +
         " s</text></g>\n<g class=\"series\">";
  for (size_t j = 0; j < clip.jiggles.size(); ++j) {
    const JiggleSeries& series = clip.jiggles[j];
    const std::string colour = kColours[j % 8];
    std::string angle, clamp;
    for (size_t t = 0; t < clip.times.size() && t < series.angle_deg.size() && t < series.clamp_deg.size(); ++t) {
      angle += (t ? " " : "") + num(X(clip.times[t]), 1) + "," + num(Y(series.angle_deg[t]), 1);
      clamp += (t ? " " : "") + num(X(clip.times[t]), 1) + "," + num(Y(series.clamp_deg[t]), 1);
    }
    svg += "<polyline points=\"" + clamp + "\" stroke=\"" + colour + "\" stroke-dasharray=\"5 3\"><title>" +
           esc(series.joint) + " cone half-angle</title></polyline>";
    svg += "<polyline points=\"" + angle + "\" stroke=\"" + colour + "\"><title>" + esc(series.joint) +
           " angle</title></polyline>";
  }
  svg += "</g>\n<g class=\"legend\">";
  for (size_t j = 0; j < clip.jiggles.size() && j < 8; ++j) {
    const double y = top + 4 + 12.0 * static_cast<double>(j);
    svg += "<line x1=\"" + num(W - right - 150, 1) + "\" y1=\"" + num(y, 1) + "\" x2=\"" + num(W - right - 136, 1) +
           "\" y2=\"" + num(y, 1) + "\" stroke=\"" + kColours[j % 8] + "\" stroke-width=\"2\"/><text x=\"" +
           num(W - right - 132, 1) + "\" y=\"" + num(y + 4, 1) + "\">" + esc(clip.jiggles[j].joint) + "</text>";
  }
  svg += "</g>\n</svg>\n";
  return svg;
}

// ---- Histogram, deformation bars ----

std::string histogramChart(const Report& report) {
  const std::vector<std::int64_t>& h = report.influence_histogram;
  if (h.empty()) return "<p class=\"note\">No skinned primitive.</p>\n";
  const CheckResult* check = findCheck(report, "INFLUENCE_COUNT");
  const double limit = check ? check->threshold : 1e9;
  const double W = 560, H = 250, left = 56, right = 14, top = 24, bottom = 34;
  std::int64_t most = 1;
  for (std::int64_t count : h) most = std::max(most, count);
  const int bins = static_cast<int>(h.size());
  const double slot = (W - left - right) / bins;
  auto Y = [&](double count) { return top + (1.0 - count / static_cast<double>(most)) * (H - top - bottom); };
  std::string svg = "<svg class=\"chart histogram\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(W, 0) +
                    "\" height=\"" + num(H, 0) + "\" viewBox=\"0 0 " + num(W, 0) + " " + num(H, 0) +
                    "\" role=\"img\" aria-label=\"influence count histogram\">\n<g class=\"axis\">";
  for (int k = 0; k <= 4; ++k) {
    const double count = most * k / 4.0;
    svg += "<line class=\"grid\" x1=\"" + num(left, 1) + "\" y1=\"" + num(Y(count), 1) + "\" x2=\"" + num(W - right, 1) +
           "\" y2=\"" + num(Y(count), 1) + "\"/><text x=\"" + num(left - 5, 1) + "\" y=\"" + num(Y(count) + 4, 1) +
           "\" text-anchor=\"end\">" + num(count, 0) + "</text>";
  }
  svg += "<text x=\"" + num((W + left - right) / 2, 1) + "\" y=\"" + num(H - 4, 1) +
         "\" text-anchor=\"middle\">non-zero influences per vertex</text></g>\n<g class=\"bars\">";
  for (int n = 0; n < bins; ++n) {
    const double x = left + n * slot + slot * 0.15, w = slot * 0.7;
    svg += "<rect class=\"" + std::string(n > limit ? "over" : "ok") + "\" x=\"" + num(x, 1) + "\" y=\"" +
           num(Y(static_cast<double>(h[n])), 1) + "\" width=\"" + num(w, 1) + "\" height=\"" +
           num(H - bottom - Y(static_cast<double>(h[n])), 1) + "\"><title>" + std::to_string(h[n]) + " vertices with " +
           std::to_string(n) + " influences</title></rect>";
    svg += "<text class=\"count\" x=\"" + num(x + w / 2, 1) + "\" y=\"" + num(Y(static_cast<double>(h[n])) - 4, 1) +
           "\" text-anchor=\"middle\">" + std::to_string(h[n]) + "</text>";
    svg += "<text x=\"" + num(x + w / 2, 1) + "\" y=\"" + num(H - bottom + 14, 1) + "\" text-anchor=\"middle\">" +
           std::to_string(n) + "</text>";
  }
  svg += "</g>\n</svg>\n";
  return svg;
}

std::string deformationChart(const Report& report) {
  if (report.deformation.empty()) return "<p class=\"note\">No packed influences to compare.</p>\n";
  const CheckResult* check = findCheck(report, "PACKED_DEFORMATION_ERROR");
  const double threshold_mm = check ? check->threshold * 1000.0 : 0.0;
  const double W = 560, left = 190, right = 96, row = 22, top = 10;
  const double H = top + row * report.deformation.size() + 30;
  double most = 0.0;
  for (const ClipDeformation& clip : report.deformation) most = std::max(most, clip.max_displacement * 1000.0);
  // Scale to the data; the threshold line is drawn when it is on the scale, otherwise named.
  const bool threshold_on_scale = threshold_mm <= most * 1.25;
  const double full = std::max(threshold_on_scale ? std::max(most, threshold_mm) * 1.05 : most * 1.05, 1e-9);
  auto X = [&](double mm) { return left + mm / full * (W - left - right); };
  std::string svg = "<svg class=\"chart deformation\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(W, 0) +
                    "\" height=\"" + num(H, 0) + "\" viewBox=\"0 0 " + num(W, 0) + " " + num(H, 0) +
                    "\" role=\"img\" aria-label=\"packed deformation error per clip\">\n";
  for (size_t i = 0; i < report.deformation.size(); ++i) {
    const ClipDeformation& clip = report.deformation[i];
    const double y = top + row * i;
    std::string name = clip.clip.size() > 30 ? clip.clip.substr(0, 29) + "..." : clip.clip;
    const double max_mm = clip.max_displacement * 1000.0, rms_mm = clip.rms_displacement * 1000.0;
    const bool over = check && check->comparison == Comparison::kAtMost && max_mm > threshold_mm;
    svg += "<g><title>" + esc(clip.clip) + ": max " + num(max_mm, 5) + " mm, rms " + num(rms_mm, 5) + " mm over " +
           std::to_string(clip.samples) + " samples</title>";
    svg += "<text class=\"label\" x=\"" + num(left - 8, 1) + "\" y=\"" + num(y + 15, 1) + "\" text-anchor=\"end\">" +
           esc(name) + "</text>";
    svg += "<rect class=\"max" + std::string(over ? " over" : "") + "\" x=\"" + num(left, 1) + "\" y=\"" + num(y + 4, 1) +
           "\" width=\"" + num(X(max_mm) - left, 1) + "\" height=\"14\"/>";
    svg += "<rect class=\"rms\" x=\"" + num(left, 1) + "\" y=\"" + num(y + 8, 1) + "\" width=\"" + num(X(rms_mm) - left, 1) +
           "\" height=\"6\"/>";
    svg += "<text class=\"value\" x=\"" + num(X(max_mm) + 5, 1) + "\" y=\"" + num(y + 15, 1) + "\">" + num(max_mm, 4) +
           " mm</text></g>\n";
  }
  const double axis_y = top + row * report.deformation.size() + 4;
  svg += "<g class=\"axis\"><line x1=\"" + num(left, 1) + "\" y1=\"" + num(axis_y, 1) + "\" x2=\"" + num(W - right, 1) +
         "\" y2=\"" + num(axis_y, 1) + "\"/><text x=\"" + num(left, 1) + "\" y=\"" + num(axis_y + 16, 1) +
         "\">0</text><text x=\"" + num(W - right, 1) + "\" y=\"" + num(axis_y + 16, 1) + "\" text-anchor=\"end\">" +
         num(full, 4) + " mm</text></g>\n";
  if (check && threshold_on_scale) {
    svg += "<g class=\"threshold\"><line x1=\"" + num(X(threshold_mm), 1) + "\" y1=\"" + num(top, 1) + "\" x2=\"" +
           num(X(threshold_mm), 1) + "\" y2=\"" + num(axis_y, 1) + "\"/><text x=\"" + num(X(threshold_mm), 1) +
           "\" y=\"" + num(axis_y + 16, 1) + "\" text-anchor=\"middle\">threshold</text></g>\n";
  }
  svg += "</svg>\n";
  if (check && !threshold_on_scale) {
    svg += "<p class=\"note\">Threshold " + num(threshold_mm, 4) + " mm is " + num(threshold_mm / std::max(most, 1e-12), 0) +
           "&#215; the largest error, off this scale.</p>\n";
  }
  return svg;
}

// ---- Tables ----

std::string checksTable(const Report& report) {
  std::string html =
      "<table class=\"checks\">\n<thead><tr><th>status</th><th>check</th><th>severity</th><th>measured</th>"
      "<th>threshold</th><th>where / what</th></tr></thead>\n<tbody>\n";
  for (const CheckResult& check : report.checks) {
    const std::string status = statusName(check.status);
    const std::string row_class = check.status == CheckStatus::kFail ? "fail-" + std::string(severityName(check.severity))
                                                                     : status;
    html += "<tr class=\"" + row_class + "\"><td><span class=\"chip " + row_class + "\">" + status + "</span></td>";
    html += "<td><code>" + esc(check.code) + "</code><div class=\"title\">" + esc(check.title) + "</div></td>";
    html += "<td>" + std::string(severityName(check.severity)) + "</td>";
    html += "<td class=\"num\">" + formatMeasured(check) + "</td><td class=\"num\">" + formatThreshold(check) + "</td>";
    html += "<td>" + (check.location.empty() ? std::string() : "<code>" + esc(check.location) + "</code><br>") +
            esc(check.message);
    if (!check.findings.empty()) {
      html += "<details><summary>" + std::to_string(check.findings.size()) + " worst items</summary><ul>";
      for (const CheckFinding& finding : check.findings) {
        html += "<li><code>" + esc(finding.location) + "</code> " + esc(finding.message) + "</li>";
      }
      html += "</ul></details>";
    }
    html += "</td></tr>\n";
  }
  html += "</tbody></table>\n";
  return html;
}

std::string memoryTable(const Report& report) {
  int most = 1;
  for (const SkinLayoutSize& layout : report.memory) most = std::max(most, layout.bytes_per_vertex);
  std::string html =
      "<table class=\"memory\">\n<thead><tr><th>layout</th><th>influences</th><th>bytes / vertex</th><th></th>"
      "<th>total for " + std::to_string(report.vertices) + " vertices</th></tr></thead>\n<tbody>\n";
  for (const SkinLayoutSize& layout : report.memory) {
    const bool this_file = layout.kind == SkinLayoutKind::kPacked && layout.influences == report.influences;
    html += "<tr" + std::string(this_file ? " class=\"this-file\"" : "") + "><td><code>" + esc(layout.id) + "</code>" +
            (this_file ? " <span class=\"tag\">this bake</span>" : "") + "</td><td class=\"num\">" +
            std::to_string(layout.influences) + "</td><td class=\"num\">" + std::to_string(layout.bytes_per_vertex) +
            "</td><td><svg width=\"160\" height=\"10\"><rect width=\"" +
            num(160.0 * layout.bytes_per_vertex / most, 1) + "\" height=\"10\"/></svg></td><td class=\"num\">" +
            num(layout.total_bytes / 1024.0, 1) + " KiB</td></tr>\n";
  }
  html += "</tbody></table>\n";
  return html;
}

const char* kStyle = R"(
:root { --ok: #2e7d32; --fail: #c62828; --warn: #b26a00; --skip: #757575; --ink: #1d2330; --muted: #5f6673; }
* { box-sizing: border-box; }
body { margin: 0; font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
       color: var(--ink); background: #f4f5f7; }
header { padding: 20px 32px; background: #fff; border-bottom: 1px solid #dde1e6; display: flex; gap: 24px; align-items: center; }
header h1 { margin: 0; font-size: 22px; }
header .sub { color: var(--muted); }
.verdict { font-weight: 700; font-size: 18px; padding: 6px 16px; border-radius: 6px; color: #fff; }
.verdict.pass { background: var(--ok); } .verdict.fail { background: var(--fail); }
main { padding: 16px 32px 40px; max-width: 1260px; }
section { background: #fff; border: 1px solid #dde1e6; border-radius: 8px; padding: 14px 18px; margin: 16px 0; }
section h2 { margin: 0 0 8px; font-size: 16px; }
.pictures figure { display: inline-block; margin: 6px 10px 10px 0; max-width: 620px; }
.pictures figcaption { font-size: 12px; color: var(--muted); }
table.quality td:nth-child(n+3) { text-align: right; font-variant-numeric: tabular-nums; }
table.quality tr.fail td { color: #b3261e; font-weight: 600; }
section p.explain { margin: 0 0 10px; color: var(--muted); max-width: 900px; }
.row { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
.row > section { flex: 1 1 580px; min-width: 0; }
.grid { display: flex; flex-wrap: wrap; gap: 10px; }
table { border-collapse: collapse; width: 100%; }
th, td { text-align: left; padding: 6px 8px; border-bottom: 1px solid #eceef1; vertical-align: top; }
th { font-size: 12px; text-transform: uppercase; letter-spacing: .04em; color: var(--muted); }
td.num { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
td .title { color: var(--muted); font-size: 12px; }
code { font: 12px/1.4 ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace; }
.chip { display: inline-block; min-width: 58px; text-align: center; padding: 2px 8px; border-radius: 10px; color: #fff;
        font-size: 12px; font-weight: 600; }
.chip.pass { background: var(--ok); } .chip.skipped { background: var(--skip); }
.chip.fail-error { background: var(--fail); } .chip.fail-warning, .chip.fail-info { background: var(--warn); }
tr.fail-error td { background: #fdecea; } tr.fail-warning td, tr.fail-info td { background: #fff4e0; }
tr.skipped td { color: var(--muted); }
details summary { cursor: pointer; color: var(--muted); font-size: 12px; }
details ul { margin: 4px 0; padding-left: 18px; font-size: 12px; }
.stats { display: flex; gap: 18px; color: var(--muted); }
.stats b { color: var(--ink); font-size: 16px; display: block; }
.legend { display: flex; flex-wrap: wrap; gap: 14px; font-size: 12px; color: var(--muted); margin: 4px 0 8px; }
.legend span { display: inline-flex; align-items: center; gap: 5px; }
.note { color: var(--muted); font-size: 12px; }
svg text { font: 11px system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif; fill: #4a505c; }
svg .view-title, svg .chart-title { font-size: 13px; font-weight: 600; fill: var(--ink); }
svg.view { background: #fbfbfc; border: 1px solid #eceef1; border-radius: 6px; }
.silhouette { fill: #d9dde3; shape-rendering: crispEdges; }
.ground { stroke: #b8bec8; stroke-width: 1; }
.bones line { stroke: #59606b; stroke-width: 2; stroke-linecap: round; }
.joints circle { fill: #59606b; }
.landmarks path { fill: #fff; stroke: #0b7a75; stroke-width: 1.3; }
.muscle polyline { fill: none; stroke-width: 4; stroke-linecap: round; stroke-linejoin: round; opacity: .9; }
.muscle .halo { stroke: var(--fail); stroke-width: 11; opacity: .35; }
.muscle .insertion { fill: #fff; stroke-width: 2; }
.scalebar line { stroke: var(--ink); stroke-width: 2; }
.chart { background: #fff; border: 1px solid #eceef1; border-radius: 6px; }
.axis line { stroke: #9aa1ab; stroke-width: 1; } .axis .grid { stroke: #eceef1; } .axis .grid.rest { stroke: #9aa1ab; stroke-dasharray: 3 3; }
.band { fill: #2e7d32; opacity: .12; } .band-outer { fill: #2e7d32; opacity: .05; }
.band-label { fill: #2e7d32; font-size: 10px; }
.series polyline { fill: none; stroke-width: 1.6; opacity: .85; }
.legend text { font-size: 10px; fill: var(--ink); }
.outside circle { fill: var(--fail); }
.callout circle { fill: var(--ink); } .callout text { font-weight: 600; fill: var(--ink); }
.histogram .ok { fill: #30638e; } .histogram .over { fill: var(--fail); } .histogram .count { fill: var(--ink); }
.deformation .max { fill: #9cc3e6; } .deformation .max.over { fill: #ef9a9a; } .deformation .rms { fill: #30638e; }
.deformation .value { fill: var(--ink); }
.threshold line { stroke: var(--fail); stroke-dasharray: 4 3; stroke-width: 1.5; } .threshold text { fill: var(--fail); }
table.memory svg rect { fill: #30638e; } tr.this-file td { background: #eaf2fb; font-weight: 600; }
.tag { font-size: 11px; background: #30638e; color: #fff; padding: 1px 6px; border-radius: 8px; }
)";

}  // namespace

namespace {

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof(text), "%+.2f", 100.0 * fraction);
  return text;
}

// The skin's surface per clip, the four skinnings side by side: roughness rise and strain (95th
// percentiles of the moving skin, docs/deformation-quality.md). A row is marked where the rig's figure
// over plain skinning's passes the threshold of SKIN_ROUGHNESS_RISE or SKIN_STRAIN (as --config set it).
std::string skinSurfaceTable(const Report& report) {
  const CheckResult* roughness = findCheck(report, "SKIN_ROUGHNESS_RISE");
  const CheckResult* strain = findCheck(report, "SKIN_STRAIN");
  std::string html;
  for (const ClipQuality& clip : report.quality.quality.clips) {
    if (!clip.surface.measured) continue;
    auto row = [&](const std::string& figure, const double (&values)[kSurfaceSkinnings], double scale, double floor,
                   const CheckResult* check, const char* format) {
      const bool worse = check && rigOverPlain(values, floor) > check->threshold;
      html += "<tr" + std::string(worse ? " class=\"fail\"" : "") + "><td>" + esc(clip.clip) + "</td><td>" + figure + "</td>";
      for (int s = 0; s < kSurfaceSkinnings; ++s) {
        char text[32];
        std::snprintf(text, sizeof(text), format, scale * values[s]);
        html += "<td>" + std::string(text) + "</td>";
      }
      html += "</tr>\n";
    };
    row("roughness rise, mm", clip.surface.roughness_rise, 1000.0, clip.surface.roughness_floor, roughness, "%.3f");
    row("edge strain, %", clip.surface.edge_strain, 100.0, kStrainFloor, strain, "%.1f");
    row("triangle-area strain, %", clip.surface.area_strain, 100.0, kStrainFloor, strain, "%.1f");
  }
  if (html.empty()) return html;
  return "<p class=\"explain\">The moving skin's surface: its roughness rise over the bind pose (how far a vertex stands out of "
         "its neighbours' plane, beyond its bind value) and its strain (edge lengths and triangle areas against the bind pose), "
         "each the 95th percentile over the skin that moves, the largest over the clip's most deformed samples. A row is marked "
         "where the rig passes its check's multiple of plain skinning's (SKIN_ROUGHNESS_RISE, SKIN_STRAIN).</p>\n<table class=\"quality\"><tr><th>clip</th><th>figure</th>"
         "<th>plain</th><th>dual quaternions</th><th>centres of rotation</th><th>rig</th></tr>\n" +
         html + "</table>\n";
}

// Volume change per clip (whole body) and the worst regions, input skinning / dual quaternions / rig,
// then the skin's surface figures and the pictures.
// `picture_uris`: each of report.quality.pictures as a PNG data URI, in order.
std::string qualitySection(const Report& report, const std::vector<std::string>& picture_uris) {
  const BakedQuality& baked = report.quality;
  std::string html = "<section id=\"quality\"><h2>Deformation quality: volume and bulge</h2>\n<p class=\"explain\">"
                     "Largest volume change against the bind pose over each clip, in percent, of the input skinning "
                     "(" + (baked.input_source.empty() ? std::string("the file's weights with each muscle joint's weight returned to its carrier")
                                                      : "the weights of " + esc(baked.input_source) + ", the character it was baked from") +
                     "), of dual-quaternion "
                     "skinning of those weights, and of the baked rig as an engine evaluates it "
                     "(docs/deformation-quality.md). Regions are closed by capping their holes. The occupied row counts each point "
                     "inside the skin once, where the signed volume counts skin pushed through opposing skin twice.</p>\n";
  if (!baked.measured) return html + "<p class=\"note\">Not measured: " + esc(baked.skip_reason) + "</p>\n</section>\n";
  const DeformationQuality& quality = baked.quality;
  html += "<table class=\"quality\"><tr><th>clip</th><th>region</th><th>input %</th><th>dual quaternion %</th><th>rig %</th></tr>\n";
  for (const ClipQuality& clip : quality.clips) {
    auto row = [&](const std::string& region, const SkinningVolumes& v) {
      const bool worse = std::min(v.input.change, 0.0) - v.rig.change > 0.01;
      html += "<tr" + std::string(worse ? " class=\"fail\"" : "") + "><td>" + esc(clip.clip) + "</td><td>" + esc(region) +
              "</td><td>" + percent(v.input.change) + "</td><td>" + percent(v.dual_quaternion.change) + "</td><td>" +
              percent(v.rig.change) + "</td></tr>\n";
    };
    row("whole body", clip.body);
    // The same body counting each point inside the skin once: skin pushed through skin keeps nothing.
    if (clip.surface.measured) {
      SkinningVolumes occupied;
      occupied.input = clip.surface.occupied[0];
      occupied.dual_quaternion = clip.surface.occupied[1];
      occupied.rig = clip.surface.occupied[3];
      row("whole body, occupied", occupied);
    }
    // The three regions where the rig departs most from the input skinning.
    std::vector<size_t> order(clip.regions.size());
    for (size_t r = 0; r < order.size(); ++r) order[r] = r;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      return std::abs(clip.regions[a].rig.change - clip.regions[a].input.change) >
             std::abs(clip.regions[b].rig.change - clip.regions[b].input.change);
    });
    for (size_t k = 0; k < std::min<size_t>(3, order.size()); ++k) row(quality.regions[order[k]], clip.regions[order[k]]);
  }
  html += "</table>\n" + skinSurfaceTable(report);
  if (!quality.unmeasured_regions.empty()) {
    std::string names;
    for (const std::string& name : quality.unmeasured_regions) names += (names.empty() ? "" : ", ") + name;
    html += "<p class=\"note\">Too flat to enclose a volume, not measured: " + esc(names) + ".</p>\n";
  }
  if (!baked.pictures.empty()) {
    html += "<p class=\"explain\">Each picture: the input skinning, the baked rig, and the rig coloured by its skin's move "
            "along the surface normal against the input skinning (red out, blue in, white none; colour grows with the square root of the move, full at the "
            "largest). The same camera for the three panels. A crease's picture (the elbow, shoulder, knee or groin at the clip that "
            "bends it most) shows plain skinning, dual quaternions, centres of rotation and the rig side by side instead.</p>\n<div class=\"pictures\">\n";
    for (size_t i = 0; i < baked.pictures.size(); ++i) {
      const QualityPicture& picture = baked.pictures[i];
      char caption[160];
      std::snprintf(caption, sizeof(caption), "full colour %.1f mm; out up to %.1f mm, in up to %.1f mm", 1000.0 * picture.scale,
                    1000.0 * picture.max_out, 1000.0 * picture.max_in);
      html += "<figure><img alt=\"" + esc(picture.title) + "\" width=\"" + std::to_string(picture.image.width) +
              "\" height=\"" + std::to_string(picture.image.height) + "\" src=\"" + picture_uris[i] +
              "\"><figcaption><b>" + esc(picture.title) + "</b><br>" + esc(picture.panels) + ": " +
              (picture.note.empty() ? std::string(caption) : esc(picture.note)) +
              (picture.marker.empty() ? std::string() : "<br>" + esc(picture.marker)) + "</figcaption></figure>\n";
    }
    html += "</div>\n";
  }
  return html + "</section>\n";
}

}  // namespace

std::string reportHtml(const Report& report, int threads) {
  int failed_errors = 0, failed_warnings = 0, skipped = 0;
  for (const CheckResult& check : report.checks) {
    if (check.status == CheckStatus::kSkipped) ++skipped;
    if (check.status == CheckStatus::kFail) ++(check.severity == Severity::kError ? failed_errors : failed_warnings);
  }
  const bool passed = report.passed();
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>rigbake validate: " + esc(report.character) + (passed ? " passed" : " FAILED") + "</title>\n";
  html += "<style>" + std::string(kStyle) + "</style>\n</head>\n<body>\n";
  html += "<header><span class=\"verdict " + std::string(passed ? "pass" : "fail") + "\">" +
          (passed ? "PASS" : "FAIL") + "</span><div><h1>" + esc(report.character) +
          "</h1><div class=\"sub\">rigbake " RIGBAKE_VERSION " validate &#183; " + std::to_string(report.checks.size()) +
          " checks: " + std::to_string(failed_errors) + " errors, " + std::to_string(failed_warnings) + " warnings, " +
          std::to_string(skipped) + " skipped</div></div>";
  html += "<div class=\"stats\"><div><b>" + std::to_string(report.joints) + "</b>joints</div><div><b>" +
          std::to_string(report.vertices) + "</b>skinned vertices</div><div><b>" + std::to_string(report.muscles) +
          "</b>muscles</div><div><b>" + (report.influences ? std::to_string(report.influences) : std::string("&#8212;")) +
          "</b>packed influences</div></div></header>\n<main>\n";

  html += "<section id=\"checks\"><h2>Checks</h2>\n" + checksTable(report) + "</section>\n";

  const std::vector<std::string> groups = groupsOf(report);
  html += "<section id=\"body\"><h2>Skeleton, landmarks and muscles</h2>\n<p class=\"explain\">Bind pose over the body "
          "silhouette. Each muscle runs origin (filled dot) &#8594; driver &#8594; insertion (ring); a red halo marks "
          "a muscle whose locator failed a locator check. Diamonds are the resolved landmarks.</p>\n";
  if (report.figure.front.columns > 0 || !report.figure.bones.empty()) {
    html += groupLegend(groups, false);
    html += "<div class=\"row\">\n" + bodyView(report.figure, true) + bodyView(report.figure, false) + "</div>\n";
  } else {
    html += "<p class=\"note\">Landmarks did not resolve, so there is no body frame to draw in.</p>\n";
  }
  html += "</section>\n";

  html += "<section id=\"ratios\"><h2>Muscle length ratio over time</h2>\n<p class=\"explain\">L / L<sub>rest</sub> "
          "of every muscle at every key of each clip. The skinned muscle joint clamps the ratio to the green "
          "[compression, stretch] band; a red dot is a sample outside it, where the muscle stops following its "
          "attach joints. The dashed grey line is rest length.</p>\n";
  if (report.ratios.empty()) {
    html += "<p class=\"note\">No muscle file was given, so muscle ratios were not evaluated.</p>\n";
  } else {
    html += groupLegend(groups, true) + "<div class=\"grid\">\n";
    for (const ClipRatios& clip : report.ratios) html += ratioChart(clip);
    html += "</div>\n";
  }
  html += "</section>\n";

  if (!report.jiggles.empty()) {
    html += "<section id=\"jiggles\"><h2>Jiggle angle over time</h2>\n<p class=\"explain\">Angle of each baked jiggle "
            "from its animated direction (solid) against its elliptical cone's half-angle in that direction (dashed): "
            "the clamp holds where the solid line stays under its dashed twin (JIGGLE_WITHIN_CLAMP).</p>\n"
            "<div class=\"grid\">\n";
    for (const ClipJiggles& clip : report.jiggles) html += jiggleChart(clip);
    html += "</div>\n</section>\n";
  }

  html += "<div class=\"row\">\n<section id=\"influences\"><h2>Influences per vertex</h2>\n<p class=\"explain\">How "
          "many joints carry non-zero weight on each vertex (WEIGHTS_n); red bars exceed the INFLUENCE_COUNT "
          "threshold.</p>\n" +
          histogramChart(report) + "</section>\n";
  html += "<section id=\"deformation\"><h2>Packed weights: deformation error per clip</h2>\n<p class=\"explain\">Largest "
          "(light) and RMS (dark) distance between vertices skinned with the packed 0.001 weights and with the "
          "file's WEIGHTS_n, over every key of the clip.</p>\n" +
          deformationChart(report) + "</section>\n</div>\n";

  // The pictures' PNG compression is most of the page's cost: each picture on its own.
  std::vector<std::string> picture_uris(report.quality.pictures.size());
  parallelForEach(threads, picture_uris.size(), [&](size_t i) { picture_uris[i] = pngDataUri(report.quality.pictures[i].image); });
  html += qualitySection(report, picture_uris);

  html += "<section id=\"memory\"><h2>Skin data memory</h2>\n<p class=\"explain\">Bytes per vertex of each skin layout "
          "for this character's skinned vertices (pipeline/memory_table.h); the highlighted row is the packed layout "
          "of this bake.</p>\n" +
          memoryTable(report) + "</section>\n";
  html += "</main>\n</body>\n</html>\n";
  return html;
}

}  // namespace rigbake
