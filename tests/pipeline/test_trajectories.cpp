// netvmo trajectories: a result folder's estimates.csv and a dataset's target.csv as TUM
// trajectory files (run/trajectories.hpp), checked against the poses they were written from.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
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
std::vector<TumPose> read_tum(const fs::path& file) {
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
    const auto got = read_tum(f.out / ("cam_" + std::to_string(c) + ".txt"));
    ASSERT_EQ(got.size(), f.estimates[c].size()) << "camera " << c;
    EXPECT_EQ(files[static_cast<size_t>(c - 1)].poses, got.size());
    for (size_t k = 0; k < got.size(); ++k)
      expect_pose(got[k], f.estimates[c][k].first, f.estimates[c][k].second);
  }
  // target.csv keeps 9 digits: the truth read back to that.
  const auto truth = read_tum(f.out / "truth.txt");
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
  const auto shifted = read_tum(f.out / "truth.txt");
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
  const auto by_frame = read_tum(f.out / "truth.txt");
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
  const auto truth7 = read_tum(dir / "out" / "target_7_truth.txt");
  const auto cam7 = read_tum(dir / "out" / "target_7_cam_1.txt");
  ASSERT_EQ(truth7.size(), 3u);
  ASSERT_EQ(cam7.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT((truth7[static_cast<size_t>(k)].p - pose_at(k, 17).translation()).norm(), 1e-8);
    EXPECT_LT((cam7[static_cast<size_t>(k)].p - pose_at(k, 7).translation()).norm(), 1e-5);
  }
  // Without target_7.csv: that target's truth is not known, the first's still written.
  fs::remove(dir / "dataset" / "target_7.csv");
  fs::remove_all(dir / "out");
  fs::create_directories(dir / "out");
  EXPECT_EQ(write_trajectories(dir / "results", dir / "dataset", dir / "out").size(), 3u);
  EXPECT_FALSE(fs::exists(dir / "out" / "target_7_truth.txt"));
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
    const auto got = read_tum(sim / "trajectories" / ("cam_" + std::to_string(camera) + ".txt"));
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
