#include "netvmo/pipeline/run/trajectories.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/number_text.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;

std::string tum_line(double t, const obs::SE3& g_wo) {
  Eigen::Quaterniond q(g_wo.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // q and -q are one rotation: one form of it
  const obs::Vec3 p = g_wo.translation();
  char buf[200];
  std::snprintf(buf, sizeof buf, "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f", t, p.x(), p.y(), p.z(),
                q.x(), q.y(), q.z(), q.w());
  return buf;
}

namespace {

struct Pending {
  TrajectoryFile file;
  std::string text;
  std::string last_where;
};

// Appends a pose to a trajectory; its time must come after the trajectory's last.
void append(Pending& p, double t, const obs::SE3& g, const std::string& where) {
  std::vector<TumRow>& rows = p.file.rows;
  if (!rows.empty() && !(t > rows.back().t)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ": t: %.9g s is not after the previous pose's %.9g s (%s)", t,
                  rows.back().t, p.last_where.c_str());
    throw InputError(where + buf);
  }
  p.text += tum_line(t, g) + "\n";
  rows.push_back({t, g, static_cast<int>(rows.size()) + 1});
  p.last_where = where;
}

// The results' clock, from their summary.json: where a dataset time t of target.csv's row of
// frame f falls on it. time_origin_s a number: t less it (cameras on their own clocks); null:
// f / fps (one clock). Without the file or the key (simulate's results, or written before the
// key existed), t itself.
std::function<double(int, double)> results_clock(const fs::path& results) {
  const auto as_is = [](int, double t) { return t; };
  const fs::path file = results / "summary.json";
  std::ifstream in(file);
  if (!in) return as_is;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) throw InputError(file.string() + ": not a JSON object");
  if (!j.contains("time_origin_s")) return as_is;
  const nlohmann::json& v = j["time_origin_s"];
  if (v.is_null()) {
    const nlohmann::json fps = j.value("fps", nlohmann::json());
    if (!fps.is_number() || !(fps.get<double>() > 0))
      throw InputError(file.string() +
                       ": fps: expected a number > 0 (time_origin_s is null: t = "
                       "frame / fps), got " +
                       fps.dump());
    const double rate = fps.get<double>();
    return [rate](int frame, double) { return frame / rate; };
  }
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    throw InputError(file.string() + ": time_origin_s: expected a number of seconds or null, got " +
                     v.dump());
  const double origin = v.get<double>();
  return [origin](int, double t) { return t - origin; };
}

std::string prefix(int target) {
  return target < 0 ? std::string() : "target_" + std::to_string(target) + "_";
}

}  // namespace

std::vector<TrajectoryFile> write_trajectories(const fs::path& results,
                                               const std::optional<fs::path>& dataset,
                                               const fs::path& out) {
  const fs::path estimates = results / "estimates.csv";
  // By (target, camera) in the order of the file's targets, then by camera id.
  std::vector<int> targets;  // in the order of the file (the first is the primary target)
  std::map<std::pair<size_t, int>, Pending> cameras;
  for (const io::EstimateRow& r : io::read_estimates_csv(estimates)) {
    size_t j = 0;
    while (j < targets.size() && targets[j] != r.target) ++j;
    if (j == targets.size()) targets.push_back(r.target);
    Pending& p = cameras[{j, r.camera}];
    p.file.target = r.target;
    p.file.camera = r.camera;
    if (r.g_w) append(p, r.t, *r.g_w, estimates.string() + ":" + std::to_string(r.line));
  }
  if (targets.empty()) throw InputError(estimates.string() + ": no rows");
  std::vector<Pending> files;
  for (auto& [key, p] : cameras) {
    if (p.file.rows.empty()) continue;  // never an estimate
    p.file.name = prefix(p.file.target) + "cam_" + std::to_string(p.file.camera) + ".txt";
    files.push_back(std::move(p));
  }
  // The truth on the results' clock (target.csv keeps the dataset's times).
  const auto clock = results_clock(results);
  if (dataset)
    for (size_t j = 0; j < targets.size(); ++j) {
      const fs::path file = *dataset / io::target_truth_file(targets[j], j == 0);
      if (j > 0 && !fs::exists(file)) continue;  // that target's truth is not known
      Pending p;
      p.file.target = targets[j];
      p.file.name = prefix(targets[j]) + "truth.txt";
      for (const io::TargetTruthRow& r : io::read_target_csv(file))
        append(p, clock(r.frame, r.t), r.g_wo,
               file.string() + ": frame " + std::to_string(r.frame));
      files.push_back(std::move(p));
    }
  std::vector<TrajectoryFile> written;
  for (Pending& p : files) {
    io::write_file_atomic(out / p.file.name, p.text);
    written.push_back(std::move(p.file));
  }
  return written;
}

namespace {

// One number of a TUM line, the whole token, finite.
double tum_number(const std::string& token, const std::string& where, int field) {
  const auto v = io::parse_finite(token);
  if (!v)
    throw InputError(where + ": field " + std::to_string(field) +
                     ": expected a finite number, got '" + token + "'");
  return *v;
}

}  // namespace

std::vector<TumRow> read_tum(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open");
  std::vector<TumRow> rows;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    std::vector<std::string> tokens;
    for (std::string token; fields >> token;) tokens.push_back(token);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::string where = file.string() + ":" + std::to_string(n);
    if (tokens.size() != 8)
      throw InputError(where + ": expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got " +
                       std::to_string(tokens.size()));
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = tum_number(tokens[static_cast<size_t>(i)], where, i + 1);
    TumRow r;
    r.t = v[0];
    r.line = n;
    if (!rows.empty() && !(r.t > rows.back().t))
      throw InputError(where + ": timestamp " + tokens[0] +
                       " is not after the previous line's; a trajectory's times must increase");
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (!(std::abs(q.norm() - 1.0) <= 1e-3))
      throw InputError(where + ": quaternion (qx qy qz qw) has norm " + std::to_string(q.norm()) +
                       ", not 1");
    r.g.linear() = q.normalized().toRotationMatrix();
    r.g.translation() = obs::Vec3(v[1], v[2], v[3]);
    rows.push_back(r);
  }
  if (rows.empty()) throw InputError(file.string() + ": no pose");
  return rows;
}

TrajectoryComparison compare_trajectory(const std::vector<TumRow>& reference,
                                        const std::vector<TumRow>& estimate,
                                        const TrajectoryComparisonSettings& settings,
                                        const std::string& what) {
  // Each estimated pose with the reference pose nearest in time (the reference's times increase).
  std::vector<std::pair<const TumRow*, const TumRow*>> pairs;  // (reference, estimate)
  TrajectoryComparison c;
  // Times on the reference's clock: t_ref + reference_time_offset is on the estimate's.
  for (const TumRow& e : estimate) {
    const double t = e.t - settings.reference_time_offset;
    const auto after = std::lower_bound(reference.begin(), reference.end(), t,
                                        [](const TumRow& r, double t_r) { return r.t < t_r; });
    const TumRow* best = nullptr;
    if (after != reference.end()) best = &*after;
    if (after != reference.begin() && (!best || t - (after - 1)->t < best->t - t))
      best = &*(after - 1);
    if (best && std::abs(best->t - t) <= settings.max_dt)
      pairs.emplace_back(best, &e);
    else
      ++c.unmatched;
  }
  c.matched = pairs.size();
  if (pairs.empty())
    throw InputError(what + ": no estimated pose has a reference pose within " +
                     std::to_string(settings.max_dt) + " s" +
                     (settings.reference_time_offset != 0.0
                          ? " after the reference's times are moved by " +
                                std::to_string(settings.reference_time_offset) + " s"
                          : std::string()) +
                     " (are they on one clock? --reference-time-offset moves the reference's)");
  if (settings.align) {
    // The rigid motion A from the estimate's frame to the reference's: every matched pair says
    // R_ref = R_A R_est and p_ref = R_A p_est + t_A. R_A is the chordal L2 mean of the pairs'
    // R_ref R_est^T: the rotation nearest their sum in the Frobenius norm, U diag(1, 1, det UV^T)
    // V^T of the sum's SVD (Hartley, Trumpf, Dai and Li, "Rotation averaging", IJCV 2013);
    // t_A the mean of p_ref - R_A p_est, least squares given R_A.
    obs::Mat3 sum = obs::Mat3::Zero();
    for (const auto& [r, e] : pairs) sum += r->g.linear() * e->g.linear().transpose();
    const Eigen::JacobiSVD<obs::Mat3> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
    if (!(svd.singularValues()(1) > 1e-9 * svd.singularValues()(0)))
      throw InputError(what +
                       ": the matched orientations disagree too much for one alignment (their "
                       "chordal mean is not unique); compare without aligning");
    obs::Mat3 d = obs::Mat3::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const obs::Mat3 rot = svd.matrixU() * d * svd.matrixV().transpose();
    obs::Vec3 shift = obs::Vec3::Zero();
    for (const auto& [r, e] : pairs) shift += r->g.translation() - rot * e->g.translation();
    c.alignment.linear() = rot;
    c.alignment.translation() = shift / static_cast<double>(pairs.size());
  }
  double sum_p2 = 0.0, sum_p = 0.0, sum_r2 = 0.0, sum_r = 0.0;
  for (const auto& [r, e] : pairs) {
    // The run's own error measures against the truth (summary.json's), the angle in radians.
    const PoseError err = pose_error(c.alignment * e->g, r->g);
    const double dp = err.position, dr = err.orientation_deg * M_PI / 180.0;
    sum_p2 += dp * dp;
    sum_p += dp;
    sum_r2 += dr * dr;
    sum_r += dr;
    c.position_max = std::max(c.position_max, dp);
    c.rotation_max = std::max(c.rotation_max, dr);
  }
  const auto n = static_cast<double>(pairs.size());
  c.position_rmse = std::sqrt(sum_p2 / n);
  c.position_mean = sum_p / n;
  c.rotation_rmse = std::sqrt(sum_r2 / n);
  c.rotation_mean = sum_r / n;
  return c;
}

namespace {

// A reference cut where it has a gap: its runs of poses whose steps are at most `gap`.
struct Segment {
  std::vector<double> times;
  std::vector<obs::SE3> poses;
};
std::vector<Segment> segments(const std::vector<TumRow>& ref, double gap) {
  std::vector<Segment> out;
  for (size_t k = 0; k < ref.size(); ++k) {
    if (k == 0 || ref[k].t - ref[k - 1].t > gap) out.emplace_back();
    out.back().times.push_back(ref[k].t);
    out.back().poses.push_back(ref[k].g);
  }
  return out;
}

// The reference's pose at time t: on the segment that holds t, interpolated on the geodesic
// between the poses around it (sources::pose_at); within max_dt before a segment's first pose or
// after its last, that pose; in a gap or beyond the ends, none.
std::optional<obs::SE3> reference_at(const std::vector<Segment>& ref, double t, double max_dt) {
  const auto after =
      std::upper_bound(ref.begin(), ref.end(), t + max_dt,
                       [](double x, const Segment& s) { return x < s.times.front(); });
  if (after == ref.begin()) return std::nullopt;
  const Segment& s = *(after - 1);
  const double inside = std::clamp(t, s.times.front(), s.times.back());
  if (std::abs(inside - t) > max_dt) return std::nullopt;
  return sources::pose_at(s.times, s.poses, inside, 0.0);
}

// The target's linear [m/s] and angular [rad/s] speed from g1 to g2, dt apart: the same in any
// world frame (a rigid motion of the world changes neither |p2 - p1| nor R1^T R2).
std::pair<double, double> speeds(const obs::SE3& g1, const obs::SE3& g2, double dt) {
  return {(g2.translation() - g1.translation()).norm() / dt,
          obs::log_so3(g1.linear().transpose() * g2.linear()).norm() / dt};
}

double median_of(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The estimates' pose noise, a variance per axis of the position [m^2] and of the rotation
// [rad^2]. Over every 5 consecutive poses of a camera (no step over 3 times `h`), a quadratic in
// time is fitted to each position axis and to each component of the rotation vectors from the
// middle pose, log(R_mid^T R_k). For white noise of variance s^2 per axis the residuals' sum over
// the three axes is s^2 times a chi-square of 3 x (5 - 3) = 6 degrees of freedom, whose median is
// 5.348; the median over the windows (a start-up transient is no noise) over 5.348. Noise
// correlated over the window (a filter's) is read as motion and left out. Fewer than 5 windows:
// none.
std::pair<double, double> pose_noise(const std::vector<const std::vector<TumRow>*>& estimates,
                                     double h) {
  constexpr int kWindow = 5;
  constexpr double kChiSquare6Median = 5.348;
  std::vector<double> rss_p, rss_r;
  for (const auto* e : estimates)
    for (size_t k = 0; k + kWindow <= e->size(); ++k) {
      const TumRow* w = e->data() + k;
      bool gap = false;
      for (int i = 1; i < kWindow; ++i) gap = gap || w[i].t - w[i - 1].t > 3.0 * h;
      if (gap) continue;
      Eigen::Matrix<double, kWindow, 3> a;
      Eigen::Matrix<double, kWindow, 3> p, r;
      const TumRow& mid = w[kWindow / 2];
      for (int i = 0; i < kWindow; ++i) {
        const double t = w[i].t - mid.t;
        a.row(i) << 1.0, t, t * t;
        p.row(i) = w[i].g.translation().transpose();
        r.row(i) = obs::log_so3(mid.g.linear().transpose() * w[i].g.linear()).transpose();
      }
      const auto qr = a.colPivHouseholderQr();
      const double sp = (p - a * qr.solve(p)).squaredNorm(),
                   sr = (r - a * qr.solve(r)).squaredNorm();
      if (!std::isfinite(sp) || !std::isfinite(sr)) continue;  // times or poses beyond doubles
      rss_p.push_back(sp);
      rss_r.push_back(sr);
    }
  if (rss_p.size() < 5) return {0.0, 0.0};
  return {median_of(rss_p) / kChiSquare6Median, median_of(rss_r) / kChiSquare6Median};
}

std::string seconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g s", s);
  return b;
}

}  // namespace

TimeOffsetEstimate estimate_time_offset(const std::vector<TumRow>& reference,
                                        const std::vector<const std::vector<TumRow>*>& estimates,
                                        double max_dt, const TimeOffsetSettings& settings,
                                        const std::string& what) {
  // The estimates' pose pairs `baseline` apart (each pose with the first at least that much
  // after it) and their speeds; a gap over 3 median steps beyond the baseline (a camera without
  // an estimate for a while) is no pair.
  struct Pair {
    double t1, t2, v, w;
  };
  std::vector<Pair> pairs;
  std::vector<double> steps;
  for (const auto* e : estimates)
    for (size_t k = 1; k < e->size(); ++k) steps.push_back((*e)[k].t - (*e)[k - 1].t);
  if (steps.empty() || reference.size() < 2)
    throw InputError(what + ": too few poses to estimate a time offset");
  const double h = median_of(steps);
  // Noise n of variance s^2 per axis on both poses of a pair raises its squared displacement by
  // 6 s^2 on average (|d + n|^2, n = n2 - n1 over three axes), so a slow target's speeds look
  // higher than they are; that bias is taken off the squares.
  const auto [noise_p, noise_r] = pose_noise(estimates, h);
  for (const auto* e : estimates)
    for (size_t k = 0, j = 1; k < e->size(); ++k) {
      const TumRow& a = (*e)[k];
      j = std::max(j, k + 1);
      while (j < e->size() && (*e)[j].t - a.t < settings.baseline) ++j;
      if (j == e->size()) break;
      const TumRow& b = (*e)[j];
      if (b.t - a.t > settings.baseline + 3.0 * h) continue;
      const double dt = b.t - a.t;
      const auto [v, w] = speeds(a.g, b.g, dt);
      const double v2 = v * v - 6.0 * noise_p / (dt * dt), w2 = w * w - 6.0 * noise_r / (dt * dt);
      pairs.push_back({a.t, b.t, std::sqrt(std::max(0.0, v2)), std::sqrt(std::max(0.0, w2))});
    }
  if (pairs.empty())
    throw InputError(what + ": no two poses of a camera lie " + seconds(settings.baseline) +
                     " apart without a gap");
  // The reference is interpolated across its usual step, not across a gap in it (3 steps).
  std::vector<double> ref_steps;
  for (size_t k = 1; k < reference.size(); ++k)
    ref_steps.push_back(reference[k].t - reference[k - 1].t);
  const auto runs = segments(reference, 3.0 * median_of(ref_steps));
  // The reference's own speed spread, over its span at the baseline (or the estimates' step).
  const double span = std::max(settings.baseline, h);
  double sv = 0.0, sw = 0.0, mv = 0.0, mw = 0.0;
  size_t n = 0;
  // (At most 100,000 samples of it, whatever its length.)
  const double stride = std::max(span, (reference.back().t - reference.front().t) / 1e5);
  for (double t = reference.front().t; t + span <= reference.back().t; t += stride) {
    const auto g1 = reference_at(runs, t, max_dt), g2 = reference_at(runs, t + span, max_dt);
    if (!g1 || !g2) continue;
    const auto [v, w] = speeds(*g1, *g2, span);
    ++n;  // Welford's running mean and sum of squares
    const double dv = v - mv, dw = w - mw;
    mv += dv / static_cast<double>(n);
    mw += dw / static_cast<double>(n);
    sv += dv * (v - mv);
    sw += dw * (w - mw);
  }
  sv = n > 1 ? std::sqrt(sv / static_cast<double>(n - 1)) : 0.0;
  sw = n > 1 ? std::sqrt(sw / static_cast<double>(n - 1)) : 0.0;
  // A speed that varies by less than a thousandth of its mean is taken as constant (a
  // reference's interpolation alone varies a constant speed by about a millionth).
  const bool use_v = sv > 1e-3 * mv, use_w = sw > 1e-3 * mw;
  if (!use_v && !use_w)
    throw InputError(what + ": the reference's speed does not change (a target that stands " +
                     "still or moves at one speed), so it does not determine a time offset; " +
                     "give --reference-time-offset");
  const double step = settings.step > 0.0 ? settings.step : h / 4.0;
  constexpr double kMaxOffsets = 1e5;
  if (!(settings.search / step <= kMaxOffsets / 2))
    throw InputError(what + ": a search within " + seconds(settings.search) + " every " +
                     seconds(step) + " (a quarter of the estimates' median step) would try more " +
                     "than 100000 offsets; search a narrower window");
  const int half = static_cast<int>(std::floor(settings.search / step));
  std::vector<double> mismatch(static_cast<size_t>(2 * half + 1),
                               std::numeric_limits<double>::quiet_NaN());
  std::vector<size_t> used(mismatch.size(), 0);
  const auto need = static_cast<size_t>(std::ceil(settings.min_overlap * pairs.size()));
  for (int i = -half; i <= half; ++i) {
    const double tau = settings.centre + i * step;
    double sum = 0.0;
    size_t m = 0;
    for (const Pair& p : pairs) {
      const auto g1 = reference_at(runs, p.t1 - tau, max_dt),
                 g2 = reference_at(runs, p.t2 - tau, max_dt);
      if (!g1 || !g2) continue;
      const auto [v, w] = speeds(*g1, *g2, p.t2 - p.t1);
      // Each speed's squared difference in units of the reference's spread, at most 9 (three
      // spreads: a camera's start-up transient is no motion of the reference's).
      if (use_v) sum += std::min(9.0, std::pow((p.v - v) / sv, 2));
      if (use_w) sum += std::min(9.0, std::pow((p.w - w) / sw, 2));
      ++m;
    }
    const auto at = static_cast<size_t>(i + half);
    used[at] = m;
    if (m > 2 && m >= need) mismatch[at] = sum / static_cast<double>(m);
  }
  std::vector<double> judged;
  size_t best = mismatch.size();
  for (size_t i = 0; i < mismatch.size(); ++i) {
    if (std::isnan(mismatch[i])) continue;
    judged.push_back(mismatch[i]);
    if (best == mismatch.size() || mismatch[i] < mismatch[best]) best = i;
  }
  const std::string window =
      "within " + seconds(settings.search) + " of " + seconds(settings.centre);
  if (judged.size() < 3)
    throw InputError(what + ": the reference covers too few of the offsets " + window +
                     " (at least " + std::to_string(static_cast<int>(100 * settings.min_overlap)) +
                     " % of the estimates' poses at each; are they on clocks this far apart?)");
  TimeOffsetEstimate r;
  r.position_noise = std::sqrt(noise_p);
  r.rotation_noise = std::sqrt(noise_r);
  r.offsets = judged.size();
  r.median_mismatch = median_of(judged);
  r.mismatch = mismatch[best];
  r.pairs = used[best];
  r.offset = settings.centre + (static_cast<double>(best) - half) * step;
  const bool left = best == 0 || std::isnan(mismatch[best - 1]),
             right = best + 1 == mismatch.size() || std::isnan(mismatch[best + 1]);
  if (left || right)
    throw InputError(what + ": the speeds match best at " + seconds(r.offset) +
                     ", the edge of the offsets tried " + window +
                     " (widen the search, or centre it with --reference-time-offset)");
  char ratio[64];
  std::snprintf(ratio, sizeof ratio, "%.2f", r.mismatch / r.median_mismatch);
  if (!(r.mismatch <= settings.max_contrast * r.median_mismatch))
    throw InputError(what + ": the speeds do not determine a time offset " + window +
                     ": their mismatch at the best, " + seconds(r.offset) + ", is " + ratio +
                     " of its median over the offsets tried (a target that barely moves, or at "
                     "one speed); give --reference-time-offset");
  // A parabola through the best offset and its two neighbours.
  const double m0 = mismatch[best - 1], m1 = mismatch[best], m2 = mismatch[best + 1];
  const double curve = m0 - 2.0 * m1 + m2;
  if (curve > 0.0) r.offset += std::clamp(0.5 * (m0 - m2) / curve, -0.5, 0.5) * step;
  return r;
}

Comparisons write_comparisons(const fs::path& out, const std::vector<TrajectoryFile>& files,
                              const std::optional<fs::path>& reference,
                              TrajectoryComparisonSettings settings,
                              const std::optional<TimeOffsetSettings>& estimate_offset) {
  std::map<int, const TrajectoryFile*> truth_of;  // by target
  for (const TrajectoryFile& f : files)
    if (f.camera < 0) truth_of[f.target] = &f;
  std::set<int> targets;
  for (const TrajectoryFile& f : files) targets.insert(f.target);
  if (reference && targets.size() > 1)
    throw InputError(reference->string() +
                     ": a reference is compared with the results of one target; these have "
                     "several (compare each target's files with their truth, --dataset)");
  if (estimate_offset && !reference)
    throw InputError(
        "a time offset is estimated for a reference alone (the dataset's truth is "
        "on the results' clock)");
  std::vector<TumRow> given;
  if (reference) given = read_tum(*reference);
  Comparisons done;
  const double centre = settings.reference_time_offset;
  if (estimate_offset) {
    std::vector<const std::vector<TumRow>*> cameras;
    for (const TrajectoryFile& f : files)
      if (f.camera >= 0) cameras.push_back(&f.rows);
    if (cameras.empty()) return done;
    TimeOffsetSettings s = *estimate_offset;
    s.centre = centre;
    done.time_offset = estimate_time_offset(given, cameras, settings.max_dt, s,
                                            reference->string() + " against the cameras' files");
    settings.reference_time_offset = done.time_offset->offset;
  }
  for (const TrajectoryFile& f : files) {
    if (f.camera < 0) continue;
    const auto truth = truth_of.find(f.target);
    if (!reference && truth == truth_of.end()) continue;
    CameraComparison row{
        f.name, f.target, f.camera, reference ? reference->string() : truth->second->name, {}};
    row.comparison = compare_trajectory(
        reference ? given : truth->second->rows, f.rows, settings,
        "camera " + std::to_string(f.camera) + " (" + f.name + ") against " + row.reference);
    done.cameras.push_back(std::move(row));
  }
  if (done.cameras.empty()) return done;
  nlohmann::json j;
  j["max_dt_s"] = settings.max_dt;
  j["reference_time_offset_s"] = settings.reference_time_offset;
  j["aligned"] = settings.align;
  if (done.time_offset) {
    const TimeOffsetEstimate& e = *done.time_offset;
    j["reference_time_offset_estimated"] = {{"searched_s", estimate_offset->search},
                                            {"centre_s", centre},
                                            {"offsets_tried", e.offsets},
                                            {"pairs", e.pairs},
                                            {"mismatch", e.mismatch},
                                            {"median_mismatch", e.median_mismatch},
                                            {"position_noise_m", e.position_noise},
                                            {"rotation_noise_deg", e.rotation_noise * 180 / M_PI}};
  } else {
    j["reference_time_offset_estimated"] = nullptr;
  }
  j["cameras"] = nlohmann::json::array();
  constexpr double deg = 180.0 / M_PI;
  for (const CameraComparison& r : done.cameras) {
    const TrajectoryComparison& c = r.comparison;
    const obs::Vec3 p = c.alignment.translation(), w = obs::rotvec(c.alignment);
    j["cameras"].push_back(
        {{"file", r.file},
         {"camera", r.camera},
         {"target", r.target < 0 ? nlohmann::json(nullptr) : nlohmann::json(r.target)},
         {"reference", r.reference},
         {"matched", c.matched},
         {"unmatched", c.unmatched},
         {"position_rmse_m", c.position_rmse},
         {"position_mean_m", c.position_mean},
         {"position_max_m", c.position_max},
         {"rotation_rmse_deg", c.rotation_rmse * deg},
         {"rotation_mean_deg", c.rotation_mean * deg},
         {"rotation_max_deg", c.rotation_max * deg},
         {"alignment",
          {{"translation_m", {p.x(), p.y(), p.z()}},
           {"rotation_vector_rad", {w.x(), w.y(), w.z()}}}}});
  }
  io::write_file_atomic(out / "comparison.json", j.dump(2) + "\n");
  return done;
}

}  // namespace netvmo::run
