// Scanline-free triangle rasterization by edge functions over each triangle's pixel bounding box
// (Pineda, "A Parallel Algorithm for Polygon Rasterization", SIGGRAPH 1988), a depth buffer, and
// Lambertian shading with interpolated vertex normals. The diverging heatmap palette is Moreland's
// "cool to warm" ("Diverging Color Maps for Scientific Visualization", ISVC 2009) end points.
#include "pipeline/render.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rigbake {

namespace {

// The orthographic camera's view axes and scale for a width x height image: renderSurfaces() draws with
// it and drawRing() marks a point where that drawing put it.
struct Projection {
  Projection(const Camera& camera, int width, int height)
      : centre(camera.centre),
        forward(camera.forward.normalized()),
        up((camera.up - camera.up.dot(forward) * forward).normalized()),
        right(forward.cross(up)),
        pixels_per_unit(0.5 * height / camera.half_height),
        half_width(0.5 * width),
        half_height(0.5 * height) {}
  // Pixel column, row (from the top) and depth along `forward`.
  Eigen::Vector3d screen(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - centre;
    return {half_width + d.dot(right) * pixels_per_unit, half_height - d.dot(up) * pixels_per_unit, d.dot(forward)};
  }
  Eigen::Vector3d centre, forward, up, right;
  double pixels_per_unit, half_width, half_height;
};

}  // namespace

Eigen::Vector3f divergingColour(double value) {
  const double t = std::clamp(value, -1.0, 1.0);
  const Eigen::Vector3d cool(0.230, 0.299, 0.754), white(0.95, 0.95, 0.95), warm(0.706, 0.016, 0.150);
  const Eigen::Vector3d colour = t < 0 ? white + (cool - white) * (-t) : white + (warm - white) * t;
  return colour.cast<float>();
}

void drawRing(const Camera& camera, const Eigen::Vector3d& point, RgbImage* image) {
  const Eigen::Vector3d at = Projection(camera, image->width, image->height).screen(point);
  const double x = at.x(), y = at.y();
  constexpr double kRadius = 6.0, kHalfLine = 1.0;
  for (int row = static_cast<int>(std::floor(y - kRadius - kHalfLine)); row <= static_cast<int>(std::ceil(y + kRadius + kHalfLine)); ++row) {
    for (int column = static_cast<int>(std::floor(x - kRadius - kHalfLine)); column <= static_cast<int>(std::ceil(x + kRadius + kHalfLine));
         ++column) {
      if (row < 0 || row >= image->height || column < 0 || column >= image->width) continue;
      const double distance = std::hypot(column + 0.5 - x, row + 0.5 - y);
      if (std::abs(distance - kRadius) > kHalfLine) continue;
      const size_t offset = (static_cast<size_t>(row) * image->width + column) * 3;
      image->pixels[offset] = image->pixels[offset + 1] = image->pixels[offset + 2] = 0;
    }
  }
}

RgbImage renderSurfaces(const std::vector<RenderSurface>& surfaces, const Camera& camera, int width, int height) {
  RgbImage image;
  image.width = width;
  image.height = height;
  image.pixels.assign(static_cast<size_t>(width) * height * 3, 255);
  std::vector<double> depth(static_cast<size_t>(width) * height, std::numeric_limits<double>::infinity());
  const Projection projection(camera, width, height);
  const Eigen::Vector3d &forward = projection.forward, &up = projection.up, &right = projection.right;
  // Light from the viewer's upper left, a little in front.
  const Eigen::Vector3d light = (-forward + 0.5 * up - 0.4 * right).normalized();

  // The depth pass keeps each pixel's nearest fragment (the first of equal depths, as drawing in order
  // with a strict depth test leaves it); only those are shaded afterwards, the same values with no
  // shading of fragments drawn over later.
  struct Fragment {
    int surface = -1;  // -1: background
    int triangle = 0;
    double w0 = 0.0, w1 = 0.0, w2 = 0.0;
  };
  std::vector<Fragment> nearest(static_cast<size_t>(width) * height);
  std::vector<std::vector<Eigen::Vector3d>> surface_normals(surfaces.size());
  for (size_t s = 0; s < surfaces.size(); ++s) {
    const RenderSurface& surface = surfaces[s];
    const std::vector<Eigen::Vector3d>& positions = *surface.positions;
    // Screen coordinates, and area-weighted vertex normals for smooth shading.
    std::vector<Eigen::Vector3d> screen(positions.size());
    for (size_t v = 0; v < positions.size(); ++v) screen[v] = projection.screen(positions[v]);
    std::vector<Eigen::Vector3d>& normals = surface_normals[s];
    normals.assign(positions.size(), Eigen::Vector3d::Zero());
    for (const auto& t : *surface.triangles) {
      const Eigen::Vector3d n = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
      for (int k = 0; k < 3; ++k) normals[t[k]] += n;
    }
    for (Eigen::Vector3d& n : normals) {
      const double length = n.norm();
      if (length > 0) n /= length;
    }
    const std::vector<std::array<int, 3>>& triangles = *surface.triangles;
    for (size_t i = 0; i < triangles.size(); ++i) {
      const auto& t = triangles[i];
      const Eigen::Vector3d& a = screen[t[0]];
      const Eigen::Vector3d& b = screen[t[1]];
      const Eigen::Vector3d& c = screen[t[2]];
      const double area = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
      if (area == 0.0) continue;
      const bool negative_area = area < 0.0;
      const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
      const int x1 = std::min(width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
      const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
      const int y1 = std::min(height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const double px = x + 0.5, py = y + 0.5;
          const double e0 = (b.x() - px) * (c.y() - py) - (c.x() - px) * (b.y() - py);
          const double e1 = (c.x() - px) * (a.y() - py) - (a.x() - px) * (c.y() - py);
          // e / area < 0 exactly when e is non-zero with the other sign (screen coordinates are far from
          // where the quotient could underflow): outside, without dividing.
          if ((e0 != 0.0 && (e0 < 0.0) != negative_area) || (e1 != 0.0 && (e1 < 0.0) != negative_area)) continue;
          const double w0 = e0 / area;
          const double w1 = e1 / area;
          const double w2 = 1.0 - w0 - w1;
          if (w0 < 0 || w1 < 0 || w2 < 0) continue;
          const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
          const size_t index = static_cast<size_t>(y) * width + x;
          if (!(z < depth[index])) continue;
          depth[index] = z;
          nearest[index] = {static_cast<int>(s), static_cast<int>(i), w0, w1, w2};
        }
      }
    }
  }
  for (size_t index = 0; index < nearest.size(); ++index) {
    const Fragment& fragment = nearest[index];
    if (fragment.surface < 0) continue;
    const RenderSurface& surface = surfaces[static_cast<size_t>(fragment.surface)];
    const std::vector<Eigen::Vector3d>& normals = surface_normals[static_cast<size_t>(fragment.surface)];
    const auto& t = (*surface.triangles)[static_cast<size_t>(fragment.triangle)];
    const double w0 = fragment.w0, w1 = fragment.w1, w2 = fragment.w2;
    Eigen::Vector3d normal = (w0 * normals[t[0]] + w1 * normals[t[1]] + w2 * normals[t[2]]).normalized();
    double facing = 1.0;
    if (normal.dot(forward) > 0) {  // the side facing away from the viewer: light its inside
      normal = -normal;
      facing = 0.7;
    }
    const double lambert = 0.25 + 0.75 * std::max(0.0, normal.dot(light));
    Eigen::Vector3d base(0.82, 0.82, 0.80);
    if (surface.colours) {
      const auto& colours = *surface.colours;
      base = (w0 * colours[t[0]] + w1 * colours[t[1]] + w2 * colours[t[2]]).cast<double>();
    }
    const Eigen::Vector3d shaded = (base * lambert * facing).cwiseMin(1.0).cwiseMax(0.0);
    for (int k = 0; k < 3; ++k) image.pixels[index * 3 + k] = static_cast<std::uint8_t>(std::lround(shaded[k] * 255.0));
  }
  return image;
}

}  // namespace rigbake
