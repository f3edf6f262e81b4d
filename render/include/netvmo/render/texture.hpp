// Textures: AprilTag bitmaps from libapriltag itself (apriltag_to_image) with a white quiet
// zone, and procedural surface patterns (solid, checker, value noise) for floors, walls and
// bodies so images are not artificially clean. Lookups are point samples of the exact printed
// pattern; anti-aliasing comes from the renderer's supersampling.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "netvmo/render/geometry.hpp"

namespace netvmo::render {

/// What printing does to a tag (docs/realistic_camera.md). The defaults are an ideal print: sharp
/// cell edges and a matte (Lambertian) surface.
struct PrintModel {
  /// Ink spread [cells], signed: every black/white edge of the printed bitmap moves by
  /// ink_spread * cell into the white (> 0, the black grows) or into the black (< 0); the black
  /// region is dilated (eroded) by a disc of that radius. |ink_spread| <= 0.5.
  double ink_spread = 0.0;
  /// Specular reflectance of a glossy print (Blinn-Phong): each light adds
  /// gloss * intensity * max(0, n.h)^shininess, h the half vector of light and view. 0..1; 0 =
  /// matte.
  double gloss = 0.0;
  double shininess = 40.0;  ///< Blinn-Phong exponent (1..10000)
  /// Curvature of the card [1/m]: the print (quiet zone included) wrapped, without stretching,
  /// on a cylinder whose axis is parallel to the tag's y axis through the tag's centre line, so
  /// its sides along x bow and those along y stay straight. A point at arc length u along x
  /// lies at (sin(k u) / k, y, -(1 - cos(k u)) / k) in the tag frame: > 0 bulges toward the
  /// face (the ends curl away from the camera, behind the plane z = 0, where a body behind the
  /// tag would hide them), < 0 the ends curl toward the camera (a sheet lifting off a wall).
  /// The tag frame stays the tangent plane at the centre line. 0 = flat; |bend| times half the
  /// printed side at most 1.5 rad.
  double bend = 0.0;
  /// Width of the printed black border on each side [cells]: top (the tag's +y), right (+x),
  /// bottom, left. The border's outer edge stays where the tag's size puts it (so the corners
  /// do not move); the grid line along its inner edge moves, across the whole print, so the
  /// cells next to it grow or shrink: a bitmap scaled by nearest neighbour to a non-integer
  /// number of device pixels per cell, or a misregistered print. 0.5..1.5 each; 1 = ideal.
  std::array<double, 4> border_width{1.0, 1.0, 1.0, 1.0};

  /// A laser print on office paper: the black grows by 0.08 cell, slightly glossy, flat.
  static PrintModel realistic() { return {0.08, 0.04, 30.0, 0.0, {1.0, 1.0, 1.0, 1.0}}; }
  bool operator==(const PrintModel& o) const {
    return ink_spread == o.ink_spread && gloss == o.gloss && shininess == o.shininess &&
           bend == o.bend && border_width == o.border_width;
  }
  /// Whether every side's border is one cell wide.
  bool even_border() const { return border_width == std::array<double, 4>{1.0, 1.0, 1.0, 1.0}; }
};

/// One printed AprilTag. Defaults: tag36h11 id 0, 0.2 m.
struct TagSpec {
  std::string family = "tag36h11";  ///< one of tag_families() (tag_family.hpp)
  int id = 0;
  double size = 0.2;           ///< side of the black border square [m] (libapriltag's definition)
  int quiet_cells = 1;         ///< extra white cells printed around libapriltag's bitmap, whose
                               ///< own outer ring is already white (so 1 gives a 2-cell margin)
  double white_albedo = 0.85;  ///< reflectance of the paper
  double black_albedo = 0.05;  ///< reflectance of the ink
  PrintModel print;            ///< ink spread and gloss (default: an ideal matte print)
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
  /// The largest |PrintModel::bend| of this tag [1/m]: its ends 1.5 rad round (the constructor
  /// refuses more).
  double max_bend() const { return 2 * kMaxBendAngle / printed_side(); }
  /// The range of bend for this tag, as messages say it: "within +-X 1/m for this tag (...)".
  std::string bend_range() const;
  static constexpr double kMaxBendAngle = 1.5;  ///< [rad]
  /// The card's point at arc length u along its x axis and at y [m], in the tag frame
  /// (PrintModel::bend; (u, y, 0) for a flat card), and its unit normal there (out of the face).
  Vec3 card_point(double u, double y) const;
  Vec3 card_normal(double u) const;
  /// The card as a triangle mesh in the tag frame: the printed square (quiet zone included); a
  /// bent card as strips along y, each at most 2 µm from the cylinder (its sagitta).
  Mesh card_mesh() const;
  /// Albedo at a point of card_mesh() in the tag frame: a bent card's point is first taken back
  /// to its arc length along x (the inverse of card_point).
  double card_albedo(const Vec3& p) const {
    const double k = spec_.print.bend;
    if (k == 0) return albedo(p.x(), p.y());
    return albedo(std::atan2(k * p.x(), 1.0 + k * p.z()) / k, p.y());
  }
  /// Albedo at tag-frame coordinates (x, y) [m] of the flat print; white outside the bitmap
  /// (quiet zone).
  double albedo(double x, double y) const {
    if (spec_.print.ink_spread != 0 || !even_border_) return spread_albedo(x, y);
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
  /// albedo() with PrintModel::ink_spread (the black dilated or eroded by a disc) on the grid
  /// of PrintModel::border_width.
  double spread_albedo(double x, double y) const;
  /// The cell of the printed grid holding bitmap coordinate f along one axis (columns: a = 3,
  /// the left side, b = 1, the right; rows: a = 0, the top, b = 2, the bottom): its index and
  /// its lower and upper grid lines, the lines along the border's inner edges moved by
  /// PrintModel::border_width.
  int grid_cell(double f, size_t a, size_t b, double& lo, double& hi) const;
  /// dark(r, c), false (white) outside the bitmap.
  bool dark_or_white(int r, int c) const {
    return r >= 0 && c >= 0 && r < total_width_ && c < total_width_ && dark(r, c);
  }

  TagSpec spec_;
  bool even_border_ = true;
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
