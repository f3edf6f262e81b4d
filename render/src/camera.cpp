#include "netvmo/render/camera.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace netvmo::render {

bool Intrinsics::has_distortion() const {
  for (double d : dist)
    if (d != 0) return true;
  return false;
}

Vec2 Intrinsics::distort(const Vec2& xn) const {
  const double x = xn.x(), y = xn.y();
  if (lens == Lens::Fisheye) {  // cv::fisheye: equidistant with a polynomial in theta
    const double r = std::hypot(x, y);
    if (r < 1e-15) return xn;
    const double th = std::atan(r), t2 = th * th;
    const double thd = th * (1 + t2 * (dist[0] + t2 * (dist[1] + t2 * (dist[2] + t2 * dist[3]))));
    return xn * (thd / r);
  }
  if (lens == Lens::Rational) {
    const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3], k3 = dist[4];
    const double k4 = dist[5], k5 = dist[6], k6 = dist[7];
    const double r2 = x * x + y * y;
    const double radial =
        (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)));
    return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
  }
  const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3], k3 = dist[4];
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

std::optional<Vec2> Intrinsics::undistort(const Vec2& xd) const {
  if (!has_distortion()) return xd;
  Vec2 x = xd;
  const double h = 1e-7;
  for (int it = 0; it < 50; ++it) {
    const Vec2 f = distort(x) - xd;
    if (f.norm() < 1e-13) return x;
    Eigen::Matrix2d J;
    J.col(0) = (distort(x + Vec2(h, 0)) - distort(x - Vec2(h, 0))) / (2 * h);
    J.col(1) = (distort(x + Vec2(0, h)) - distort(x - Vec2(0, h))) / (2 * h);
    if (std::abs(J.determinant()) < 1e-9) return std::nullopt;
    x -= J.inverse() * f;
    if (!x.allFinite()) return std::nullopt;
  }
  return (distort(x) - xd).norm() < 1e-9 ? std::optional<Vec2>(x) : std::nullopt;
}

std::optional<Vec2> Intrinsics::project(const Vec3& p) const {
  if (!(p.z() > 0)) return std::nullopt;
  const Vec2 d = distort(Vec2(p.x() / p.z(), p.y() / p.z()));
  return Vec2(fx * d.x() + cx, fy * d.y() + cy);
}

std::optional<Vec2> Intrinsics::unproject(const Vec2& uv) const {
  return undistort(Vec2((uv.x() - cx) / fx, (uv.y() - cy) / fy));
}

void Intrinsics::validate() const {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw std::invalid_argument("image size must be between 1 and 16384 pixels");
  if (!(fx > 0) || !(fy > 0)) throw std::invalid_argument("focal lengths fx, fy must be positive");
  if (!std::isfinite(cx) || !std::isfinite(cy))
    throw std::invalid_argument("cx, cy must be finite");
  for (double d : dist)
    if (!std::isfinite(d)) throw std::invalid_argument("distortion coefficients must be finite");
  const size_t used = lens == Lens::Fisheye ? 4 : lens == Lens::Rational ? 8 : 5;
  for (size_t i = used; i < dist.size(); ++i)
    if (dist[i] != 0)
      throw std::invalid_argument("the lens model takes " + std::to_string(used) +
                                  " distortion coefficients");
}

}  // namespace netvmo::render

namespace netvmo::render {

SensorModel SensorModel::realistic() {
  SensorModel m;
  m.tone = Tone::Srgb;
  m.full_well = 240;
  m.bloom = 0.3;
  m.vignetting = Vignetting::Cos4;
  m.psf_sigma = 0.6;
  m.jpeg_quality = 90;
  m.exposure_time = 0.004;
  m.line_delay = 20e-6;
  m.f_number = 2.8;
  m.focus_distance = 2.0;
  m.focal_length_mm = 6.0;
  return m;
}

bool SensorModel::image_effects() const {
  return gain != 1.0 || tone != Tone::Linear || full_well > 0 || vignetting != Vignetting::None ||
         psf_sigma > 0 || sharpen_amount > 0;
}

double SensorModel::focal_length_m(double fx) const {
  if (focal_length_mm > 0) return focal_length_mm * 1e-3;
  const double v = fx * pixel_pitch_um * 1e-6, d = focus_distance;
  return v * d / (v + d);
}

void SensorModel::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(what);
  };
  need(gain > 0 && std::isfinite(gain), "sensor.gain must be positive");
  need(gamma > 0 && std::isfinite(gamma), "sensor.gamma must be positive");
  need(full_well >= 0 && std::isfinite(full_well), "sensor.full_well must be >= 0 (0 = none)");
  need(bloom >= 0 && bloom <= 1, "sensor.bloom must be between 0 and 1");
  for (double a : vignetting_poly)
    need(std::isfinite(a), "sensor.vignetting_poly coefficients must be finite");
  need(psf_sigma >= 0 && psf_sigma <= 20, "sensor.psf_sigma must be between 0 and 20 px");
  need(jpeg_quality >= 0 && jpeg_quality <= 100, "sensor.jpeg_quality must be between 1 and 100");
  need(sharpen_amount >= 0 && sharpen_amount <= 10,
       "sensor.sharpen_amount must be between 0 and 10");
  need(sharpen_sigma >= 0.1 && sharpen_sigma <= 20,
       "sensor.sharpen_sigma must be between 0.1 and 20 px");
  need(exposure_time >= 0 && exposure_time <= 10, "sensor.exposure_time must be 0..10 s");
  need(std::abs(line_delay) <= 1e-2, "sensor.line_delay must be within +-0.01 s");
  need(f_number == 0 || (f_number >= 0.5 && f_number <= 1000),
       "sensor.f_number must be 0 (pinhole) or between 0.5 and 1000");
  if (f_number > 0) {
    need(focus_distance > 0 && std::isfinite(focus_distance),
         "sensor.focus_distance must be positive");
    need(focal_length_mm > 0 || pixel_pitch_um > 0,
         "sensor.f_number needs focal_length_mm or pixel_pitch_um");
  }
  need(focal_length_mm >= 0 && focal_length_mm < 1e4, "sensor.focal_length_mm must be >= 0");
  need(pixel_pitch_um >= 0 && pixel_pitch_um < 1e3, "sensor.pixel_pitch_um must be >= 0");
}

Pose CameraSpec::believed_pose(double t) const {
  if (!moving()) return g_wi_believed;
  const Pose delta0 = g_wi_believed * true_pose(0.0).inverse();  // Delta(0)
  Pose drift = Pose::Identity();
  drift.linear() = exp_so3(t * believed_drift.tail<3>());
  drift.translation() = t * believed_drift.head<3>();
  return drift * delta0 * true_pose(t);
}

bool CameraSpec::moving() const {
  return (motion && motion->kind != Trajectory::Kind::Static) || !believed_drift.isZero(0.0);
}

void CameraSpec::set_resolution(int width, int height) {
  Intrinsics& k = intrinsics;
  // width / k.width == height / k.height, in integers.
  if (width <= 0 || height <= 0 ||
      static_cast<long long>(width) * k.height != static_cast<long long>(height) * k.width)
    throw std::invalid_argument("resolution " + std::to_string(width) + "x" +
                                std::to_string(height) + " for camera " + std::to_string(id) +
                                " of " + std::to_string(k.width) + "x" + std::to_string(k.height) +
                                ": needs the same aspect ratio");
  const double s = static_cast<double>(width) / k.width;
  k.width = width;
  k.height = height;
  k.fx *= s;
  k.fy *= s;
  k.cx = (k.cx + 0.5) * s - 0.5;
  k.cy = (k.cy + 0.5) * s - 0.5;
  sensor.psf_sigma *= s;
  sensor.sharpen_sigma *= s;
  sensor.pixel_pitch_um /= s;
  sensor.line_delay /= s;
}

}  // namespace netvmo::render
