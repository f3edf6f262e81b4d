#include "synth.hpp"

#include "test_util.hpp"

#include <apriltag/apriltag.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <utility>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::testing {
namespace fs = std::filesystem;
using io::Calibration;

namespace {

struct Bitmap {
  cv::Mat bits;  // total_width x total_width, 255 white / 0 black
  int total = 0, border = 0;
};

Bitmap tag_bitmap(const std::string& family, int id) {
  const render::TagFamilyPtr fam = render::create_tag_family(family);
  if (id < 0 || static_cast<uint32_t>(id) >= fam->ncodes)
    throw std::invalid_argument("synth: tag id out of range");
  image_u8_t* im = apriltag_to_image(fam.get(), id);
  Bitmap b;
  b.total = fam->total_width;
  b.border = (fam->total_width - fam->width_at_border) / 2;
  b.bits = cv::Mat(im->height, im->width, CV_8UC1);
  for (int r = 0; r < im->height; ++r)
    for (int c = 0; c < im->width; ++c) b.bits.at<uchar>(r, c) = im->buf[r * im->stride + c];
  // libapriltag 3.3 does not export image_u8_destroy; it is free(buf) + free(im).
  std::free(im->buf);
  std::free(im);
  return b;
}

/// Undistorted normalized ray (x, y) of every sub-sample, cached for the last few
/// calibrations (undistorting ~5 M sub-samples takes about a second).
const std::vector<cv::Point2d>& subsample_rays(const Calibration& c, int ss) {
  struct Entry {
    Calibration calib;
    int ss;
    std::vector<cv::Point2d> rays;
  };
  static std::vector<std::unique_ptr<Entry>> cache;
  for (const auto& e : cache)
    if (e->ss == ss && e->calib.width == c.width && e->calib.height == c.height &&
        cv::norm(cv::Mat(e->calib.K), cv::Mat(c.K)) == 0 && cv::norm(e->calib.dist - c.dist) == 0 &&
        cv::norm(e->calib.rational - c.rational) == 0)
      return e->rays;
  if (cache.size() >= 4) cache.erase(cache.begin());
  auto entry = std::make_unique<Entry>();
  entry->calib = c;
  entry->ss = ss;
  std::vector<cv::Point2d> px;
  px.reserve(static_cast<size_t>(c.width) * c.height * ss * ss);
  for (int r = 0; r < c.height; ++r)
    for (int sr = 0; sr < ss; ++sr)
      for (int col = 0; col < c.width; ++col)
        for (int sc = 0; sc < ss; ++sc)
          px.emplace_back(col - 0.5 + (sc + 0.5) / ss, r - 0.5 + (sr + 0.5) / ss);
  auto& rays = entry->rays;
  if (c.has_distortion()) {
    rays = io::normalize_points(px, c);
  } else {
    rays.resize(px.size());
    const cv::Matx33d Ki = c.K.inv();
    for (size_t i = 0; i < px.size(); ++i) {
      const cv::Vec3d q = Ki * cv::Vec3d(px[i].x, px[i].y, 1.0);
      rays[i] = cv::Point2d(q[0] / q[2], q[1] / q[2]);
    }
  }
  cache.push_back(std::move(entry));
  return cache.back()->rays;
}

/// Whether the print is white at bitmap coordinates (cx, cy) (inside the bitmap), with the black
/// grown by `spread` cells (Euclidean dilation; negative: the white grown, i.e. an erosion). The
/// bordered families' outermost bitmap ring is white, so the black never spreads beyond it.
bool printed_white(const cv::Mat& bits, double cx, double cy, double spread) {
  const int c = static_cast<int>(cx), r = static_cast<int>(cy);
  const bool white = bits.at<uchar>(r, c) > 127;
  if (spread == 0.0) return white;
  // Grown colour: the opposite of this cell's when a cell of the growing colour lies within
  // |spread| (cells outside the bitmap are the white quiet zone).
  const bool grow_black = spread > 0.0;
  if (white != grow_black) return white;  // the cell already has the growing colour
  const double reach = std::abs(spread);
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc) {
      if (!dr && !dc) continue;
      const int rr = r + dr, cc = c + dc;
      const bool inside = rr >= 0 && cc >= 0 && rr < bits.rows && cc < bits.cols;
      const bool w = !inside || bits.at<uchar>(rr, cc) > 127;
      if (w == white) continue;  // not the growing colour
      const double ex = std::max({0.0, cc - cx, cx - (cc + 1)});
      const double ey = std::max({0.0, rr - cy, cy - (rr + 1)});
      if (ex * ex + ey * ey <= reach * reach) return !white;
    }
  return white;
}

/// The ray o + lambda d (tag frame) against a card of curvature k wrapped on the cylinder of
/// SynthTag::bend: the nearest hit with lambda > 0 on the card's half of the cylinder
/// (cos(k u) > 0), as lambda and (u, y, 0), u the arc length along the tag's x axis.
std::optional<std::pair<double, obs::Vec3>> bent_hit(const obs::Vec3& o, const obs::Vec3& d,
                                                     double k) {
  // (o_x + l d_x)^2 + (o_z + l d_z + 1/k)^2 = 1/k^2, multiplied by k: the terms in 1/k cancel
  const double a = k * (d.x() * d.x() + d.z() * d.z());
  const double b = 2.0 * (k * (o.x() * d.x() + o.z() * d.z()) + d.z());
  const double c = k * (o.x() * o.x() + o.z() * o.z()) + 2.0 * o.z();
  const double disc = b * b - 4.0 * a * c;
  if (!(disc >= 0.0)) return std::nullopt;
  const double h = -0.5 * (b + std::copysign(std::sqrt(disc), b));  // no cancellation
  std::optional<std::pair<double, obs::Vec3>> best;
  for (const double l : {h != 0.0 ? c / h : -1.0, a != 0.0 ? h / a : -1.0}) {
    if (!(l > 0.0) || (best && l >= best->first)) continue;
    const obs::Vec3 x = o + l * d;
    if (!(1.0 + k * x.z() > 0.0)) continue;  // the far half of the cylinder
    best = {l, obs::Vec3(std::atan2(k * x.x(), 1.0 + k * x.z()) / k, x.y(), 0.0)};
  }
  return best;
}

}  // namespace

cv::Mat render_tags(const Calibration& calib, const std::vector<SynthTag>& tags,
                    const SynthSettings& opt) {
  const int ss = opt.supersample;
  const auto& rays = subsample_rays(calib, ss);
  struct Prepared {
    Bitmap bm;
    obs::Mat3 R;
    obs::Vec3 t, n;
    double cell, half, bend;
    obs::Vec3 origin;  // the camera centre in the tag frame
  };
  std::vector<Prepared> prep;
  for (const auto& tag : tags) {
    Prepared p;
    p.bm = tag_bitmap(opt.family, tag.id);
    for (const auto& [r, c] : tag.flipped_cells)
      p.bm.bits.at<uchar>(r, c) = static_cast<uchar>(255 - p.bm.bits.at<uchar>(r, c));
    p.R = tag.g_io.linear();
    p.t = tag.g_io.translation();
    p.n = p.R.col(2);
    const int at_border = p.bm.total - 2 * p.bm.border;
    p.cell = tag.size / at_border;
    p.half = 0.5 * tag.size;
    p.bend = tag.bend;
    p.origin = -p.R.transpose() * p.t;
    // the printed face is visible only from the side its z axis points to
    if (p.origin.z() > 0) prep.push_back(std::move(p));
  }
  const double wq = opt.quiet_zone_cells;
  // A border other than one cell wide on some edge: the ring painted here, not from the bitmap.
  bool uneven = opt.border_width != 1.0;
  for (double w : opt.border_width_per_edge) uneven = uneven || w != 1.0;
  cv::Mat out(calib.height, calib.width, CV_8UC1);
  std::mt19937_64 rng(opt.seed);
  std::normal_distribution<double> noise(0.0, opt.noise_sigma > 0 ? opt.noise_sigma : 1.0);
  size_t i = 0;
  std::vector<double> row_acc(static_cast<size_t>(calib.width));
  for (int r = 0; r < calib.height; ++r) {
    std::fill(row_acc.begin(), row_acc.end(), 0.0);
    for (int sr = 0; sr < ss; ++sr)
      for (int col = 0; col < calib.width; ++col)
        for (int sc = 0; sc < ss; ++sc, ++i) {
          const obs::Vec3 ray(rays[i].x, rays[i].y, 1.0);
          double best = 1e300, value = opt.background;
          for (const auto& p : prep) {
            double lambda;
            obs::Vec3 q;  // the hit in the tag frame; for a bent card, (arc length along x, y)
            if (p.bend == 0.0) {
              const double den = p.n.dot(ray);
              if (std::abs(den) < 1e-12) continue;
              lambda = p.n.dot(p.t) / den;
              if (!(lambda > 0) || lambda >= best) continue;
              q = p.R.transpose() * (lambda * ray - p.t);
            } else {
              const auto hit = bent_hit(p.origin, p.R.transpose() * ray, p.bend);
              if (!hit) continue;
              lambda = hit->first;
              if (lambda >= best) continue;
              q = hit->second;
            }
            const double cx = (q.x() + p.half) / p.cell + p.bm.border;  // bitmap column
            const double cy = (p.half - q.y()) / p.cell + p.bm.border;  // bitmap row (+y up)
            if (cx < -wq || cy < -wq || cx >= p.bm.total + wq || cy >= p.bm.total + wq) continue;
            best = lambda;
            // Distance into the black square from its outer edge [cells] (< 0 outside it).
            const double in =
                std::min(std::min(cx, cy), std::min(p.bm.total - cx, p.bm.total - cy)) -
                p.bm.border;
            // Into the black square from its top, right, bottom and left edges [cells].
            const std::array<double, 4> from{cy - p.bm.border, p.bm.total - p.bm.border - cx,
                                             p.bm.total - p.bm.border - cy, cx - p.bm.border};
            bool ring = false, inked = false;
            for (size_t e = 0; e < 4; ++e) {
              const double w = opt.border_width * opt.border_width_per_edge[e];
              ring = ring || (in >= 0.0 && from[e] < std::max(1.0, w));
              inked = inked || (in >= 0.0 && from[e] < w);
            }
            if (uneven && ring)
              value = inked ? opt.black : opt.white;
            else if (cx >= 0 && cy >= 0 && cx < p.bm.total && cy < p.bm.total)
              value = printed_white(p.bm.bits, cx, cy, opt.ink_spread) ? opt.white : opt.black;
            else
              value = opt.white;
          }
          row_acc[static_cast<size_t>(col)] += value;
        }
    for (int col = 0; col < calib.width; ++col) {
      double v = row_acc[static_cast<size_t>(col)] / (ss * ss);
      for (const auto& o : opt.occluders)
        if (o.contains(cv::Point(col, r))) v = opt.occluder_level;
      if (opt.noise_sigma > 0) v += noise(rng);
      out.at<uchar>(r, col) = cv::saturate_cast<uchar>(v);
    }
  }
  return out;
}

cv::Mat render_camera_picture(const Calibration& calib, const std::vector<SynthTag>& tags,
                              const SynthSettings& opt, double blur_sigma, double gamma) {
  SynthSettings linear = opt;
  linear.noise_sigma = 0.0;
  cv::Mat v;
  render_tags(calib, tags, linear).convertTo(v, CV_64F, 1.0 / 255.0);
  if (opt.motion_blur != cv::Point2d(0.0, 0.0)) {
    // The line from -motion/2 to +motion/2, 16 samples per px of length, each splatted
    // bilinearly into the kernel: a box of the motion's length along its direction.
    const double len = cv::norm(opt.motion_blur);
    const int half = static_cast<int>(std::ceil(0.5 * len)) + 1;
    cv::Mat k = cv::Mat::zeros(2 * half + 1, 2 * half + 1, CV_64F);
    const int steps = std::max(2, static_cast<int>(std::ceil(16 * len)));
    for (int i = 0; i < steps; ++i) {
      const cv::Point2d q = ((i + 0.5) / steps - 0.5) * opt.motion_blur + cv::Point2d(half, half);
      const int x0 = static_cast<int>(std::floor(q.x)), y0 = static_cast<int>(std::floor(q.y));
      const double ax = q.x - x0, ay = q.y - y0;
      k.at<double>(y0, x0) += (1 - ax) * (1 - ay);
      k.at<double>(y0, x0 + 1) += ax * (1 - ay);
      k.at<double>(y0 + 1, x0) += (1 - ax) * ay;
      k.at<double>(y0 + 1, x0 + 1) += ax * ay;
    }
    k /= cv::sum(k)[0];
    cv::filter2D(v, v, -1, k, cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
  }
  if (blur_sigma > 0.0) cv::GaussianBlur(v, v, cv::Size(0, 0), blur_sigma);
  cv::pow(v, 1.0 / gamma, v);
  v *= 255.0;
  if (opt.noise_sigma > 0.0) {
    std::mt19937_64 rng(opt.seed);
    std::normal_distribution<double> noise(0.0, opt.noise_sigma);
    for (int r = 0; r < v.rows; ++r)
      for (int c = 0; c < v.cols; ++c) v.at<double>(r, c) += noise(rng);
  }
  cv::Mat out;
  v.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

double max_corner_error(const std::array<cv::Point2d, 4>& a, const std::array<cv::Point2d, 4>& b) {
  double e = 0.0;
  for (size_t k = 0; k < 4; ++k) e = std::max(e, cv::norm(a[k] - b[k]));
  return e;
}

std::array<cv::Point2d, 4> move_side(const std::array<cv::Point2d, 4>& quad, size_t k, double d) {
  const cv::Point2d a = quad[k], b = quad[(k + 1) % 4];
  const cv::Point2d centre = 0.25 * (quad[0] + quad[1] + quad[2] + quad[3]);
  cv::Point2d n(b.y - a.y, a.x - b.x);
  n /= cv::norm(n);
  if (n.dot(0.5 * (a + b) - centre) < 0) n = -n;
  auto out = quad;
  out[k] += d * n;
  out[(k + 1) % 4] += d * n;
  return out;
}

std::array<cv::Point2d, 4> project_corners(const Calibration& calib, const obs::SE3& g_io,
                                           double size) {
  const auto model = obs::FeatureModel::square(size);
  std::vector<cv::Point3d> cam_pts;
  for (const auto& p : model.points_o) {
    const obs::Vec3 q = g_io * p;
    cam_pts.emplace_back(q.x(), q.y(), q.z());
  }
  std::vector<cv::Point2d> px;
  cv::projectPoints(cam_pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calib.K),
                    calib.distortion(), px);
  return {px[0], px[1], px[2], px[3]};
}

std::array<cv::Point2d, 4> project_corners(const Calibration& calib, const SynthTag& tag) {
  if (tag.bend == 0.0) return project_corners(calib, tag.g_io, tag.size);
  const double k = tag.bend;
  std::vector<cv::Point3d> cam_pts;
  for (const auto& p : obs::FeatureModel::square(tag.size).points_o) {
    const double u = p.x();  // the corner's arc length along x
    const obs::Vec3 q =
        tag.g_io * obs::Vec3(std::sin(k * u) / k, p.y(), -(1.0 - std::cos(k * u)) / k);
    cam_pts.emplace_back(q.x(), q.y(), q.z());
  }
  std::vector<cv::Point2d> px;
  cv::projectPoints(cam_pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calib.K),
                    calib.distortion(), px);
  return {px[0], px[1], px[2], px[3]};
}

Calibration test_calibration(bool distortion) {
  Calibration c;
  c.width = 640;
  c.height = 480;
  c.K = cv::Matx33d(610.0, 0, 321.7, 0, 605.0, 238.4, 0, 0, 1);
  if (distortion) c.dist = {-0.12, 0.05, 4e-4, -3e-4, 0.0};
  return c;
}

Rectified rectify(const cv::Mat& raw, const Calibration& calib, double m, int interpolation) {
  Rectified r;
  r.calib.width = static_cast<int>(std::lround(calib.width * m));
  r.calib.height = static_cast<int>(std::lround(calib.height * m));
  r.calib.K = cv::Matx33d(calib.K(0, 0) * m, 0, (calib.K(0, 2) + 0.5) * m - 0.5, 0,
                          calib.K(1, 1) * m, (calib.K(1, 2) + 0.5) * m - 0.5, 0, 0, 1);
  cv::Mat mx, my;
  cv::initUndistortRectifyMap(cv::Mat(calib.K), calib.distortion(), cv::Mat(), cv::Mat(r.calib.K),
                              cv::Size(r.calib.width, r.calib.height), CV_32FC1, mx, my);
  cv::remap(raw, r.image, mx, my, interpolation, cv::BORDER_CONSTANT, cv::Scalar(0));
  return r;
}

obs::SE3 facing_pose(double distance, double dx, double dy, const obs::Vec3& tilt) {
  obs::SE3 g = obs::SE3::Identity();
  g.linear() = obs::exp_so3(obs::Vec3(M_PI, 0, 0)) * obs::exp_so3(tilt);
  g.translation() = obs::Vec3(dx, dy, distance);
  return g;
}

double corner_rms(const std::array<cv::Point2d, 4>& a, const std::array<cv::Point2d, 4>& b) {
  double s = 0;
  for (size_t k = 0; k < 4; ++k) {
    const cv::Point2d d = a[k] - b[k];
    s += d.dot(d);
  }
  return std::sqrt(s / 4.0);
}

SynthDatasetSpec simple_dataset_spec(int cameras, int frames, bool video) {
  SynthDatasetSpec spec;
  for (int i = 0; i < cameras; ++i) {
    SynthCamera c;
    c.id = i + 1;
    c.calib = test_calibration();
    c.g_wi.translation() = obs::Vec3(0.3 * i, 0.0, 0.0);
    spec.cameras.push_back(c);
  }
  for (int f = 0; f < frames; ++f)
    spec.g_wo.push_back(facing_pose(2.0, 0.1 + 0.05 * f, -0.05, {0.2, -0.15 + 0.05 * f, 0.3 * f}));
  spec.video = video;
  return spec;
}

namespace {
// Directories made by fresh_dir() in this process, removed at exit.
struct TempDirs {
  std::vector<fs::path> dirs;
  ~TempDirs() {
    for (const auto& d : dirs) {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  }
};
TempDirs g_temp_dirs;
}  // namespace

fs::path fresh_dir(const std::string& name) {
  const fs::path d = test::make_scratch_dir(name);
  g_temp_dirs.dirs.push_back(d);
  return d;
}

std::vector<std::vector<std::array<cv::Point2d, 4>>> write_synth_dataset(
    const fs::path& dir, const SynthDatasetSpec& spec) {
  fs::create_directories(dir / "calib");
  std::ofstream net(dir / "network.yaml");
  net.precision(17);
  net << "fps: " << spec.fps << "\n";
  net << "target: {family: " << spec.options.family << ", id: " << spec.target_id
      << ", size: " << spec.tag_size << "}\n";
  net << "cameras:\n";
  for (const auto& c : spec.cameras) {
    const obs::Vec3 p = c.g_wi.translation(), w = obs::rotvec(c.g_wi);
    net << "  - {id: " << c.id << ", p_wi: [" << p.x() << ", " << p.y() << ", " << p.z()
        << "], r_wi: [" << w.x() << ", " << w.y() << ", " << w.z() << "]}\n";
  }
  net << "edges: [";
  for (size_t k = 1; k < spec.cameras.size(); ++k)
    net << (k > 1 ? ", " : "") << "[" << spec.cameras[k - 1].id << ", " << spec.cameras[k].id
        << "]";
  net << "]\n";
  net.close();

  std::ofstream truth(dir / "truth.csv"), target(dir / "target.csv");
  truth.precision(10);
  target.precision(12);
  truth << "frame,t,camera,in_fov,visible_fraction,u0,v0,u1,v1,u2,v2,u3,v3\n";
  target << "frame,t,px,py,pz,rx,ry,rz\n";
  for (size_t f = 0; f < spec.g_wo.size(); ++f) {
    const obs::Vec3 p = spec.g_wo[f].translation(), w = obs::rotvec(spec.g_wo[f]);
    target << f << "," << f / spec.fps << "," << p.x() << "," << p.y() << "," << p.z() << ","
           << w.x() << "," << w.y() << "," << w.z() << "\n";
  }

  std::vector<std::vector<std::array<cv::Point2d, 4>>> corners(spec.cameras.size());
  for (size_t ci = 0; ci < spec.cameras.size(); ++ci) {
    const auto& cam = spec.cameras[ci];
    const std::string name = "cam_" + std::to_string(cam.id);
    io::save_calibration_opencv(dir / "calib" / (name + ".yaml"), cam.calib);
    cv::VideoWriter vw;
    if (spec.video) {
      const std::string& cc = spec.video_fourcc;
      if (cc.size() != 4) throw std::invalid_argument("synth: fourcc must have 4 characters");
      vw.open((dir / (name + spec.video_ext)).string(),
              cv::VideoWriter::fourcc(cc[0], cc[1], cc[2], cc[3]), spec.fps,
              cv::Size(cam.calib.width, cam.calib.height), false);
      if (!vw.isOpened()) throw std::runtime_error("synth: cannot open VideoWriter " + cc);
    } else {
      fs::create_directories(dir / name);
    }
    for (size_t f = 0; f < spec.g_wo.size(); ++f) {
      const obs::SE3 g_io = cam.g_wi.inverse() * spec.g_wo[f];
      SynthSettings opt = spec.options;
      opt.seed = spec.options.seed + 1000 * static_cast<std::uint64_t>(cam.id) + f;
      const cv::Mat img = render_tags(cam.calib, {{spec.target_id, spec.tag_size, g_io, {}}}, opt);
      if (spec.video) {
        vw.write(img);
      } else {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%06zu.png", f);
        cv::imwrite((dir / name / buf).string(), img);
      }
      const auto c = project_corners(cam.calib, g_io, spec.tag_size);
      corners[ci].push_back(c);
      const bool front = (g_io * obs::Vec3(0, 0, 0)).z() > 0;
      bool in_fov = front;
      for (const auto& p : c)
        in_fov = in_fov && p.x >= -0.5 && p.y >= -0.5 && p.x <= cam.calib.width - 0.5 &&
                 p.y <= cam.calib.height - 0.5;
      truth << f << "," << f / spec.fps << "," << cam.id << "," << (in_fov ? 1 : 0) << ","
            << (in_fov ? 1.0 : 0.0);
      for (const auto& p : c) {
        if (front)
          truth << "," << p.x << "," << p.y;
        else
          truth << ",,";
      }
      truth << "\n";
    }
  }
  return corners;
}

}  // namespace netvmo::testing
