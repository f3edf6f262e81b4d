// The tag's black square in bit-cell coordinates and its image (internal to the front end):
// shared by the edge fit (refine.cpp) and the frame check (border_check.cpp).
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend::detail {

/// The sides of the object square [0, n]^2 (X right, Y down the printed tag): side k runs from
/// corner k to corner k + 1 (c0 (0, n), c1 (n, n), c2 (n, 0), c3 (0, 0), libapriltag's order),
/// from `start` along the unit `along`, with the outward unit normal `outward` [cells].
struct SquareSides {
  explicit SquareSides(int n) {
    const double N = n;
    const cv::Point2d s[4] = {{0, N}, {N, N}, {N, 0}, {0, 0}};
    const cv::Point2d d[4] = {{1, 0}, {0, -1}, {-1, 0}, {0, 1}};
    const cv::Point2d o[4] = {{0, 1}, {1, 0}, {0, -1}, {-1, 0}};
    for (int k = 0; k < 4; ++k) start[k] = s[k], along[k] = d[k], outward[k] = o[k];
  }
  cv::Point2d start[4], along[4], outward[4];
};

/// Object square in cell units -> image pixels: the homography of the corners, in undistorted
/// (ideal) pixels when the calibration has distortion, then re-distorted.
class SquareToImage {
 public:
  SquareToImage(const std::array<cv::Point2d, 4>& corners, int n, const io::Calibration* calib)
      : SquareToImage(ideal_corners(corners, calib), n, calib, Ideal{}) {}
  /// Marks corners given in undistorted (ideal) pixels already.
  struct Ideal {};
  /// From corners in undistorted (ideal) pixels; `calib` re-distorts the mapped points.
  SquareToImage(const std::array<cv::Point2d, 4>& ideal, int n, const io::Calibration* calib, Ideal)
      : calib_(calib && calib->has_distortion() ? calib : nullptr) {
    // Corner k of the object square is the start of side k (SquareSides): c0 bottom-left, c1
    // bottom-right, c2 top-right, c3 top-left of the printed tag.
    const SquareSides sides(n);
    // H with h33 = 1 from the four correspondences (8 x 8 linear system, in double).
    cv::Matx<double, 8, 8> A;
    cv::Matx<double, 8, 1> b;
    for (int k = 0; k < 4; ++k) {
      const double x = sides.start[k].x, y = sides.start[k].y;
      const double u = ideal[static_cast<size_t>(k)].x, v = ideal[static_cast<size_t>(k)].y;
      const double r0[8] = {x, y, 1, 0, 0, 0, -x * u, -y * u};
      const double r1[8] = {0, 0, 0, x, y, 1, -x * v, -y * v};
      for (int j = 0; j < 8; ++j) {
        A(2 * k, j) = r0[j];
        A(2 * k + 1, j) = r1[j];
      }
      b(2 * k) = u;
      b(2 * k + 1) = v;
    }
    cv::Matx<double, 8, 1> h;
    ok_ = cv::solve(A, b, h, cv::DECOMP_LU);
    for (int j = 0; j < 8; ++j) H_(j / 3, j % 3) = h(j);
    H_(2, 2) = 1.0;
  }
  /// `corners` in undistorted (ideal) pixels where `calib` has distortion, else as they are.
  static std::array<cv::Point2d, 4> ideal_corners(const std::array<cv::Point2d, 4>& corners,
                                                  const io::Calibration* calib) {
    if (!calib || !calib->has_distortion()) return corners;
    const auto c = io::ideal_pixels({corners.begin(), corners.end()}, *calib);
    return {c[0], c[1], c[2], c[3]};
  }
  bool ok() const { return ok_; }
  std::vector<cv::Point2d> map(const std::vector<cv::Point2d>& obj) const {
    return to_image(map_ideal(obj));
  }
  /// The homography alone: object points to undistorted (ideal) pixels.
  std::vector<cv::Point2d> map_ideal(const std::vector<cv::Point2d>& obj) const {
    std::vector<cv::Point2d> out;
    out.reserve(obj.size());
    for (const auto& p : obj) {
      const cv::Vec3d q = H_ * cv::Vec3d(p.x, p.y, 1.0);
      out.emplace_back(q[0] / q[2], q[1] / q[2]);
    }
    return out;
  }
  /// Ideal pixels to image pixels (re-distorted where the calibration has distortion).
  std::vector<cv::Point2d> to_image(std::vector<cv::Point2d> ideal) const {
    return calib_ ? io::distorted_pixels(ideal, *calib_) : ideal;
  }

 private:
  const io::Calibration* calib_;
  cv::Matx33d H_ = cv::Matx33d::zeros();
  bool ok_ = false;
};

}  // namespace netvmo::frontend::detail
