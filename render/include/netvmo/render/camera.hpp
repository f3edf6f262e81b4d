// Pinhole cameras with optional lens distortion: OpenCV's radial-tangential model (k1, k2, p1,
// p2, k3), its 8-coefficient rational model (+ k4, k5, k6 in the denominator), or the fisheye
// (equidistant, cv::fisheye) model (k1..k4).
// Pixel convention (OpenCV): pixel (col, row) has its centre at continuous (col, row) and
// covers [col-0.5, col+0.5] x [row-0.5, row+0.5].
#pragma once

#include <array>
#include <optional>

#include "netvmo/render/geometry.hpp"
#include "netvmo/render/trajectory.hpp"

namespace netvmo::render {

struct Intrinsics {
  /// The distortion model, on undistorted normalized (x, y), r^2 = x^2 + y^2:
  ///  RadTan (cv::projectPoints with 5 coefficients): x (1 + k1 r^2 + k2 r^4 + k3 r^6) +
  ///    tangential 2 p1 x y + p2 (r^2 + 2 x^2) (and the same for y with p1, p2 swapped);
  ///  Rational (cv::projectPoints with 8): the radial factor divided by 1 + k4 r^2 + k5 r^4 + k6
  ///  r^6; Fisheye (cv::fisheye::projectPoints): theta = atan(r), theta_d = theta (1 + k1 theta^2 +
  ///    k2 theta^4 + k3 theta^6 + k4 theta^8), (x, y) scaled by theta_d / r.
  enum class Lens { RadTan, Rational, Fisheye };
  int width = 640, height = 480;
  double fx = 600, fy = 600;
  double cx = 319.5, cy = 239.5;
  Lens lens = Lens::RadTan;
  /// RadTan: k1, k2, p1, p2, k3 (OpenCV order; the rest zero); Rational: k1, k2, p1, p2, k3, k4,
  /// k5, k6; Fisheye: k1, k2, k3, k4 (the rest zero). All zero = none.
  std::array<double, 8> dist{};

  bool has_distortion() const;
  /// Normalized undistorted point (x/z, y/z) -> distorted normalized point (the lens model).
  Vec2 distort(const Vec2& xn) const;
  /// Inverse of distort() by Newton iteration; nullopt if it does not converge.
  std::optional<Vec2> undistort(const Vec2& xd) const;
  /// Camera-frame point -> pixel with distortion (like cv::projectPoints); nullopt if z <= 0.
  std::optional<Vec2> project(const Vec3& p_cam) const;
  /// Pixel (u, v) -> undistorted normalized point.
  std::optional<Vec2> unproject(const Vec2& uv) const;
  /// Throws std::invalid_argument naming the problem (size, focal length, ...).
  void validate() const;
};

/// What a real camera does between the scene's radiance and the 8-bit image, per camera
/// (docs/realistic_camera.md has each formula). The defaults are the renderer's clean imaging
/// (a pinhole, an instantaneous global shutter, a linear sensor clamped at 255): with them the
/// image is exactly the reference one, byte for byte. Order per pixel: samples (pixel area,
/// exposure time, lens aperture) averaged -> vignetting -> optical PSF -> full well and bloom ->
/// read and shot noise -> gain -> tone curve -> 8 bits (-> JPEG, when a dataset is written).
struct SensorModel {
  enum class Tone { Linear, Srgb, Gamma };
  enum class Vignetting { None, Cos4, Poly };

  // Sensor and ISP, on the linear signal S = 255 * exposure * radiance [DN before gain].
  double gain = 1.0;         ///< S *= gain after the noise (> 0)
  Tone tone = Tone::Linear;  ///< DN = 255 * tone(S / 255): linear, sRGB encoding, or x^(1/gamma)
  double gamma = 2.2;        ///< Tone::Gamma's exponent (> 0)
  /// Full well [DN of S]: a pixel holds at most this much; 0 = unlimited (clamped at 255 only).
  double full_well = 0.0;
  /// Fraction (0..1) of a saturated pixel's excess charge that spills equally into its four
  /// neighbours (repeatedly, while they overflow); the rest is lost.
  double bloom = 0.0;
  Vignetting vignetting = Vignetting::None;
  /// Poly: V = 1 + a1 rho^2 + a2 rho^4 + a3 rho^6, rho = distance to (cx, cy) / half the image
  /// diagonal (rho = 1 at the corners). Cos4: V = cos^4(theta) = 1 / (1 + x^2 + y^2)^2 with
  /// (x, y) the pixel's normalized coordinates.
  std::array<double, 3> vignetting_poly{};
  double psf_sigma =
      0.0;  ///< optical point-spread function: Gaussian sigma [px], on the linear image
  /// JPEG quality (1..100) of the images `netvmo render` writes (cv::imencode); 0 = PNG. The
  /// renderer's own images are never compressed.
  int jpeg_quality = 0;
  /// In-camera sharpening, as phone and webcam ISPs apply before compressing: an unsharp mask on
  /// the encoded image (after the tone curve and the noise), DN' = DN + amount (DN - G * DN),
  /// G a Gaussian of sharpen_sigma px (separable, edges replicated). It steepens edges and rings
  /// beside them. 0 = none.
  double sharpen_amount = 0.0;
  double sharpen_sigma = 1.0;  ///< the unsharp mask's Gaussian [px]

  // Exposure and shutter.
  /// Exposure time [s]: the samples of a pixel are spread uniformly over it (motion blur). The
  /// brightness stays Imaging::exposure's. 0 = instantaneous.
  double exposure_time = 0.0;
  /// Rolling shutter: row r is exposed (r - (height - 1) / 2) * line_delay [s] after the frame's
  /// time, so the middle row's exposure is centred on the frame's time; 0 = global shutter.
  double line_delay = 0.0;

  // Thin lens (defocus). f_number 0: a pinhole.
  double f_number = 0.0;        ///< aperture diameter A = F / f_number (>= 0.5 when on)
  double focus_distance = 1.0;  ///< distance of the plane in focus along the optical axis [m]
  /// Focal length F [mm]; or 0 and pixel_pitch_um, then F = v d / (v + d) with the image distance
  /// v = fx * pitch and d = focus_distance (thin lens, fx the calibrated focal length).
  double focal_length_mm = 0.0;
  double pixel_pitch_um = 0.0;  ///< pixel pitch [um] (only to derive F)

  /// Plausible values of everything at once for a 640 x 480 machine-vision camera: sRGB tone,
  /// mild vignetting, a 0.6 px PSF, 4 ms exposure, 20 us line delay, f/2.8 focused at 2 m (6 mm
  /// lens), JPEG quality 90, full well at 240 DN with 30 % bloom.
  static SensorModel realistic();
  /// Whether each group of effects is on.
  bool image_effects() const;  ///< anything between radiance and 8 bits (a whole-image pass)
  bool time_effects() const { return exposure_time > 0 || line_delay != 0; }
  bool lens_effects() const { return f_number > 0; }
  /// The focal length F [m] (focal_length_mm, or derived from pixel_pitch_um and fx).
  double focal_length_m(double fx) const;
  /// The aperture diameter A = F / f_number [m]; 0 for a pinhole.
  double aperture(double fx) const { return f_number > 0 ? focal_length_m(fx) / f_number : 0.0; }
  /// Throws std::invalid_argument naming the key out of its physical range.
  void validate() const;
};

/// One camera of the network. id is the positive integer of the scenario.
///
/// A moving camera's true pose follows `motion`; its believed pose is the true one seen
/// through a mis-registered world frame, Delta(t) g_wi,true(t), with
///   Delta(0) = g_wi_believed g_wi,true(0)^-1   (the localisation error at t = 0) and
///   Delta(t) = [exp(t hat(drift_w)), t drift_v] Delta(0)   (a drift of the mis-registration),
/// so a static target's fictitious pose Delta(t) g_wo stays put while only the camera moves.
/// A static camera without drift believes g_wi_believed at every frame.
struct CameraSpec {
  int id = 1;
  Intrinsics intrinsics;
  SensorModel sensor;                     ///< the realistic camera model (default: clean)
  Pose g_wi_true = Pose::Identity();      ///< true pose at t = 0 (motion->at(0) when moving)
  Pose g_wi_believed = Pose::Identity();  ///< believed pose at t = 0 (its localization error)
  std::optional<Trajectory> motion;       ///< true g_wi(t); none: static at g_wi_true
  Vec6 believed_drift = Vec6::Zero();     ///< [drift_v (m/s); drift_w (rad/s)], world frame
  /// Its own frame rate [1/s]; none: the scene's fps (SceneDescription::image_times).
  std::optional<double> fps;
  double start = 0.0;  ///< time of its first image [s] (>= 0)

  /// True pose at time t [s] (used to render and for the ground truth).
  Pose true_pose(double t) const { return motion ? motion->at(t) : g_wi_true; }
  /// Believed pose at time t [s].
  Pose believed_pose(double t) const;
  /// Whether the true or the believed pose changes over time.
  bool moving() const;
  /// The same camera with a sensor of width x height pixels over the same area: the image is
  /// scaled by s = width / intrinsics.width, which must equal height / intrinsics.height (same
  /// aspect ratio; throws std::invalid_argument otherwise). Pixel quantities scale with it:
  /// fx, fy and (cx + 1/2), (cy + 1/2) by s (pixel centres at integers), psf_sigma by s,
  /// pixel_pitch_um by 1 / s; the rolling shutter's line_delay by 1 / s (the same readout time
  /// per frame). Distortion (on normalized coordinates), poses and the lens stay.
  void set_resolution(int width, int height);
};

}  // namespace netvmo::render
