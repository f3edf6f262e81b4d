// The scene description the renderer is built from: cameras, the tagged target, static and
// moving occluders, lights, imaging settings, timing and the communication graph. Plain
// structs with documented defaults; no files (pipeline/ loads scenario YAML into this).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "netvmo/render/camera.hpp"
#include "netvmo/render/geometry.hpp"
#include "netvmo/render/texture.hpp"
#include "netvmo/render/trajectory.hpp"

namespace netvmo::render {

/// A piece of geometry with its own frame `pose` in the parent frame (the world for static
/// occluders, the body frame for moving bodies and the target).
struct Shape {
  enum class Kind { Box, Plane, Cylinder, Mesh };
  Kind kind = Kind::Box;
  /// Box: full side lengths (x, y, z). Plane: (sx, sy, unused), normal +z.
  /// Cylinder: (radius, unused, height) with the axis along z.
  Vec3 size = Vec3(0.3, 0.3, 0.3);
  int segments = 48;  ///< cylinder facets
  Mesh mesh;          ///< Kind::Mesh: vertices in the shape frame (e.g. from parse_obj)
  Pose pose = Pose::Identity();
  Material material;
  std::string name;  ///< for messages
};

/// An occluder: static (no motion: its shapes' poses are in the world and its BVH is built
/// once) or moving (its shapes are posed in a body frame that follows `motion`).
struct Body {
  std::string name;
  std::vector<Shape> shapes;
  std::optional<Trajectory> motion;
};

/// A tag placed on the target, pose g_ot in the target (object) frame.
struct PlacedTag {
  TagSpec tag;
  Pose g_ot = Pose::Identity();
};

/// The tagged rigid target. Its object frame o IS the frame of the primary `tag` (origin at the
/// tag centre, z out of the printed face), so ground truth corners are (+-s/2, +-s/2, 0) in o.
/// Body shapes are posed in o; keep their faces a little behind z = 0 (the tag is a separate
/// quad at z = 0).
struct Target {
  TagSpec tag;
  std::vector<PlacedTag> extra_tags;
  std::vector<Shape> shapes;
  Trajectory motion;  ///< g_wo(t)
};

struct Light {
  enum class Kind { Directional, Point };
  Kind kind = Kind::Directional;
  Vec3 direction = Vec3(0.3, 0.5, -1.0);  ///< Directional: direction the light travels (world)
  Vec3 position = Vec3(0, 0, 3);          ///< Point: position (world) [m]
  /// Directional: irradiance factor on a surface facing the light. Point: the same at 1 m,
  /// falling off with 1 / d^2.
  double intensity = 0.7;
  bool shadows = true;  ///< cast shadow rays (rtcOccluded)
};

/// Image formation. Pixel value DN = 255 * exposure * radiance + noise, clamped to [0, 255],
/// radiance = albedo * (ambient + sum of lights), averaged over the samples of a pixel.
struct Imaging {
  int spp = 4;  ///< samples per pixel; perfect squares use an n x n stratified
                ///< grid, other counts a Hammersley pattern
  /// Where each pixel's samples lie. Grid: the pattern of `spp` at the same offsets in every
  /// pixel, so an edge along the pixel rows or columns is quantised alike over its whole
  /// length (to 1/n px with an n x n grid; a sensor integrating over its pixels makes no such
  /// error). Jittered: each pixel's pattern shifted toroidally within the pixel by the pixel's
  /// own offset, drawn from (seed, camera id, pixel) and the same in every frame: the samples
  /// stay one per stratum, and the quantisation becomes a noise that averages out along an
  /// edge. Grid is the default: the project's renderings and the figures measured on them.
  enum class Sampling { Grid, Jittered };
  Sampling sampling = Sampling::Grid;
  double exposure = 1.0;
  double background = 0.55;  ///< radiance of rays that hit nothing
  double ambient = 0.3;      ///< ambient light level
  bool noise = true;
  double read_noise = 1.5;   ///< Gaussian read noise sigma [DN]
  double shot_noise = 0.04;  ///< shot noise variance per DN of signal [DN]
  std::uint64_t seed = 1;    ///< noise seed; each tile draws from (seed, camera id, frame, tile)
  int threads = 0;           ///< render threads; 0 = std::thread::hardware_concurrency()
  int tile = 16;             ///< tile side [px]
  int visibility_grid = 16;  ///< samples per side over the printed tag for visible_fraction
  /// Reuse a camera's previous noise-free radiance wherever no body that moved since (nor its
  /// shadow) can have changed it, re-trace the rest, and draw new sensor noise over the whole
  /// image; the image is byte-identical to tracing everything again. A camera whose own pose
  /// changed (CameraSpec::motion) re-traces its whole image.
  bool reuse_radiance = true;
};

struct SceneDescription {
  std::vector<CameraSpec> cameras;
  /// The tagged bodies, at least one; the first is "the" target of single-target scenes. Tags
  /// are told apart by id: no (family, id) on two of them.
  std::vector<Target> targets{Target{}};
  std::vector<Body> occluders;
  std::vector<Light> lights{Light{}};
  Imaging imaging;
  double fps = 30;
  int frames = 1;
  std::vector<std::pair<int, int>> edges;  ///< communication graph, camera ids

  /// The first target.
  const Target& target() const { return targets.at(0); }
  Target& target() { return targets.at(0); }
  /// Throws std::invalid_argument with one line naming the problem.
  void validate() const;
  /// Whether every camera takes its images at the scene's clock (k / fps, no own fps or start).
  bool one_clock() const;
  /// The times [s] of camera `ci`'s images over a run of `frames` frames at the scene's fps:
  /// start + k / its fps for k = 0, 1, ... while the time is before frames / fps (k / fps for
  /// k < frames on the scene's clock).
  std::vector<double> image_times(size_t ci, int frames) const;
};

}  // namespace netvmo::render
