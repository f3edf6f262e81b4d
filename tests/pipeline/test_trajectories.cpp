// netvmo trajectories: a result folder's estimates.csv and a dataset's target.csv as TUM
// trajectory files (run/trajectories.hpp), checked against the poses they were written from.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/run/trajectories.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace netvmo::run {
namespace {

struct TumPose {
  double t = 0.0;
  obs::Vec3 p = obs::Vec3::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // as written, not normalised
};

// A TUM file's lines; each must hold exactly eight numbers.
std::vector<TumPose> parse_tum(const fs::path& file) {
  std::vector<TumPose> out;
  std::ifstream in(file);
  EXPECT_TRUE(in.good()) << file;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    TumPose r;
    double qx = 0, qy = 0, qz = 0, qw = 0;
    s >> r.t >> r.p.x() >> r.p.y() >> r.p.z() >> qx >> qy >> qz >> qw;
    EXPECT_FALSE(s.fail()) << file << ": " << line;
    std::string rest;
    s >> rest;
    EXPECT_TRUE(rest.empty()) << file << ": more than eight fields: " << line;
    r.q = Eigen::Quaterniond(qw, qx, qy, qz);
    out.push_back(r);
  }
  return out;
}

double angle_between(const obs::Mat3& a, const obs::Mat3& b) {
  return obs::log_so3(a.transpose() * b).norm();
}

// The pose a line gives against the pose it was written from.
void expect_pose(const TumPose& got, double t, const obs::SE3& want) {
  EXPECT_NEAR(got.t, t, 5e-7);
  EXPECT_LT((got.p - want.translation()).norm(), 1e-8);
  EXPECT_NEAR(got.q.norm(), 1.0, 1e-8);
  EXPECT_GE(got.q.w(), 0.0);
  EXPECT_LT(angle_between(got.q.normalized().toRotationMatrix(), want.linear()), 1e-8);
}

// Rotation by theta about the unit axis u is the quaternion (u sin(theta/2), cos(theta/2)): the
// closed form, for angles up to pi, where the written sign (qw >= 0) matters.
TEST(Trajectories, TumLineIsTheClosedFormQuaternion) {
  const std::vector<obs::Vec3> axes = {obs::Vec3::UnitX(), obs::Vec3::UnitY(), obs::Vec3::UnitZ(),
                                       obs::Vec3(1, -2, 0.5).normalized()};
  for (const obs::Vec3& u : axes)
    for (const double theta : {0.0, 0.3, 1.5, 3.0, M_PI - 1e-6}) {
      const obs::Vec3 p(0.25, -1.5, 2.0);
      const std::string line = tum_line(12.5, obs::make_pose(p, u * theta));
      std::istringstream s(line);
      double t, x, y, z, qx, qy, qz, qw;
      s >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
      ASSERT_FALSE(s.fail()) << line;
      EXPECT_DOUBLE_EQ(t, 12.5);
      EXPECT_NEAR(x, p.x(), 1e-9);
      EXPECT_NEAR(y, p.y(), 1e-9);
      EXPECT_NEAR(z, p.z(), 1e-9);
      const double sh = std::sin(theta / 2), ch = std::cos(theta / 2);
      EXPECT_NEAR(qx, u.x() * sh, 2e-9) << line;
      EXPECT_NEAR(qy, u.y() * sh, 2e-9) << line;
      EXPECT_NEAR(qz, u.z() * sh, 2e-9) << line;
      EXPECT_NEAR(qw, ch, 2e-9) << line;
    }
  // Past pi the rotation vector's quaternion has qw < 0; the line gives its negative, qw >= 0.
  const std::string line = tum_line(0.0, obs::make_pose(obs::Vec3::Zero(), {0, 0, 4.0}));
  std::istringstream s(line);
  double t, x, y, z, qx, qy, qz, qw;
  s >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
  EXPECT_NEAR(qz, -std::sin(2.0), 1e-9) << line;
  EXPECT_NEAR(qw, -std::cos(2.0), 1e-9) << line;
}

struct Fixture {
  fs::path dir, results, dataset, out;
  std::map<int, std::vector<std::pair<double, obs::SE3>>> estimates;  // by camera
  std::vector<std::pair<double, obs::SE3>> truth;
};

obs::SE3 pose_at(int k, int camera) {
  return obs::make_pose(obs::Vec3(0.1 * k, -0.02 * camera, 1.0 + 0.01 * k),
                        obs::Vec3(0.2 + 0.1 * k, -0.3 * camera, 0.05 * k));
}

// One target, three cameras over four frames at 30 fps: camera 1 has an estimate from frame 0,
// camera 2 from frame 2 (rows before with an empty pose), camera 3 never; the dataset's truth
// for every frame.
Fixture one_target(const std::string& name) {
  Fixture f;
  f.dir = test::scratch_dir("trajectories_" + name);
  f.results = f.dir / "results";
  f.dataset = f.dir / "dataset";
  f.out = f.dir / "out";
  for (const auto& d : {f.results, f.dataset, f.out}) fs::create_directories(d);
  std::ofstream est(f.results / "estimates.csv");
  est.precision(17);
  est << io::kEstimatesHeader << "\n";
  std::ofstream target(f.dataset / "target.csv");
  target << io::kTargetHeader << "\n";
  for (int k = 0; k < 4; ++k) {
    const double t = k / 30.0;
    for (int c = 1; c <= 3; ++c) {
      est << k << ',' << t << ',' << c << ",1";
      if ((c == 1) || (c == 2 && k >= 2)) {
        const obs::SE3 g = pose_at(k, c);
        const obs::Vec3 p = g.translation(), w = obs::rotvec(g);
        est << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << w.x() << ',' << w.y() << ','
            << w.z();
        f.estimates[c].emplace_back(t, g);
      } else {
        est << ",,,,,,";
      }
      est << "\n";
    }
    const obs::SE3 g_wo = pose_at(k, 0);
    target << io::format_target_row(k, t, g_wo) << "\n";
    f.truth.emplace_back(t, g_wo);
  }
  return f;
}

TEST(Trajectories, EveryCameraWithAnEstimateAndTheTruthReadBack) {
  Fixture f = one_target("one");
  const auto files = write_trajectories(f.results, f.dataset, f.out);
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].name, "cam_1.txt");
  EXPECT_EQ(files[1].name, "cam_2.txt");
  EXPECT_EQ(files[2].name, "truth.txt");
  EXPECT_FALSE(fs::exists(f.out / "cam_3.txt")) << "camera 3 never had an estimate";
  for (int c : {1, 2}) {
    const auto got = parse_tum(f.out / ("cam_" + std::to_string(c) + ".txt"));
    ASSERT_EQ(got.size(), f.estimates[c].size()) << "camera " << c;
    EXPECT_EQ(files[static_cast<size_t>(c - 1)].rows.size(), got.size());
    for (size_t k = 0; k < got.size(); ++k)
      expect_pose(got[k], f.estimates[c][k].first, f.estimates[c][k].second);
  }
  // target.csv keeps 9 digits: the truth read back to that.
  const auto truth = parse_tum(f.out / "truth.txt");
  ASSERT_EQ(truth.size(), f.truth.size());
  const auto rows = io::read_target_csv(f.dataset / "target.csv");
  for (size_t k = 0; k < truth.size(); ++k) {
    expect_pose(truth[k], rows[k].t, rows[k].g_wo);
    EXPECT_LT((rows[k].g_wo.translation() - f.truth[k].second.translation()).norm(), 1e-8);
  }
  // Results whose files count time from a later dataset time (summary.json's time_origin_s, as
  // a merge of cameras on their own clocks writes): the truth on that clock.
  test::write_text(f.results / "summary.json", "{\"time_origin_s\": 0.05, \"fps\": 30}\n");
  fs::remove_all(f.out);
  fs::create_directories(f.out);
  write_trajectories(f.results, f.dataset, f.out);
  const auto shifted = parse_tum(f.out / "truth.txt");
  ASSERT_EQ(shifted.size(), rows.size());
  for (size_t k = 0; k < rows.size(); ++k) expect_pose(shifted[k], rows[k].t - 0.05, rows[k].g_wo);
  // Results on one clock (time_origin_s null): t = frame / fps, whatever times the dataset lists
  // (here 10 s later than that).
  test::write_text(f.results / "summary.json", "{\"time_origin_s\": null, \"fps\": 30}\n");
  std::string later = std::string(io::kTargetHeader) + "\n";
  for (const auto& r : rows) later += io::format_target_row(r.frame, r.t + 10.0, r.g_wo) + "\n";
  test::write_text(f.dataset / "target.csv", later);
  fs::remove_all(f.out);
  fs::create_directories(f.out);
  write_trajectories(f.results, f.dataset, f.out);
  const auto by_frame = parse_tum(f.out / "truth.txt");
  ASSERT_EQ(by_frame.size(), rows.size());
  for (size_t k = 0; k < rows.size(); ++k)
    expect_pose(by_frame[k], rows[k].frame / 30.0, rows[k].g_wo);
  // Without a dataset, no truth.
  fs::remove_all(f.out);
  fs::create_directories(f.out);
  EXPECT_EQ(write_trajectories(f.results, std::nullopt, f.out).size(), 2u);
  EXPECT_FALSE(fs::exists(f.out / "truth.txt"));
}

// Several targets: the target column names the files; a later target's truth is
// target_<id>.csv, used where the dataset has it.
TEST(Trajectories, SeveralTargetsEachTheirOwnFiles) {
  const auto dir = test::scratch_dir("trajectories_targets");
  fs::create_directories(dir / "results");
  fs::create_directories(dir / "dataset");
  fs::create_directories(dir / "out");
  std::ofstream est(dir / "results" / "estimates.csv");
  est << io::kEstimatesTargetsHeader << "\n";
  std::ofstream t0(dir / "dataset" / "target.csv"), t7(dir / "dataset" / "target_7.csv");
  t0 << io::kTargetHeader << "\n";
  t7 << io::kTargetHeader << "\n";
  for (const int target : {3, 7})
    for (int k = 0; k < 3; ++k) {
      const obs::SE3 g = pose_at(k, target);
      const obs::Vec3 p = g.translation(), w = obs::rotvec(g);
      est << k << ',' << k * 0.1 << ',' << target << ",1,1," << p.x() << ',' << p.y() << ','
          << p.z() << ',' << w.x() << ',' << w.y() << ',' << w.z() << "\n";
      (target == 3 ? t0 : t7) << io::format_target_row(k, k * 0.1, pose_at(k, 10 + target)) << "\n";
    }
  est.close();
  t0.close();
  t7.close();
  const auto files = write_trajectories(dir / "results", dir / "dataset", dir / "out");
  std::vector<std::string> names;
  for (const auto& f : files) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"target_3_cam_1.txt", "target_7_cam_1.txt",
                                             "target_3_truth.txt", "target_7_truth.txt"}));
  const auto truth7 = parse_tum(dir / "out" / "target_7_truth.txt");
  const auto cam7 = parse_tum(dir / "out" / "target_7_cam_1.txt");
  ASSERT_EQ(truth7.size(), 3u);
  ASSERT_EQ(cam7.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT((truth7[static_cast<size_t>(k)].p - pose_at(k, 17).translation()).norm(), 1e-8);
    EXPECT_LT((cam7[static_cast<size_t>(k)].p - pose_at(k, 7).translation()).norm(), 1e-5);
  }
  // Each target's cameras compared with that target's truth; one reference for several targets
  // is refused.
  const auto compared = write_comparisons(dir / "out", files, std::nullopt, {}).cameras;
  ASSERT_EQ(compared.size(), 2u);
  EXPECT_EQ(compared[1].reference, "target_7_truth.txt");
  EXPECT_EQ(compared[1].comparison.matched, 3u);
  double worst = 0.0;
  for (int k = 0; k < 3; ++k)
    worst = std::max(worst, (pose_at(k, 17).translation() - pose_at(k, 7).translation()).norm());
  EXPECT_NEAR(compared[1].comparison.position_max, worst, 1e-5);
  EXPECT_TRUE(fs::exists(dir / "out" / "comparison.json"));
  test::expect_input_error(
      [&] { write_comparisons(dir / "out", files, dir / "out" / "target_3_truth.txt", {}); },
      {"target_3_truth.txt", "several"});
  // Without target_7.csv: that target's truth is not known, the first's still written.
  fs::remove(dir / "dataset" / "target_7.csv");
  fs::remove_all(dir / "out");
  fs::create_directories(dir / "out");
  const auto without = write_trajectories(dir / "results", dir / "dataset", dir / "out");
  EXPECT_EQ(without.size(), 3u);
  EXPECT_FALSE(fs::exists(dir / "out" / "target_7_truth.txt"));
  EXPECT_EQ(write_comparisons(dir / "out", without, std::nullopt, {}).cameras.size(), 1u);
}

// Bad input: one line naming the file, line and column, and no file written.
TEST(Trajectories, BadInputNamesFileLineAndColumnAndWritesNothing) {
  const Fixture f = one_target("bad");
  const fs::path est = f.results / "estimates.csv";
  const std::string good = test::slurp(est);
  const auto expect_error = [&](const std::string& text, std::initializer_list<std::string> n) {
    test::write_text(est, text);
    test::expect_input_error([&] { write_trajectories(f.results, f.dataset, f.out); }, n);
    EXPECT_TRUE(fs::is_empty(f.out)) << "a file was written before the error";
  };
  expect_error("frame,t,cam,delta,px,py,pz,rx,ry,rz\n",
               {est.string() + ":1:", "unexpected header"});
  expect_error(test::replaced(good, "\n1,0.033", "\n1,0.03x"), {est.string() + ":5:", "t:"});
  expect_error(test::replaced(good, "\n0,0,2,1,,,", "\n0,0,2,1,0.5,,"),
               {est.string() + ":3:", "py:", "all six"});
  expect_error(test::replaced(good, "\n0,0,3,", "\n0,0,0,"), {est.string() + ":4:", "camera:"});
  // Frame 1's row of camera 1 at frame 0's time: camera 1's times do not increase.
  std::ostringstream t1;
  t1.precision(17);
  t1 << 1 / 30.0;
  expect_error(test::replaced(good, "\n1," + t1.str() + ",1,", "\n1,0,1,"),
               {est.string() + ":5:", "t:", "not after", ":2)"});
  expect_error(std::string(io::kEstimatesHeader) + "\n", {est.string(), "no rows"});
  // The truth: a bad target.csv is named too.
  test::write_text(est, good);
  const fs::path target = f.dataset / "target.csv";
  test::write_text(target, test::replaced(test::slurp(target), "\n2,", "\n2x,"));
  test::expect_input_error([&] { write_trajectories(f.results, f.dataset, f.out); },
                           {target.string() + ":4:", "frame:"});
  EXPECT_TRUE(fs::is_empty(f.out));
  test::write_text(target, test::replaced(test::slurp(target), "\n2x,", "\n2,"));
  const fs::path summary = f.results / "summary.json";
  test::write_text(summary, "{\"time_origin_s\": \"soon\"}");
  test::expect_input_error([&] { write_trajectories(f.results, f.dataset, f.out); },
                           {summary.string(), "time_origin_s", "soon"});
  test::write_text(summary, "{\"time_origin_s\": null}");
  test::expect_input_error([&] { write_trajectories(f.results, f.dataset, f.out); },
                           {summary.string(), "fps:"});
  test::write_text(summary, "{\"time_origin_s\": ");
  test::expect_input_error([&] { write_trajectories(f.results, f.dataset, f.out); },
                           {summary.string(), "not a JSON object"});
  EXPECT_TRUE(fs::is_empty(f.out));
  fs::remove(est);
  test::expect_input_error([&] { write_trajectories(f.results, f.dataset, f.out); },
                           {est.string(), "cannot open"});
}

// A TUM file as other tools write it: comments, blank lines and commas; its poses with the
// quaternion normalised. Each malformed line is named with its file and line number.
TEST(Trajectories, ReadTumSkipsCommentsAndNamesEveryBadLine) {
  const auto dir = test::scratch_dir("trajectories_read_tum");
  const fs::path file = dir / "ref.txt";
  const double h = std::sqrt(0.5);
  test::write_text(file,
                   "# timestamp tx ty tz qx qy qz qw\n\n"
                   "1.5 0.1 0.2 0.3 0 0 0 1\n"
                   "  2.0,1,2,3,0," +
                       std::to_string(h) + ",0," + std::to_string(h) +
                       "\n"
                       "2.25\t1 2 3 0 0 0 1.0005\n");
  const auto rows = read_tum(file);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].line, 3);
  EXPECT_EQ(rows[1].line, 4);
  EXPECT_DOUBLE_EQ(rows[1].t, 2.0);
  EXPECT_LT((rows[1].g.translation() - obs::Vec3(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT(angle_between(rows[1].g.linear(),
                          Eigen::AngleAxisd(M_PI / 2, obs::Vec3::UnitY()).toRotationMatrix()),
            1e-6);
  EXPECT_LT((rows[2].g.linear() - obs::Mat3::Identity()).norm(), 1e-12) << "normalised";
  const auto expect_error = [&](const std::string& line, std::initializer_list<std::string> n) {
    test::write_text(file, "1 0 0 0 0 0 0 1\n" + line + "\n");
    test::expect_input_error([&] { read_tum(file); }, n);
  };
  expect_error("2 0 0 0 0 0 1", {file.string() + ":2:", "expected 8 numbers", "got 7"});
  expect_error("2 0 0 0 0 0 0 1 5", {file.string() + ":2:", "got 9"});
  expect_error("2 0 0x 0 0 0 0 1", {file.string() + ":2:", "field 3", "'0x'"});
  expect_error("2 0 0 nan 0 0 0 1", {file.string() + ":2:", "field 4", "finite"});
  expect_error("1 0 0 0 0 0 0 1", {file.string() + ":2:", "not after"});
  expect_error("2 0 0 0 0 0 0 0.5", {file.string() + ":2:", "norm 0.5"});
  test::write_text(file, "# nothing\n");
  test::expect_input_error([&] { read_tum(file); }, {file.string(), "no pose"});
  test::expect_input_error([&] { read_tum(dir / "none.txt"); },
                           {(dir / "none.txt").string(), "cannot open"});
}

// compare_trajectory against closed forms, on a helix (radius 1, rising 0.3 m/s, turning) at
// 100 Hz and an estimate at 30 Hz, 2 ms after the reference's poses:
// - the estimate displaced by d: every position error |d|, no rotation error;
// - the estimate rotated by theta about the world z axis: every rotation error theta (a
//   conjugate has the same angle) and every position error 2 sin(theta/2) (the helix's radius
//   is 1);
// - aligned, the rigid motion is found (its inverse) and the errors vanish, also for a target
//   that stays at one point.
TEST(Trajectories, ComparisonIsTheClosedFormAndTheAlignmentUndoesARigidMotion) {
  std::vector<TumRow> reference;
  for (int j = 0; j <= 300; ++j) {
    const double t = j / 100.0;
    TumRow r;
    r.t = t;
    r.g = obs::make_pose(obs::Vec3(std::cos(t), std::sin(t), 0.3 * t), obs::Vec3(0.2, -0.1, t));
    reference.push_back(r);
  }
  const auto estimate_of = [&](const obs::SE3& motion) {
    std::vector<TumRow> e;
    for (int j = 0; j <= 300; j += 3) {  // every third: 33.3 Hz
      TumRow r = reference[static_cast<size_t>(j)];
      r.t += 0.002;
      r.g = motion * r.g;
      e.push_back(r);
    }
    return e;
  };
  TrajectoryComparisonSettings plain;
  const obs::Vec3 d(0.03, -0.04, 0.12);  // |d| = 0.13
  const auto shifted = compare_trajectory(
      reference, estimate_of(obs::make_pose(d, obs::Vec3::Zero())), plain, "shifted");
  EXPECT_EQ(shifted.matched, 101u);
  EXPECT_EQ(shifted.unmatched, 0u);
  EXPECT_NEAR(shifted.position_rmse, 0.13, 1e-12);
  EXPECT_NEAR(shifted.position_mean, 0.13, 1e-12);
  EXPECT_NEAR(shifted.position_max, 0.13, 1e-12);
  EXPECT_LT(shifted.rotation_max, 1e-7);
  const double theta = 0.25;
  const obs::SE3 turn = obs::make_pose(obs::Vec3::Zero(), obs::Vec3(0, 0, theta));
  const auto turned = compare_trajectory(reference, estimate_of(turn), plain, "turned");
  EXPECT_NEAR(turned.position_rmse, 2 * std::sin(theta / 2), 1e-12);
  EXPECT_NEAR(turned.position_max, 2 * std::sin(theta / 2), 1e-12);
  EXPECT_NEAR(turned.rotation_rmse, theta, 1e-9);
  EXPECT_NEAR(turned.rotation_mean, theta, 1e-9);
  EXPECT_NEAR(turned.rotation_max, theta, 1e-9);

  TrajectoryComparisonSettings aligned;
  aligned.align = true;
  const obs::SE3 motion = obs::make_pose(obs::Vec3(1.5, -2.0, 0.7), obs::Vec3(0.3, -0.5, 1.1));
  const auto undone = compare_trajectory(reference, estimate_of(motion), aligned, "moved");
  EXPECT_LT((undone.alignment * motion).translation().norm(), 1e-9);
  EXPECT_LT(obs::rotvec(undone.alignment * motion).norm(), 1e-9);
  EXPECT_LT(undone.position_max, 1e-9);
  EXPECT_LT(undone.rotation_max, 1e-8);
  // Aligned, a displacement is undone too; unaligned (the same motion), it is all error.
  EXPECT_LT(compare_trajectory(reference, estimate_of(obs::make_pose(d, obs::Vec3::Zero())),
                               aligned, "shifted")
                .position_max,
            1e-9);
  EXPECT_GT(compare_trajectory(reference, estimate_of(motion), plain, "moved").position_rmse, 1.0);

  // Matching in time: a pose past the reference's end is left out; none within max_dt is an
  // error, as are an alignment from fewer than 3 poses and from positions on one line.
  auto late = estimate_of(obs::SE3::Identity());
  TumRow past = late.back();
  past.t = 3.5;
  late.push_back(past);
  const auto with_late = compare_trajectory(reference, late, plain, "late");
  EXPECT_EQ(with_late.matched, 101u);
  EXPECT_EQ(with_late.unmatched, 1u);
  TrajectoryComparisonSettings tight;
  tight.max_dt = 0.001;
  test::expect_input_error([&] { compare_trajectory(reference, late, tight, "the pair"); },
                           {"the pair", "no estimated pose", "0.001"});
  // A reference on another clock (100 s ahead): nothing matches until its times are moved back,
  // then every pose matches its own as before. Moved by 10 ms less, every estimated pose but the
  // first (2 ms after its own) is nearer the reference pose before its own, one step of the
  // helix back.
  std::vector<TumRow> ahead = reference;
  for (auto& r : ahead) r.t += 100.0;
  const auto displaced = estimate_of(obs::make_pose(d, obs::Vec3::Zero()));
  test::expect_input_error([&] { compare_trajectory(ahead, displaced, plain, "the pair"); },
                           {"the pair", "no estimated pose", "--reference-time-offset"});
  TrajectoryComparisonSettings back = plain;
  back.reference_time_offset = -100.0;
  const auto moved_back = compare_trajectory(ahead, displaced, back, "moved back");
  EXPECT_EQ(moved_back.matched, 101u);
  EXPECT_EQ(moved_back.unmatched, 0u);
  EXPECT_NEAR(moved_back.position_rmse, 0.13, 1e-12);
  EXPECT_LT(moved_back.rotation_max, 1e-7);
  back.reference_time_offset = -100.0 + 0.01;
  const auto one_back = compare_trajectory(ahead, displaced, back, "one back");
  EXPECT_EQ(one_back.matched, 101u);  // the first with its own, the only one within 10 ms
  EXPECT_EQ(one_back.unmatched, 0u);
  // The figures of the pairs (reference pose j - 1, estimate j), and (0, 0), computed here pair
  // by pair.
  double sum_p2 = 0.0, rot_max = 0.0;
  for (int j = 0; j <= 300; j += 3) {
    const obs::SE3& r = reference[static_cast<size_t>(std::max(j - 1, 0))].g;
    const obs::SE3& e = reference[static_cast<size_t>(j)].g;
    sum_p2 += (r.translation() - (e.translation() + d)).squaredNorm();
    rot_max = std::max(rot_max, obs::log_so3(r.linear().transpose() * e.linear()).norm());
  }
  EXPECT_NEAR(one_back.position_rmse, std::sqrt(sum_p2 / 101.0), 1e-12);
  EXPECT_NEAR(one_back.rotation_max, rot_max, 1e-12);
  EXPECT_GT(one_back.rotation_max, 1e-3);  // a step of the helix turns it by about 0.01 rad
  // A target that stays at one point and turns: the positions alone would leave the alignment's
  // rotation free; the orientations give it.
  std::vector<TumRow> still = reference;
  for (auto& r : still) r.g.translation() = obs::Vec3(0.4, -0.2, 1.5);
  std::vector<TumRow> still_moved = still;
  for (auto& r : still_moved) r.g = motion.inverse() * r.g;
  const auto still_undone = compare_trajectory(still, still_moved, aligned, "still");
  EXPECT_LT((still_undone.alignment * motion.inverse()).translation().norm(), 1e-9);
  EXPECT_LT(obs::rotvec(still_undone.alignment * motion.inverse()).norm(), 1e-9);
  EXPECT_LT(still_undone.position_max, 1e-9);
  // Orientations whose differences cancel (the identity and a half turn): no unique mean.
  std::vector<TumRow> half = {reference[0], reference[1]};
  half[1].g.linear() =
      reference[1].g.linear() * Eigen::AngleAxisd(M_PI, obs::Vec3::UnitZ()).toRotationMatrix();
  const std::vector<TumRow> est = {reference[0], reference[1]};
  test::expect_input_error([&] { compare_trajectory(half, est, aligned, "the pair"); },
                           {"the pair", "not unique"});
}

// A target moved by hand: its speeds change over time, so they fix the time offset.
obs::SE3 hand_moved(double t) {
  return obs::make_pose(obs::Vec3(0.5 * std::sin(1.3 * t) + 0.2 * t, 0.3 * std::cos(0.7 * t),
                                  0.1 * std::sin(2.1 * t)),
                        obs::Vec3(0.4 * std::sin(0.9 * t), 0.2 * t, 0.3 * std::cos(1.7 * t)));
}

// A reference sampled at `hz` over [t0, t1] on its own clock.
std::vector<TumRow> sampled(const std::function<obs::SE3(double)>& pose, double hz, double t0,
                            double t1) {
  std::vector<TumRow> rows;
  for (int j = 0; t0 + j / hz <= t1 + 1e-12; ++j) {
    TumRow r;
    r.t = t0 + j / hz;
    r.g = pose(r.t);
    rows.push_back(r);
  }
  return rows;
}

// Estimates at 30 Hz over [2, 8] s of the results' clock, in another world frame (the rigid
// motion A), of the reference's pose `offset` earlier on its clock (a reference pose at t_ref is
// the estimate's at t_ref + offset), with noise of `sigma_m` and `sigma_rad` per axis (seeded).
std::vector<TumRow> estimated(const std::function<obs::SE3(double)>& pose, double offset,
                              double sigma_m, double sigma_rad, unsigned seed) {
  const obs::SE3 a = obs::make_pose(obs::Vec3(1.5, -2.0, 0.7), obs::Vec3(0.3, -0.5, 1.1));
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<TumRow> rows;
  for (int k = 0; k <= 180; ++k) {
    TumRow r;
    r.t = 2.0 + k / 30.0;
    const obs::SE3 noise = obs::make_pose(sigma_m * obs::Vec3(n(rng), n(rng), n(rng)),
                                          sigma_rad * obs::Vec3(n(rng), n(rng), n(rng)));
    r.g = a * pose(r.t - offset) * noise;
    rows.push_back(r);
  }
  return rows;
}

// The offset of a reference on another clock from the target's speeds: within a grid step of
// the truth on noisy estimates in another world frame (two of them, as two cameras), and then
// the alignment leaves only the noise; refused where the speeds cannot fix it: a target that
// stands still or moves at one speed, estimates of another motion, a best match at the edge of
// the offsets tried, and a reference that covers too few offsets.
TEST(Trajectories, TimeOffsetFromTheSpeedsOrRefusedWhereTheyDoNotFixIt) {
  const double offset = 0.137;  // [s]
  const auto reference = sampled(hand_moved, 200.0, 0.0, 10.0);
  const auto cam1 = estimated(hand_moved, offset, 0.002, 0.0035, 1),
             cam2 = estimated(hand_moved, offset, 0.002, 0.0035, 2);
  const double max_dt = 0.01;
  TimeOffsetSettings s;  // within 1 s of 0, every 1/120 s (a quarter of the estimates' step)
  const auto found = estimate_time_offset(reference, {&cam1, &cam2}, max_dt, s, "hand");
  std::printf("offset found %.5f s (true %.3f s), mismatch %.3f, median %.3f, %zu offsets\n",
              found.offset, offset, found.mismatch, found.median_mismatch, found.offsets);
  EXPECT_LT(std::abs(found.offset - offset), 1.0 / 120.0);
  // The noise read off the estimates, whose bias on the speeds is taken off.
  std::printf("noise read %.3f mm and %.3f mrad per axis (2 and 3.5)\n", found.position_noise * 1e3,
              found.rotation_noise * 1e3);
  EXPECT_NEAR(found.position_noise, 0.002, 0.0003);
  EXPECT_NEAR(found.rotation_noise, 0.0035, 0.0005);
  EXPECT_EQ(found.offsets, 241u);     // the reference's 10 s cover every offset within 1 s
  EXPECT_GE(found.pairs, 2u * 176u);  // each camera's 181 poses, 3-4 frames (0.1 s) apart
  EXPECT_LT(found.mismatch, s.max_contrast * found.median_mismatch);
  // Compared at the offset found, aligned: the noise (2 mm per axis) and the rest of the offset.
  TrajectoryComparisonSettings c;
  c.align = true;
  c.reference_time_offset = found.offset;
  const auto at_found = compare_trajectory(reference, cam1, c, "hand");
  c.reference_time_offset = 0.0;
  const auto at_zero = compare_trajectory(reference, cam1, c, "hand");
  std::printf("aligned position RMSE at the offset found %.4f m, at 0 %.4f m\n",
              at_found.position_rmse, at_zero.position_rmse);
  EXPECT_LT(at_found.position_rmse, 0.006);
  EXPECT_GT(at_zero.position_rmse, 5 * at_found.position_rmse);
  // Centred elsewhere (a rough offset given), the same offset.
  TimeOffsetSettings centred = s;
  centred.centre = 0.4;
  EXPECT_NEAR(estimate_time_offset(reference, {&cam1}, max_dt, centred, "hand").offset,
              found.offset, 1.0 / 120.0);

  // A convergence (as an observer's estimate of a still target approaches it): a shifted
  // exponential is the same one scaled, so the speeds' values fix the offset, not their shape.
  const auto converging = [](double t) {
    const double e = std::exp(-t / 1.5);
    return obs::make_pose(obs::Vec3(0.8, -0.5, 1.2) * e + obs::Vec3(0, 0, 1),
                          obs::Vec3(0.6, 0.2, -0.4) * e);
  };
  const auto converged = estimated(converging, offset, 0.0005, 0.001, 7);
  const double from_values =
      estimate_time_offset(sampled(converging, 200.0, 0.0, 10.0), {&converged}, max_dt, s, "c")
          .offset;
  std::printf("convergence: offset found %.5f s\n", from_values);
  EXPECT_NEAR(from_values, offset, 1.0 / 120.0);

  // A target that stands still, and one that turns at one speed on a circle at one speed.
  const auto still =
      sampled([](double) { return obs::make_pose(obs::Vec3(1, 2, 3), obs::Vec3(0.1, 0, 0)); },
              200.0, 0.0, 10.0);
  const auto circle = [](double t) {
    return obs::make_pose(obs::Vec3(std::cos(t), std::sin(t), 0.5), obs::Vec3(0, 0, t));
  };
  const auto on_circle = estimated(circle, offset, 0.002, 0.0035, 3);
  const auto turning = sampled(circle, 200.0, 0.0, 10.0);
  for (const auto* ref : {&still, &turning})
    test::expect_input_error([&] { estimate_time_offset(*ref, {&on_circle}, max_dt, s, "steady"); },
                             {"steady", "speed does not change", "--reference-time-offset"});
  // Estimates of another motion: the mismatch is flat.
  const auto other = estimated(
      [](double t) {
        return obs::make_pose(obs::Vec3(0.3 * std::sin(2.9 * t), 0.2 * t * t / 10, 0.0),
                              obs::Vec3(0.0, 0.6 * std::cos(0.4 * t), 0.0));
      },
      offset, 0.002, 0.0035, 4);
  test::expect_input_error([&] { estimate_time_offset(reference, {&other}, max_dt, s, "other"); },
                           {"other", "do not determine", "median"});
  // The true offset outside the offsets tried: the best lies at their edge.
  TimeOffsetSettings narrow = s;
  narrow.search = 0.1;
  test::expect_input_error([&] { estimate_time_offset(reference, {&cam1}, max_dt, narrow, "n"); },
                           {"n", "edge of the offsets tried", "widen"});
  // A reference 100 s ahead covers no offset within 1 s of 0.
  std::vector<TumRow> ahead = reference;
  for (auto& r : ahead) r.t += 100.0;
  test::expect_input_error([&] { estimate_time_offset(ahead, {&cam1}, max_dt, s, "ahead"); },
                           {"ahead", "too few of the offsets"});
}

// The command: a reference 1000 s ahead with a rough offset of -1000 s given, refined to the
// estimates' own from the speeds (two cameras of simulate's form of estimates.csv), compared at
// it, and what was found in comparison.json; without --reference, and against a reference of a
// target that stands still, one line, and the comparison already written stays.
TEST(Cli, TrajectoriesEstimateAReferencesTimeOffset) {
  const auto dir = test::scratch_dir("cli_time_offset");
  const double offset = 0.137;
  fs::create_directories(dir / "results");
  {
    std::ofstream est(dir / "results" / "estimates.csv");
    est.precision(17);
    est << io::kSimulationEstimatesHeader << "\n";
    const auto cam1 = estimated(hand_moved, offset, 0.002, 0.0035, 5),
               cam2 = estimated(hand_moved, offset, 0.002, 0.0035, 6);
    for (size_t k = 0; k < cam1.size(); ++k)
      for (const auto* cam : {&cam1, &cam2}) {
        const obs::SE3& g = (*cam)[k].g;
        const obs::Vec3 p = g.translation(), w = obs::rotvec(g);
        est << (*cam)[k].t << ',' << (cam == &cam1 ? 1 : 2) << ',' << p.x() << ',' << p.y() << ','
            << p.z() << ',' << w.x() << ',' << w.y() << ',' << w.z() << "\n";
      }
    std::ofstream ref(dir / "mocap.txt");
    for (const TumRow& r : sampled(hand_moved, 200.0, 0.0, 10.0))
      ref << tum_line(r.t + 1000.0, r.g) << "\n";
    std::ofstream still(dir / "still.txt");
    for (int j = 0; j <= 2000; ++j)
      still << tum_line(1000.0 + j / 200.0, obs::make_pose(obs::Vec3(1, 2, 3), obs::Vec3::Zero()))
            << "\n";
  }
  const std::string cmd = "trajectories " + (dir / "results").string() + " --align";
  const auto r = test::run_netvmo(cmd + " --reference " + (dir / "mocap.txt").string() +
                                      " --reference-time-offset -1000 --estimate-time-offset",
                                  dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("reference time offset: -999.8"), std::string::npos) << r.out;
  const fs::path json = dir / "results" / "trajectories" / "comparison.json";
  const auto j = nlohmann::json::parse(test::slurp(json));
  EXPECT_NEAR(j["reference_time_offset_s"].get<double>(), offset - 1000.0, 1.0 / 120.0);
  EXPECT_EQ(j["reference_time_offset_estimated"]["centre_s"].get<double>(), -1000.0);
  EXPECT_EQ(j["reference_time_offset_estimated"]["searched_s"].get<double>(), 1.0);
  EXPECT_NEAR(j["reference_time_offset_estimated"]["position_noise_m"].get<double>(), 0.002,
              0.0003);
  EXPECT_NEAR(j["reference_time_offset_estimated"]["rotation_noise_deg"].get<double>(),
              0.0035 * 180 / M_PI, 0.0005 * 180 / M_PI);
  ASSERT_EQ(j["cameras"].size(), 2u);
  for (const auto& c : j["cameras"]) {
    EXPECT_EQ(c["matched"].get<int>(), 181);
    EXPECT_LT(c["position_rmse_m"].get<double>(), 0.006) << c;
  }
  const std::string before = test::slurp(json);
  auto bad = test::run_netvmo(cmd + " --estimate-time-offset", dir);
  EXPECT_EQ(bad.code, 1);
  test::expect_one_line(bad.err, {"--estimate-time-offset", "needs --reference"});
  bad = test::run_netvmo(cmd + " --time-offset-search 2", dir);  // CLI11's check
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("--time-offset-search requires --estimate-time-offset"), std::string::npos)
      << bad.err;
  bad = test::run_netvmo(cmd + " --reference " + (dir / "still.txt").string() +
                             " --reference-time-offset -1000 --estimate-time-offset",
                         dir);
  EXPECT_EQ(bad.code, 1);
  test::expect_one_line(bad.err, {(dir / "still.txt").string(), "does not change"});
  EXPECT_EQ(test::slurp(json), before);
  fs::remove_all(dir);
}

// The command on netvmo simulate's output (the paper's Section 5): every camera's file holds its
// estimates.csv rows, in order; run again, it replaces its own folder; it refuses to replace the
// results and names a folder without estimates.csv, each in one line with a non-zero exit.
TEST(Cli, TrajectoriesOfASimulationAreItsEstimates) {
  const auto dir = test::scratch_dir("cli_trajectories");
  const fs::path sim = dir / "sim";
  const auto s = test::run_netvmo(
      "simulate " + std::string(NETVMO_SOURCE_DIR) + "/datasets/paper5.yaml --out " + sim.string(),
      dir);
  ASSERT_EQ(s.code, 0) << s.err;
  for (int pass = 0; pass < 2; ++pass) {
    const auto r = test::run_netvmo("trajectories " + sim.string(), dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("cam_5.txt (901 poses)"), std::string::npos) << r.out;
  }
  std::map<int, std::vector<io::EstimateRow>> rows;
  for (const auto& r : io::read_estimates_csv(sim / "estimates.csv")) rows[r.camera].push_back(r);
  ASSERT_EQ(rows.size(), 5u);
  for (const auto& [camera, want] : rows) {
    const auto got = parse_tum(sim / "trajectories" / ("cam_" + std::to_string(camera) + ".txt"));
    ASSERT_EQ(got.size(), want.size()) << "camera " << camera;
    for (size_t k = 0; k < got.size(); ++k) {
      ASSERT_TRUE(want[k].g_w.has_value());
      expect_pose(got[k], want[k].t, *want[k].g_w);
    }
  }
  const auto refused =
      test::run_netvmo("trajectories " + sim.string() + " --out " + sim.string(), dir);
  EXPECT_EQ(refused.code, 1);
  test::expect_one_line(refused.err, {sim.string(), "netvmo simulate"});
  fs::create_directories(dir / "empty");
  const auto missing = test::run_netvmo("trajectories " + (dir / "empty").string(), dir);
  EXPECT_EQ(missing.code, 1);
  test::expect_one_line(missing.err, {(dir / "empty" / "estimates.csv").string(), "cannot open"});
}

}  // namespace
}  // namespace netvmo::run
