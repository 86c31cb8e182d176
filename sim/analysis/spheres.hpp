#pragma once
// The truth for spheres: a CPU ray cast, in double precision, of a scene's spheres and
// triangles (world-space rays through every pixel centre, from the inverse of the camera's
// view-projection: independent of the GP's screen conic), and the measurements `pp5sim
// spheres` and the tests make of what the firmware drew against it: coverage, depth, shading
// and the curves where spheres meet.
//
// Contract: pure functions of (configuration, scene) and the firmware's fields; no pixel value
// is computed here for the image. Depth is in the depth buffer's units (the GP's mapping of
// a triangle's vertices: (ndc z + 1) / 2 * (2^gp.depth_bits - 1)).
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/scene/scene.hpp"

namespace pp5 {

// What the ray through each pixel centre meets first. `what` is -1 for nothing, the sphere's
// index for a sphere, and -2 - t for triangle t; `covers` lists, per pixel, how many spheres
// the ray meets.
struct RayCast {
  int width = 0, height = 0;
  std::vector<double> depth;  // depth units; +inf where nothing
  std::vector<int> what;
  std::vector<double> nx, ny, nz;     // eye-space unit normal of the nearest hit (spheres)
  std::vector<std::uint8_t> spheres;  // spheres the ray meets (saturating at 255)
};
RayCast ray_cast(const MachineConfig& config, const Scene& scene);

// The exact depth (depth units) of sphere `index` at pixel (x, y), or +inf if the ray misses.
double sphere_depth_at(const MachineConfig& config, const Scene& scene, int index, int x, int y);

// The firmware's view of a frame: fields read back from every pixel (sim/analysis/field_render).
struct DrawnSpheres {
  std::vector<std::uint64_t> covered;    // 1 where a primitive was drawn
  std::vector<std::int64_t> z;           // the depth buffer
  std::vector<std::int64_t> nx, ny, nz;  // the stored normal, * 127
};
// Runs `program` (which must have fields covered, z, nx, ny, nz: phong) on the scene.
DrawnSpheres draw_spheres(const MachineConfig& config, const Scene& scene, const Program& program,
                          int threads);

// Which primitive each pixel shows, read from firmware as `pp5sim visible` reads it: the scene
// `drawn` is run with every primitive's index + 1 as its unlit colour (24 bits over red,
// green, blue) under a z-buffer on the same depth expressions as phong.pp5 (`depth` for a
// triangle, `sphere_depth` for a sphere), and the frame decoded. Per pixel: the index of the
// sphere shown, -1 for background, -2 for a triangle that stands for no sphere.
// `triangle_sphere[t]` is the sphere triangle t of drawn.mesh stands for (a tessellation's
// triangle), or -1; empty: no triangle stands for a sphere.
std::vector<int> shown_spheres(const MachineConfig& config, const Scene& drawn,
                               const std::vector<int>& triangle_sphere, int threads);
// The same with `program` drawing the index colours: it must leave in its output the unlit
// colours its `triangle` and `sphere` procedures load (sphere_depth_methods.hpp's
// unshaded_program), so that each pixel shows the primitive the program's own depth code keeps.
std::vector<int> shown_spheres_by(const MachineConfig& config, const Scene& drawn,
                                  const std::vector<int>& triangle_sphere, const Program& program,
                                  int threads);

// The accuracy of a drawn frame against the ray cast.
struct SphereAccuracy {
  std::uint64_t pixels = 0;            // pixels the ray cast finds covered
  std::uint64_t coverage_extra = 0;    // drawn but not covered
  std::uint64_t coverage_missing = 0;  // covered but not drawn
  double depth_max_error = 0;          // depth units, over pixels both cover
  double depth_mean_error = 0;
  double normal_max_error_degrees = 0;  // angle between drawn and exact normals
  double normal_mean_error_degrees = 0;
  // Overlap pixels: a sphere is visible and the ray meets two or more spheres.
  std::uint64_t overlap_pixels = 0;
  std::uint64_t overlap_depth_wrong = 0;  // ... where the drawn depth is nearer another sphere's
  std::uint64_t overlap_shown_wrong = 0;  // ... where the pixel shows another primitive
  // Intersection-curve pixels: the visible sphere differs from a 4-neighbour's, and both
  // spheres' surfaces cover both pixels with their depth order swapped between them (the two
  // surfaces cross between the centres: a silhouette over another sphere is not counted).
  std::uint64_t curve_pixels = 0;
  std::uint64_t curve_shown_wrong = 0;  // ... where the pixel shows another primitive
  // Triangle pixels: the ray cast's visible surface is a triangle; the largest depth error
  // there (depth units), and pixels that show something else.
  std::uint64_t triangle_pixels = 0;
  double triangle_depth_max_error = 0;
  std::uint64_t triangle_shown_wrong = 0;
};
// `shown` (shown_spheres), or empty to leave the *_shown_wrong counts 0.
SphereAccuracy measure_spheres(const MachineConfig& config, const Scene& scene,
                               const RayCast& truth, const DrawnSpheres& drawn,
                               const std::vector<int>& shown = {});

}  // namespace pp5
