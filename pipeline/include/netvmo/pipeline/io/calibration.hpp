// Camera intrinsics for the tag front end: OpenCV's pinhole model with the 5-coefficient
// Brown-Conrady distortion (k1, k2, p1, p2, k3), optionally OpenCV's rational model (k4, k5, k6
// in the denominator), or OpenCV's fisheye (equidistant) model cv::fisheye (k1..k4); pixel
// (col,row) centred at continuous (col,row). Every use of the distortion goes through OpenCV
// (distortion(), normalize_points(), denormalize_points()).
//
// Three file formats are read:
//  - OpenCV FileStorage (YAML/XML/JSON as written by cv::FileStorage, e.g. by OpenCV's own
//    calibration tools or by `netvmo render`): `image_width`, `image_height`, `camera_matrix`
//    (3x3), `distortion_coefficients` (4, 5 or 8 numbers; 12/14 accepted when the coefficients
//    past the 8th are all zero); optional `lens_model`: pinhole (the default) or fisheye (then
//    distortion_coefficients are cv::fisheye's 4, k1..k4; `netvmo render` writes the key only for
//    fisheye cameras); optional `distortion_model` (as some converters write: plumb_bob,
//    rational_polynomial or equidistant, checked against the coefficients and lens_model).
//  - ROS camera_info YAML (as written by ROS's camera_calibration, read with yaml-cpp), detected
//    by its top-level `distortion_model` key in a file without any mark of OpenCV FileStorage
//    (the `%YAML:1.0` first line, the `!!opencv-matrix` tag, a matrix's `dt` key): `image_width`,
//    `image_height`, `camera_name`, `camera_matrix`, `distortion_model` (plumb_bob: 5 coefficients,
//    rational_polynomial: 8, equidistant: 4, cv::fisheye's k1..k4), `distortion_coefficients`,
//    `rectification_matrix` (must be the identity: a monocular camera's; the images are used raw),
//    `projection_matrix` (3x4, checked, not used: it describes rectified images), each matrix as
//    {rows, cols, data}.
//  - ViSP XML (vpXmlParserCamera), camera name `cam_<id>`: the projection with distortion if
//    the file has one, otherwise without. ViSP's distortion model is a single radial term:
//    u = u0 + px x (1 + kud r^2), which is OpenCV's model with k1 = kud and the others zero;
//    ViSP's inverse coefficient kdu is not used (undistortion is done by iterating the
//    forward model, see normalize_points()).
// Every error is an InputError naming the file and, where it applies, the node.
#pragma once

#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace netvmo::io {

struct Calibration {
  int width = 0, height = 0;                  ///< image size in pixels
  cv::Matx33d K = cv::Matx33d::eye();         ///< [fx 0 cx; 0 fy cy; 0 0 1]
  cv::Vec<double, 5> dist = {0, 0, 0, 0, 0};  ///< k1, k2, p1, p2, k3
  cv::Vec3d rational = {0, 0, 0};             ///< k4, k5, k6 (OpenCV's rational model)
  /// OpenCV's fisheye (equidistant) model, cv::fisheye: dist[0..3] are its k1..k4, dist[4] and
  /// rational are zero.
  bool fisheye = false;
  std::string source;  ///< file it was read from (for messages)

  bool has_distortion() const { return cv::norm(dist) != 0.0 || cv::norm(rational) != 0.0; }
  bool is_rational() const { return cv::norm(rational) != 0.0; }
  /// The coefficients as OpenCV takes them: 1x5 (k1 k2 p1 p2 k3), or 1x8 with k4 k5 k6; fisheye:
  /// 1x4 (k1 k2 k3 k4, for cv::fisheye's functions).
  cv::Mat distortion() const;
};

/// Reads an OpenCV FileStorage calibration file (.yaml/.yml/.xml/.json).
Calibration load_calibration_opencv(const std::filesystem::path& file);
/// Reads a ViSP XML calibration file (vpXmlParserCamera) for the named camera.
Calibration load_calibration_visp_xml(const std::filesystem::path& file,
                                      const std::string& camera_name);
/// Reads a ROS camera_info YAML calibration file (see the top of this header).
Calibration load_calibration_ros(const std::filesystem::path& file);
/// The format a .yaml/.yml calibration file is read as, and why (for messages).
struct CalibrationFormat {
  enum Kind { opencv, ros_camera_info } kind = opencv;
  std::string why;  ///< e.g. "it starts with OpenCV's %YAML:1.0 (line 1)"
  const char* name() const {
    return kind == opencv ? "an OpenCV FileStorage file" : "a ROS camera_info file";
  }
};
/// Picks the format of a .yaml/.yml calibration file by its content: any mark of OpenCV
/// FileStorage (a first line `%YAML:1.0`, a `!!opencv-matrix` tag, a matrix's `dt` key) makes it
/// OpenCV's, whatever else it holds (a `distortion_model` key too); otherwise a top-level
/// `distortion_model` key makes it a ROS camera_info; otherwise OpenCV's.
CalibrationFormat detect_yaml_calibration_format(const std::filesystem::path& file);
/// True when detect_yaml_calibration_format() takes the file for a ROS camera_info.
bool looks_like_ros_camera_info(const std::filesystem::path& file);
/// Reads a .yaml/.yml calibration file in the format detect_yaml_calibration_format() picks;
/// an error names the file and key and ends with the format it was read as and why.
Calibration load_calibration_yaml(const std::filesystem::path& file);
/// Writes an OpenCV FileStorage YAML calibration (the format `netvmo render` writes).
void save_calibration_opencv(const std::filesystem::path& file, const Calibration& calib);

/// Writes a ROS camera_info YAML (as ROS's camera_calibration does for a monocular camera:
/// identity rectification, projection_matrix = [K | 0]), e.g. to hand a calibration to ROS.
void save_calibration_ros(const std::filesystem::path& file, const Calibration& calib,
                          const std::string& camera_name);

/// Pixel points (OpenCV convention) to undistorted normalized image coordinates
/// ((u - cx)/fx, (v - cy)/fy after removing distortion), with cv::undistortPoints iterated to
/// convergence (OpenCV's default of 5 fixed iterations leaves errors of ~0.1 px at the image
/// border for strong distortion); cv::fisheye::undistortPoints for a fisheye calibration.
std::vector<cv::Point2d> normalize_points(const std::vector<cv::Point2d>& px,
                                          const Calibration& calib);
/// Inverse: normalized (undistorted) coordinates to distorted pixels (cv::projectPoints;
/// cv::fisheye::distortPoints for a fisheye calibration).
std::vector<cv::Point2d> denormalize_points(const std::vector<cv::Point2d>& xy,
                                            const Calibration& calib);
/// Pixel points to ideal (undistorted) pixels: K times their normalize_points() coordinates,
/// where straight lines of the scene are straight.
std::vector<cv::Point2d> ideal_pixels(const std::vector<cv::Point2d>& px, const Calibration& calib);
/// Inverse of ideal_pixels(): ideal pixels to distorted pixels (K^-1, then denormalize_points()).
std::vector<cv::Point2d> distorted_pixels(const std::vector<cv::Point2d>& ideal,
                                          const Calibration& calib);

}  // namespace netvmo::io
