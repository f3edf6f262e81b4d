// Camera intrinsics for the tag front end: OpenCV's pinhole model with the 5-coefficient
// Brown-Conrady distortion (k1, k2, p1, p2, k3), pixel (col,row) centred at continuous (col,row).
//
// Two file formats are read:
//  - OpenCV FileStorage (YAML/XML/JSON as written by cv::FileStorage, e.g. by OpenCV's own
//    calibration tools or by `netvmo render`): `image_width`, `image_height`, `camera_matrix`
//    (3x3), `distortion_coefficients` (4 or 5 numbers; 8/12/14 accepted when the extra
//    coefficients are all zero).
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
  std::string source;                         ///< file it was read from (for messages)

  bool has_distortion() const { return cv::norm(dist) != 0.0; }
};

/// Reads an OpenCV FileStorage calibration file (.yaml/.yml/.xml/.json).
Calibration load_calibration_opencv(const std::filesystem::path& file);
/// Reads a ViSP XML calibration file (vpXmlParserCamera) for the named camera.
Calibration load_calibration_visp_xml(const std::filesystem::path& file,
                                      const std::string& camera_name);
/// Writes an OpenCV FileStorage YAML calibration (the format `netvmo render` writes).
void save_calibration_opencv(const std::filesystem::path& file, const Calibration& calib);

/// Pixel points (OpenCV convention) to undistorted normalized image coordinates
/// ((u - cx)/fx, (v - cy)/fy after removing distortion), with cv::undistortPoints iterated to
/// convergence (OpenCV's default of 5 fixed iterations leaves errors of ~0.1 px at the image
/// border for strong distortion).
std::vector<cv::Point2d> normalize_points(const std::vector<cv::Point2d>& px,
                                          const Calibration& calib);
/// Inverse: normalized (undistorted) coordinates to distorted pixels (cv::projectPoints).
std::vector<cv::Point2d> denormalize_points(const std::vector<cv::Point2d>& xy,
                                            const Calibration& calib);

}  // namespace netvmo::io
