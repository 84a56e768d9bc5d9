// A small software rasterizer for the validation report's pictures (docs/validate.md): shaded surfaces
// and heatmaps, made without a GPU or a display, deterministic to the bit (plain double arithmetic in
// a fixed order, no threads). Orthographic camera, z-buffer, Lambert shading from a fixed light.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace rigbake {

struct Camera {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();   // looked at
  Eigen::Vector3d forward = -Eigen::Vector3d::UnitZ(); // unit, from the eye into the scene
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();       // unit, across forward
  double half_height = 1.0;                            // scene units shown above and below the centre
};

struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, top row first, 3 bytes per pixel
};

// One surface to draw: positions, triangles (counter-clockwise seen from outside) and, optionally, one
// colour per vertex (0..1 RGB); without colours the surface is light grey.
struct RenderSurface {
  const std::vector<Eigen::Vector3d>* positions = nullptr;
  const std::vector<std::array<int, 3>>* triangles = nullptr;
  const std::vector<Eigen::Vector3f>* colours = nullptr;
};

// Draws the surfaces into a width x height image with a white background. Both sides of a triangle
// are lit (open meshes show their inside), the side facing away slightly darker.
RgbImage renderSurfaces(const std::vector<RenderSurface>& surfaces, const Camera& camera, int width, int height);

// A black ring (6 pixels across the middle of its 2-pixel line) around where `point` projects in an
// image that renderSurfaces() drew with `camera`: a marker over the surface, drawn whether or not the
// surface hides the point.
void drawRing(const Camera& camera, const Eigen::Vector3d& point, RgbImage* image);

// A diverging colour for a signed value in [-1, 1]: blue (inward) through white to red (outward).
Eigen::Vector3f divergingColour(double value);

}  // namespace rigbake
