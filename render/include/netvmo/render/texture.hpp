// Textures: AprilTag bitmaps from libapriltag itself (apriltag_to_image) with a white quiet
// zone, and procedural surface patterns (solid, checker, value noise) for floors, walls and
// bodies so images are not artificially clean. Lookups are point samples of the exact printed
// pattern; anti-aliasing comes from the renderer's supersampling.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "netvmo/render/geometry.hpp"

namespace netvmo::render {

/// One printed AprilTag. Defaults: tag36h11 id 0, 0.2 m.
struct TagSpec {
  std::string family = "tag36h11";  ///< one of tag_families() (tag_family.hpp)
  int id = 0;
  double size = 0.2;           ///< side of the black border square [m] (libapriltag's definition)
  int quiet_cells = 1;         ///< extra white cells printed around libapriltag's bitmap, whose
                               ///< own outer ring is already white (so 1 gives a 2-cell margin)
  double white_albedo = 0.85;  ///< reflectance of the paper
  double black_albedo = 0.05;  ///< reflectance of the ink
};

/// The tag bitmap and its geometry in the tag frame (origin at the tag centre, x right, y up
/// the printed tag, z out of the printed face).
class TagTexture {
 public:
  /// Builds the bitmap with apriltag_to_image; throws std::invalid_argument for an unknown
  /// family, an id out of range or a non-positive size.
  explicit TagTexture(const TagSpec& spec);

  const TagSpec& spec() const { return spec_; }
  /// Side of one bitmap cell [m] = size / width_at_border.
  double cell() const { return cell_; }
  /// Side of the whole printed square including the quiet zone [m].
  double printed_side() const { return cell_ * (total_width_ + 2 * spec_.quiet_cells); }
  /// Albedo at tag-frame coordinates (x, y) [m]; white outside the bitmap (quiet zone).
  double albedo(double x, double y) const {
    const double half = 0.5 * total_width_;
    const double fc = x / cell_ + half, fr = half - y / cell_;
    if (fc < 0 || fr < 0) return spec_.white_albedo;
    const int c = static_cast<int>(fc), r = static_cast<int>(fr);
    if (c >= total_width_ || r >= total_width_) return spec_.white_albedo;
    return dark_[static_cast<size_t>(r * total_width_ + c)] ? spec_.black_albedo
                                                            : spec_.white_albedo;
  }
  int total_width() const { return total_width_; }
  int width_at_border() const { return width_at_border_; }
  /// Bitmap row r (0 = top of the printed tag), column c (0 = left): true where black.
  bool dark(int r, int c) const { return dark_[static_cast<size_t>(r * total_width_ + c)] != 0; }

 private:
  TagSpec spec_;
  int total_width_ = 0, width_at_border_ = 0;
  double cell_ = 0;
  std::vector<std::uint8_t> dark_;
};

/// A diffuse surface pattern, evaluated at a point of the shape's own frame [m].
struct Material {
  enum class Pattern { Solid, Checker, Noise };
  Pattern pattern = Pattern::Solid;
  double albedo = 0.6;     ///< solid albedo; checker colour 1; noise mean
  double albedo2 = 0.3;    ///< checker colour 2; noise amplitude (peak deviation)
  double scale = 0.25;     ///< checker square side / noise feature size [m]
  std::uint32_t seed = 0;  ///< noise pattern seed

  /// Albedo at point p with unit normal n, both in the shape frame. The checker ignores the
  /// coordinate along the dominant normal axis, so a face lying on a cell boundary (a floor at
  /// z = 0) does not flicker between cells with rounding.
  double eval(const Vec3& p, const Vec3& n) const;
};

/// Parses "solid", "checker", "noise"; throws std::invalid_argument otherwise.
Material::Pattern parse_pattern(const std::string& name);

}  // namespace netvmo::render
