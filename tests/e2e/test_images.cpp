// End to end on images rendered at test time: render -> AprilTag front end -> networked
// observer -> evaluation. delta_i(t) always comes from detection.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/run/image_run.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/run/run_report.hpp"
#include "netvmo/pipeline/run/trajectories.hpp"
#include "netvmo/pipeline/sources/render_source.hpp"
#include "netvmo/render/renderer.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace netvmo;

using test::slurp;

namespace {
const fs::path kSource = NETVMO_SOURCE_DIR;

render::SceneDescription scenario(const char* name) {
  return io::load_render_scenario(kSource / "datasets" / name);
}

run::ImageRunSettings quiet_options() {
  run::ImageRunSettings o;
  o.progress = false;
  return o;
}

// A small rendered dataset shared by the recorded-data and bad-input tests.
class SmallDataset : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test::scratch_dir("small"));
    auto scene = scenario("paper5_render.yaml");
    scene.imaging.spp = 1;
    render::Renderer r(scene);
    io::DatasetSettings o;
    o.frames = 12;
    o.progress = false;
    io::write_dataset(r, *dir_ / "rendered", o);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static fs::path* dir_;
};
fs::path* SmallDataset::dir_ = nullptr;

double angle_deg(const obs::SE3& a, const obs::SE3& b) {
  return obs::log_so3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}
}  // namespace

// The paper's setting made visible: cameras 1-3 see the tag, camera 4 looks away and camera 5
// is blocked by a pillar. Static target, k_e = 1, k_s = 50, five seconds.
TEST(EndToEnd, StaticTargetEveryCameraConvergesToGStar) {
  auto source = sources::make_render_source(scenario("paper5_render.yaml"), 150);
  const auto r = run::run_images(*source, quiet_options());
  const auto& last = r.history.back();
  ASSERT_TRUE(last.g_star.has_value());
  for (size_t i = 0; i < 5; ++i) {
    int seen = 0;
    for (const auto& f : r.history) seen += f.cameras[i].delta;
    if (i < 3) {
      EXPECT_EQ(seen, 150) << "camera " << i + 1 << " should see the tag in every frame";
    } else {
      EXPECT_EQ(seen, 0) << "camera " << i + 1 << " should never see the tag";
    }
    const auto e = run::pose_error(last.cameras[i].est_w, *last.g_star);
    EXPECT_LT(e.position, 0.01) << "camera " << i + 1;
    EXPECT_LT(e.orientation_deg, 0.5) << "camera " << i + 1;
  }
  // Blind cameras end on their neighbours' estimates.
  EXPECT_LT((last.cameras[3].est_w.translation() - last.cameras[2].est_w.translation()).norm(),
            0.005);
  EXPECT_LT((last.cameras[4].est_w.translation() - last.cameras[0].est_w.translation()).norm(),
            0.005);
  // The networked observer beats the independent observers.
  ASSERT_TRUE(last.energies && last.energies_indep);
  EXPECT_LT(last.energies->U_p, last.energies_indep->U_p);
  EXPECT_LT(last.energies->U_R, last.energies_indep->U_R);
}

// The tag crosses the room; it enters and leaves the cameras' fields of view and passes
// behind a pillar and a moving cart.
TEST(EndToEnd, MovingTargetDeltaIsDetectionAndEstimatesStayBounded) {
  auto scene = scenario("moving_target.yaml");
  scene.imaging.spp = 1;
  const int frames = scene.frames;
  auto source = sources::make_render_source(scene, frames);
  auto options = quiet_options();
  options.runner.k_e = 10.0;  // faster tracking of a moving target (docs/images.md, "Moving target
                              // and tracking lag")
  options.runner.k_s = 100.0;
  const auto r = run::run_images(*source, options);
  ASSERT_EQ(static_cast<int>(r.history.size()), frames);

  // delta_i(t) is a real detection: every tag an independent full-frame detection of the same
  // images finds is detected, and the run's searches (tracking window at full resolution for
  // small tags, normalised retry under shadows, acquisition) find more only where the tag is
  // there: those corners lie within 1 px of the renderer's.
  frontend::DetectorSettings ds;
  ds.target_id = scene.target().tag.id;
  frontend::FrontEnd fe(ds);
  auto again = sources::make_render_source(scene, frames);
  render::Renderer truth(scene);
  int changes = 0, detected = 0, extra = 0;
  for (int k = 0; k < frames; ++k) {
    for (size_t i = 0; i < scene.cameras.size(); ++i) {
      const bool d = fe.observe(again->read(i, k), again->calibration(i)).delta;
      const auto& run_obs = r.frames[static_cast<size_t>(k)][i];
      EXPECT_EQ(r.history[static_cast<size_t>(k)].cameras[i].delta, run_obs.delta);
      if (d) {
        EXPECT_TRUE(run_obs.delta) << "frame " << k << " camera " << i + 1;
      }
      if (run_obs.delta && !d) {
        ++extra;
        const auto t = truth.truth(static_cast<int>(i), k);
        for (size_t c = 0; c < 4; ++c) {
          ASSERT_TRUE(t.corners[c].has_value()) << "frame " << k << " camera " << i + 1;
          EXPECT_LT(std::hypot(run_obs.corners_px[c].x - t.corners[c]->x(),
                               run_obs.corners_px[c].y - t.corners[c]->y()),
                    1.0)
              << "frame " << k << " camera " << i + 1;
        }
      }
      detected += d;
      if (k > 0)
        changes += r.history[static_cast<size_t>(k)].cameras[i].delta !=
                   r.history[static_cast<size_t>(k) - 1].cameras[i].delta;
    }
  }
  std::printf("moving target: %d full-frame detections, %d more by the run's searches\n", detected,
              extra);
  EXPECT_GE(changes, 6) << "visibility should change over time";
  EXPECT_GT(detected, frames);

  // The observer has no model of the target's motion, so it lags: in consensus the average
  // obeys n dp/dt = k_e sum_{i in V_f} (p_oi - p), a lag of v n / (k_e |V_f|) at speed v
  // (docs/images.md, "Moving target and tracking lag"). Bounded: once initialised, every estimate
  // stays within 0.6 m of the moving g*(t) (the target moves at ~1.2 m/s; the lag bound with one
  // visible camera is ~0.6 m). Re-convergence: after each stretch without any detection, the error
  // shrinks once the target is seen again.
  auto network_error = [&](size_t k) {
    double e = 0.0;
    for (const auto& c : r.history[k].cameras)
      e = std::max(e, (c.est_w.translation() - r.history[k].g_star->translation()).norm());
    return e;
  };
  double worst = 0.0;
  for (size_t k = 0; k < r.history.size(); ++k)
    if (r.history[k].g_star) worst = std::max(worst, network_error(k));
  EXPECT_LT(worst, 0.6);
  int reacquisitions = 0;
  for (size_t k = 1; k + 10 < r.history.size(); ++k) {
    if (!r.history[k].g_star || r.history[k - 1].g_star) continue;
    ++reacquisitions;
    ASSERT_TRUE(r.history[k + 10].g_star) << "frame " << k + 10;
    EXPECT_LT(network_error(k + 10), 0.8 * network_error(k)) << "after frame " << k;
  }
  EXPECT_GE(reacquisitions, 1) << "the scenario should hide the target from every camera once";
  RecordProperty("reacquisitions", reacquisitions);
}

TEST_F(SmallDataset, RecordedFoldersAndVideoGiveTheSameEstimates) {
  const fs::path rendered = *dir_ / "rendered", recorded = *dir_ / "recorded";
  fs::create_directories(recorded / "calib");
  for (const char* f : {"network.yaml", "target.csv", "truth_cameras.csv"})
    fs::copy_file(rendered / f, recorded / f);
  for (int id = 1; id <= 5; ++id) {
    const std::string cam = "cam_" + std::to_string(id);
    fs::copy_file(rendered / "calib" / (cam + ".yaml"), recorded / "calib" / (cam + ".yaml"));
    if (id == 3) {
      // Camera 3 as a lossless video file.
      cv::VideoWriter w((recorded / (cam + ".mkv")).string(),
                        cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 30, cv::Size(640, 480), false);
      ASSERT_TRUE(w.isOpened());
      for (int k = 0; k < 12; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", k);
        w.write(cv::imread((rendered / cam / name).string(), cv::IMREAD_GRAYSCALE));
      }
    } else {
      // Other cameras as folders of JPEG-free, non-numerically named PNGs (ordered by name).
      fs::create_directories(recorded / cam);
      for (int k = 0; k < 12; ++k) {
        char from[32], to[32];
        std::snprintf(from, sizeof from, "%06d.png", k);
        std::snprintf(to, sizeof to, "shot_%03d.png", k);
        fs::copy_file(rendered / cam / from, recorded / cam / to);
      }
    }
  }
  auto a = sources::open_dataset_source(rendered);
  auto b = sources::open_dataset_source(recorded);
  const auto ra = run::run_images(*a, quiet_options());
  const auto rb = run::run_images(*b, quiet_options());
  ASSERT_EQ(ra.history.size(), 12u);
  ASSERT_EQ(rb.history.size(), 12u);
  int detections = 0;
  for (size_t k = 0; k < 12; ++k) {
    for (size_t i = 0; i < 5; ++i) {
      const auto& ca = ra.history[k].cameras[i];
      const auto& cb = rb.history[k].cameras[i];
      EXPECT_EQ(ca.delta, cb.delta);
      detections += ca.delta;
      EXPECT_LT((ca.est_w.translation() - cb.est_w.translation()).norm(), 1e-9);
      EXPECT_LT(angle_deg(ca.est_w, cb.est_w), 1e-7);
    }
  }
  EXPECT_EQ(detections, 36);
}

// The front end's threads (it runs ahead of the observer, each free thread taking the next
// camera's frame) and the skipped searches of cameras that see nothing in a static scene
// (TrackingSettings::change_pixels) change no detection and no estimate, to the last bit.
TEST_F(SmallDataset, FrontEndThreadsAndSkippedSearchesChangeNothing) {
  auto source = sources::open_dataset_source(*dir_ / "rendered");
  const auto run_with = [&](int workers, int change_pixels) {
    auto o = quiet_options();
    o.workers = workers;
    o.tracking.change_pixels = change_pixels;
    return run::run_images(*source, o);
  };
  const int skipping = frontend::TrackingSettings{}.change_pixels;
  const auto ref = run_with(1, 0);
  for (const auto& [workers, change_pixels] :
       {std::pair{1, skipping}, std::pair{2, skipping}, std::pair{3, 0}}) {
    SCOPED_TRACE(std::to_string(workers) + " workers, change_pixels " +
                 std::to_string(change_pixels));
    const auto r = run_with(workers, change_pixels);
    ASSERT_EQ(r.history.size(), ref.history.size());
    for (size_t k = 0; k < r.history.size(); ++k)
      for (size_t i = 0; i < 5; ++i) {
        const auto &a = r.history[k].cameras[i], &b = ref.history[k].cameras[i];
        EXPECT_EQ(a.delta, b.delta) << "frame " << k << " camera " << i;
        EXPECT_TRUE(a.est_w.matrix() == b.est_w.matrix()) << "frame " << k << " camera " << i;
        EXPECT_EQ(r.frames[k][i].status, ref.frames[k][i].status);
      }
  }
  // The workers' front ends are built in parallel: a setting they reject is the run's error
  // on any number of them.
  for (const int workers : {1, 2, 3}) {
    auto o = quiet_options();
    o.workers = workers;
    o.tracking.window_max_decimate = 0;
    try {
      run::run_images(*source, o);
      ADD_FAILURE() << workers << " workers: no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("window_max_decimate"), std::string::npos) << e.what();
    }
  }
}

// The overlays: by default the mosaic alone (its tiles 320 px wide), with camera_videos each
// camera's video at its own resolution too; drawn on the writer thread, whose error (a video
// that cannot be opened) stops the run with the file's name.
TEST_F(SmallDataset, OverlaysWriteTheMosaicAndCameraVideosOnRequest) {
  auto source = sources::open_dataset_source(*dir_ / "rendered");
  const auto run_with = [&](const fs::path& out, const run::OverlaySettings& settings) {
    run::OverlayWriter writer(out, *source, settings);
    run::run_images(*source, quiet_options(),
                    [&](int k, const std::vector<cv::Mat>& images,
                        const std::vector<std::vector<frontend::Observation>>& cams,
                        const std::vector<const run::FrameRecord*>& records) {
                      writer(k, images, cams, records);
                    });
    writer.finish();
  };
  const fs::path plain = *dir_ / "overlays_plain", all = *dir_ / "overlays_all";
  run_with(plain, {});
  const cv::Mat mosaic = cv::imread((plain / "overlays" / "mosaic.png").string());
  EXPECT_EQ(mosaic.cols, 3 * 320);  // five 640x480 cameras, 3 per row
  EXPECT_EQ(mosaic.rows, 2 * 240);
  EXPECT_TRUE(fs::exists(plain / "overlays" / "mosaic.mp4"));
  EXPECT_FALSE(fs::exists(plain / "overlays" / "cam_1.mp4"));

  run::OverlaySettings videos;
  videos.camera_videos = true;
  run_with(all, videos);
  for (int id = 1; id <= 5; ++id) {
    cv::VideoCapture v((all / "overlays" / ("cam_" + std::to_string(id) + ".mp4")).string());
    ASSERT_TRUE(v.isOpened()) << id;
    cv::Mat f;
    ASSERT_TRUE(v.read(f)) << id;
    EXPECT_EQ(f.cols, 640);
    EXPECT_EQ(f.rows, 480);
    EXPECT_EQ(static_cast<int>(v.get(cv::CAP_PROP_FRAME_COUNT)), 12) << id;
  }

  const fs::path bad = *dir_ / "overlays_bad";
  fs::create_directories(bad / "overlays" / "mosaic.mp4");  // a folder where the video goes
  try {
    run_with(bad, {});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mosaic.mp4"), std::string::npos) << e.what();
  }
}

// The same dataset with every calibration as a ROS camera_info file (detected by its content):
// `netvmo run` gives the same summary.json, timing and the dataset's name aside.
TEST_F(SmallDataset, RosCalibrationFilesGiveTheSameSummary) {
  const fs::path rendered = *dir_ / "rendered", ros = *dir_ / "ros";
  fs::copy(rendered, ros, fs::copy_options::recursive);
  for (int id = 1; id <= 5; ++id) {
    const fs::path f = ros / "calib" / ("cam_" + std::to_string(id) + ".yaml");
    const io::Calibration c = io::load_calibration_opencv(f);
    io::save_calibration_ros(f, c, "cam_" + std::to_string(id));
    ASSERT_TRUE(io::looks_like_ros_camera_info(f));
  }
  const auto summary = [&](const fs::path& ds, const std::string& out) {
    const auto c = test::run_netvmo(
        "run " + ds.string() + " --out " + (*dir_ / out).string() + " --no-overlays --no-plots",
        *dir_);
    EXPECT_EQ(c.code, 0) << c.err;
    auto s = nlohmann::json::parse(slurp(*dir_ / out / "summary.json"));
    s.erase("timing");
    s.erase("dataset");
    return s;
  };
  const auto a = summary(rendered, "run_opencv"), b = summary(ros, "run_ros");
  EXPECT_EQ(a, b);
  EXPECT_EQ(a["cameras"].size(), 5u);
  EXPECT_EQ(slurp(*dir_ / "run_opencv" / "estimates.csv"),
            slurp(*dir_ / "run_ros" / "estimates.csv"));
  // An image size that differs from the ROS file's: one line naming the image and the file.
  std::string text = slurp(ros / "calib" / "cam_2.yaml");
  text.replace(text.find("image_width: 640"), 16, "image_width: 800");
  std::ofstream(ros / "calib" / "cam_2.yaml") << text;
  const auto c = test::run_netvmo(
      "run " + ros.string() + " --out " + (*dir_ / "run_ros_bad").string() + " --no-overlays",
      *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_NE(
      c.err.find("is 640x480 but " + (ros / "calib" / "cam_2.yaml").string() + " says 800x480"),
      std::string::npos)
      << c.err;
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
}

// netvmo trajectories --dataset: every camera's absolute trajectory error against the true target
// pose (run::compare_trajectory, on the poses of the TUM files it writes) is the run's own
// evaluation of its estimate against the truth (summary.json, networked vs_true), to 1e-8 m
// (estimates.csv's digits); aligned, a small rigid motion; a bad reference is one line, and the
// comparison already written stays.
TEST_F(SmallDataset, TrajectoryErrorsAgainstTheTruthAreTheRunsOwn) {
  const fs::path rendered = *dir_ / "rendered", results = *dir_ / "run_trajectories";
  auto c = test::run_netvmo(
      "run " + rendered.string() + " --out " + results.string() + " --no-overlays --no-plots",
      *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  const std::string trajectories =
      "trajectories " + results.string() + " --dataset " + rendered.string();
  c = test::run_netvmo(trajectories, *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("absolute trajectory error"), std::string::npos) << c.out;
  const fs::path comparison = results / "trajectories" / "comparison.json";
  const auto summary = nlohmann::json::parse(slurp(results / "summary.json"));
  const auto compared = nlohmann::json::parse(slurp(comparison));
  EXPECT_EQ(compared["aligned"], false);
  ASSERT_EQ(compared["cameras"].size(), 5u);
  ASSERT_EQ(summary["cameras"].size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    const auto& got = compared["cameras"][i];
    const auto& want = summary["cameras"][i]["networked"]["vs_true"];
    EXPECT_EQ(got["camera"], summary["cameras"][i]["id"]);
    EXPECT_EQ(got["reference"], "truth.txt");
    EXPECT_EQ(got["matched"], want["frames"]);
    EXPECT_EQ(got["unmatched"], 0);
    EXPECT_NEAR(got["position_mean_m"].get<double>(), want["mean_position_m"].get<double>(), 1e-8)
        << "camera " << got["camera"];
    EXPECT_NEAR(got["rotation_mean_deg"].get<double>(), want["mean_orientation_deg"].get<double>(),
                1e-6)
        << "camera " << got["camera"];
    EXPECT_GT(got["position_mean_m"].get<double>(), 0.0);
  }
  // Aligned (the static target's positions are one point; the orientations give the rotation):
  // a rigid motion of the size of the cameras' errors, and the rotation errors no larger.
  c = test::run_netvmo(trajectories + " --align", *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto aligned = nlohmann::json::parse(slurp(comparison));
  EXPECT_EQ(aligned["aligned"], true);
  for (size_t i = 0; i < 5; ++i) {
    const auto& a = aligned["cameras"][i];
    std::vector<double> p = a["alignment"]["translation_m"],
                        w = a["alignment"]["rotation_vector_rad"];
    EXPECT_LT(std::hypot(p[0], p[1], p[2]), 0.2) << "camera " << a["camera"];
    EXPECT_LT(std::hypot(w[0], w[1], w[2]), 5 * M_PI / 180) << "camera " << a["camera"];
    EXPECT_LE(a["rotation_rmse_deg"].get<double>(),
              1.01 * compared["cameras"][i]["rotation_rmse_deg"].get<double>());
  }
  // The truth as a reference on a clock 50 s ahead: refused until --reference-time-offset moves
  // it back, then the same errors as against the dataset's truth.
  const fs::path ahead = *dir_ / "truth_ahead.txt";
  {
    std::ofstream o(ahead);
    for (const run::TumRow& r : run::read_tum(results / "trajectories" / "truth.txt"))
      o << run::tum_line(r.t + 50.0, r.g) << '\n';
  }
  const std::string with_ahead = "trajectories " + results.string() + " --reference " +
                                 ahead.string() + " --out " + (*dir_ / "ahead_out").string();
  c = test::run_netvmo(with_ahead, *dir_);
  EXPECT_EQ(c.code, 1);
  test::expect_one_line(c.err, {ahead.string(), "no estimated pose", "--reference-time-offset"});
  c = test::run_netvmo(with_ahead + " --reference-time-offset -50", *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto moved = nlohmann::json::parse(slurp(*dir_ / "ahead_out" / "comparison.json"));
  EXPECT_EQ(moved["reference_time_offset_s"], -50.0);
  ASSERT_EQ(moved["cameras"].size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(moved["cameras"][i]["matched"], compared["cameras"][i]["matched"]);
    EXPECT_NEAR(moved["cameras"][i]["position_mean_m"].get<double>(),
                compared["cameras"][i]["position_mean_m"].get<double>(), 1e-8);
  }
  // A reference that cannot be read: one line, and the comparison already written stays.
  const std::string before = slurp(comparison);
  c = test::run_netvmo(trajectories + " --reference " + (*dir_ / "none.txt").string(), *dir_);
  EXPECT_EQ(c.code, 1);
  test::expect_one_line(c.err, {(*dir_ / "none.txt").string(), "cannot open"});
  EXPECT_EQ(slurp(comparison), before);
  c = test::run_netvmo("trajectories " + results.string() + " --align", *dir_);
  EXPECT_EQ(c.code, 1);
  test::expect_one_line(c.err, {"--align", "--reference"});
  EXPECT_EQ(slurp(comparison), before);
  c = test::run_netvmo(trajectories + " --reference-time-offset 2", *dir_);
  EXPECT_EQ(c.code, 1);
  test::expect_one_line(c.err, {"--reference-time-offset", "needs --reference"});
  EXPECT_EQ(slurp(comparison), before);
  c = test::run_netvmo(with_ahead + " --reference-time-offset nan", *dir_);
  EXPECT_EQ(c.code, 1);
  test::expect_one_line(c.err, {"--reference-time-offset", "not a finite number"});
}

TEST_F(SmallDataset, BadInputGivesOneClearLineAndKeepGoingBlindsTheCamera) {
  const fs::path bad = *dir_ / "bad";
  fs::copy(*dir_ / "rendered", bad, fs::copy_options::recursive);
  std::ofstream(bad / "cam_2" / "000005.png", std::ios::trunc) << "not a png";
  const std::string out = (*dir_ / "out_bad").string();
  auto c = test::run_netvmo("run " + bad.string() + " --out " + out + " --no-overlays --no-plots",
                            *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_NE(c.err.find("cam_2/000005.png"), std::string::npos) << c.err;
  EXPECT_FALSE(fs::exists(fs::path(out) / "summary.json"));

  c = test::run_netvmo(
      "run " + bad.string() + " --out " + out + " --no-overlays --no-plots --keep-going", *dir_);
  EXPECT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.err.find("cam_2/000005.png"), std::string::npos) << "warned: " << c.err;
  // Camera 2 is blind at frame 5 only; the others keep detecting.
  std::ifstream est(fs::path(out) / "estimates.csv");
  std::string line;
  std::getline(est, line);
  int rows = 0;
  while (std::getline(est, line)) {
    int frame, camera, delta;
    double t;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%lf,%d,%d", &frame, &t, &camera, &delta), 4) << line;
    ++rows;
    if (camera == 2) {
      EXPECT_EQ(delta, frame == 5 ? 0 : 1) << line;
    } else if (camera == 1 || camera == 3) {
      EXPECT_EQ(delta, 1) << line;
    }
  }
  EXPECT_EQ(rows, 12 * 5);

  // An unknown camera in network.yaml's edges, and a disconnected graph.
  const fs::path unknown = *dir_ / "unknown";
  fs::copy(*dir_ / "rendered", unknown, fs::copy_options::recursive);
  std::string net = slurp(unknown / "network.yaml");
  const auto edges_at = net.find("edges:");
  ASSERT_NE(edges_at, std::string::npos);
  std::ofstream(unknown / "network.yaml")
      << net.substr(0, edges_at) << "edges: [[1, 2], [1, 3], [1, 5], [2, 3], [3, 4], [4, 9]]\n";
  c = test::run_netvmo("run " + unknown.string() + " --out " + out + "_u", *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_NE(c.err.find("network.yaml"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("9"), std::string::npos) << c.err;
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;

  std::ofstream(unknown / "network.yaml")
      << net.substr(0, edges_at) << "edges: [[1, 2], [1, 3], [2, 3], [4, 5]]\n";
  c = test::run_netvmo("run " + unknown.string() + " --out " + out + "_d", *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_NE(c.err.find("components {1,2,3} {4,5}"), std::string::npos) << c.err;
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
}

// netvmo sweep detects once (OUT/inputs.csv, reused by a second sweep), replays exactly what
// netvmo run computes at the same gains, and refuses a bad grid with one line.
TEST_F(SmallDataset, SweepDetectsOnceAndReplaysTheRun) {
  const std::string ds = (*dir_ / "rendered").string(), out = (*dir_ / "sweep").string();
  auto c = test::run_netvmo("sweep " + ds + " --out " + out + " --ks 0,50 --no-plot", *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("detected"), std::string::npos) << c.out;
  const std::string first = slurp(fs::path(out) / "sweep.csv");
  c = test::run_netvmo("sweep " + ds + " --out " + out + " --ks 0,50 --no-plot", *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("reusing"), std::string::npos) << c.out;
  EXPECT_EQ(slurp(fs::path(out) / "sweep.csv"), first);

  const std::string run_out = (*dir_ / "run50").string();
  c = test::run_netvmo("run " + ds + " --out " + run_out + " --no-overlays --no-plots", *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  const auto s = nlohmann::json::parse(slurp(fs::path(run_out) / "summary.json"));
  std::istringstream rows(first);
  std::string line;
  std::getline(rows, line);  // header
  int points = 0;
  while (std::getline(rows, line)) {
    double ke, ks, k, rounds, sf, eps_p, eps_R;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf", &ke, &ks, &k, &rounds, &sf,
                          &eps_p, &eps_R),
              7)
        << line;
    ++points;
    if (ks != 50) continue;
    EXPECT_EQ(rounds, s["rounds_per_frame"].get<double>());
    EXPECT_NEAR(eps_p, s["final"]["eps_p"].get<double>(), 1e-8 * eps_p) << line;
    EXPECT_NEAR(eps_R, s["final"]["eps_R"].get<double>(), 1e-8 * eps_R) << line;
  }
  EXPECT_EQ(points, 2);

  c = test::run_netvmo("sweep " + ds + " --out " + out + " --ks 1,x", *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_NE(c.err.find("--ks: 'x' is not a number"), std::string::npos) << c.err;
  EXPECT_EQ(std::count(c.err.begin(), c.err.end(), '\n'), 1) << c.err;
  EXPECT_EQ(slurp(fs::path(out) / "sweep.csv"), first) << "a failure leaves results alone";
}

namespace {
// sweep.csv as header names -> column of numbers, one entry per grid point.
std::map<std::string, std::vector<double>> read_sweep_csv(const fs::path& file) {
  std::istringstream in(slurp(file));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream hs(line);
  for (std::string n; std::getline(hs, n, ',');) names.push_back(n);
  std::map<std::string, std::vector<double>> cols;
  while (std::getline(in, line)) {
    if (line.empty()) continue;  // between blocks of k_e
    std::stringstream ls(line);
    size_t c = 0;
    for (std::string v; std::getline(ls, v, ','); ++c)
      cols[c < names.size() ? names[c] : "?"].push_back(std::strtod(v.c_str(), nullptr));
    EXPECT_EQ(c, names.size()) << line;
  }
  return cols;
}

// Runs netvmo with a `gnuplot` first on PATH that fails the way gnuplot does on a plot whose
// points are all undefined.
test::CliResult run_netvmo_with_failing_gnuplot(const std::string& args, const fs::path& scratch) {
  const fs::path bin = scratch / "failing_gnuplot";
  fs::create_directories(bin);
  std::ofstream(bin / "gnuplot") << "#!/bin/sh\ncat > /dev/null\n"
                                    "echo '         \"sweep.gp\" line 9: all points y value "
                                    "undefined!' >&2\nexit 1\n";
  fs::permissions(bin / "gnuplot", fs::perms::owner_all);
  const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cmd = "PATH='" + bin.string() + "':\"$PATH\" timeout -k 5 600 " +
                          std::string(NETVMO_BINARY_DIR) + "/netvmo " + args + " > " +
                          out.string() + " 2> " + err.string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}
}  // namespace

// A recorded dataset has no ground truth: netvmo sweep still succeeds, with nan where g* is
// needed, and tabulates and plots what the measurements define, the same numbers as on the
// dataset with its truth (they do not read it); it says which columns are undefined.
TEST_F(SmallDataset, SweepWithoutGroundTruthWritesWhatIsDefined) {
  const fs::path with = *dir_ / "rendered", without = *dir_ / "no_truth";
  fs::copy(with, without, fs::copy_options::recursive);
  for (const char* f : {"target.csv", "truth_cameras.csv", "truth.csv"})
    ASSERT_TRUE(fs::remove(without / f)) << f;
  const fs::path out = *dir_ / "sweep_no_truth", ref = *dir_ / "sweep_truth";
  auto c = test::run_netvmo("sweep " + without.string() + " --out " + out.string() + " --ks 0,5,50",
                            *dir_);
  ASSERT_EQ(c.code, 0) << c.out << c.err;
  EXPECT_TRUE(fs::is_regular_file(out / "sweep.png")) << c.out;
  EXPECT_TRUE(fs::is_regular_file(out / "inputs.csv"));
  EXPECT_NE(c.out.find("no ground truth in " + without.string()), std::string::npos) << c.out;
  const size_t undefined = c.out.find("undefined, nan in sweep.csv and not plotted: ");
  ASSERT_NE(undefined, std::string::npos) << c.out;
  const std::string listed = c.out.substr(undefined, c.out.find(';', undefined) - undefined);
  for (const char* name : {"eps_p", "eps_R", "U_p", "worst_position_mm", "theorem1_eps_p"})
    EXPECT_NE(listed.find(name), std::string::npos) << name << " not listed: " << listed;
  for (const char* name : {"eps_p_measured", "disagreement_mm", "last_quarter_step_mm"})
    EXPECT_EQ(listed.find(name), std::string::npos) << name << " listed: " << listed;

  c = test::run_netvmo(
      "sweep " + with.string() + " --out " + ref.string() + " --ks 0,5,50 --no-plot", *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_EQ(c.out.find("no ground truth"), std::string::npos) << c.out;
  auto a = read_sweep_csv(out / "sweep.csv"), b = read_sweep_csv(ref / "sweep.csv");
  ASSERT_EQ(a["k_s"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    for (const char* name :
         {"eps_p", "eps_R", "U_p", "U_R", "worst_position_mm", "theorem1_eps_p", "theorem1_eps_R"})
      EXPECT_TRUE(std::isnan(a[name][i])) << name << " at k_s " << a["k_s"][i];
    if (a["k_s"][i] > 0) {
      for (const char* name : {"eps_p", "eps_R", "U_p", "worst_position_mm"})
        EXPECT_TRUE(std::isfinite(b[name][i])) << name << " with truth";
    }
    for (const char* name : {"eps_p_measured", "eps_R_measured", "disagreement_mm",
                             "disagreement_deg", "last_quarter_step_mm", "last_quarter_step_deg"}) {
      EXPECT_EQ(std::isnan(a[name][i]), std::isnan(b[name][i])) << name;
      if (!std::isnan(b[name][i])) {
        EXPECT_EQ(a[name][i], b[name][i]) << name;
      }
    }
    if (a["k_s"][i] == 50) {  // every camera has an estimate: everything measured is defined
      for (const char* name : {"eps_p_measured", "eps_R_measured", "disagreement_mm"})
        EXPECT_TRUE(std::isfinite(a[name][i]) && a[name][i] >= 0) << name << " " << a[name][i];
    }
  }
  // The mutual term pulls the cameras together: at k_s = 50 they disagree less than at 5.
  EXPECT_LT(a["disagreement_mm"][2], a["disagreement_mm"][1]);
}

// A plot that fails leaves nothing under the result's name (and a previous result intact), and
// the message is gnuplot's own, not a guess about a missing package.
TEST_F(SmallDataset, SweepWhosePlotFailsLeavesNothingUnderItsName) {
  const fs::path ds = *dir_ / "rendered", out = *dir_ / "sweep_plot_fails";
  auto c = run_netvmo_with_failing_gnuplot(
      "sweep " + ds.string() + " --out " + out.string() + " --ks 0,50", *dir_);
  EXPECT_NE(c.code, 0);
  // One error line (after the progress bars), naming the plot under OUT and gnuplot's message.
  const size_t error = c.err.find("netvmo sweep: error: ");
  ASSERT_NE(error, std::string::npos) << c.err;
  const std::string line = c.err.substr(error);
  EXPECT_EQ(line.find((out / "sweep.png").string() + ": gnuplot failed: "), 21u) << line;
  EXPECT_NE(line.find("all points y value undefined"), std::string::npos) << line;
  EXPECT_EQ(line.find("installed"), std::string::npos) << line;
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << line;
  EXPECT_FALSE(fs::exists(out)) << "left " << out;
  for (const auto& e : fs::directory_iterator(*dir_)) {
    const std::string n = e.path().filename().string();
    if (n.rfind(out.filename().string(), 0) == 0) {
      EXPECT_EQ(n, out.filename().string() + ".lock") << "left " << n;
    }
  }
  // Over a previous result: it stays as it was.
  c = test::run_netvmo("sweep " + ds.string() + " --out " + out.string() + " --ks 0,50 --no-plot",
                       *dir_);
  ASSERT_EQ(c.code, 0) << c.err;
  const std::string before = slurp(out / "sweep.csv");
  c = run_netvmo_with_failing_gnuplot(
      "sweep " + ds.string() + " --out " + out.string() + " --ks 0,5,50", *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_EQ(slurp(out / "sweep.csv"), before);
  EXPECT_FALSE(fs::exists(out / "sweep.png"));
  // netvmo run's plots likewise: the message names the plot under OUT, and OUT is not there.
  const fs::path run_out = *dir_ / "run_plot_fails";
  c = run_netvmo_with_failing_gnuplot(
      "run " + ds.string() + " --out " + run_out.string() + " --no-overlays", *dir_);
  EXPECT_NE(c.code, 0);
  EXPECT_NE(c.err.find("netvmo run: error: " + (run_out / "energies.png").string() +
                       ": gnuplot failed: "),
            std::string::npos)
      << c.err;
  EXPECT_FALSE(fs::exists(run_out));
}

// On rendered images with exact relative poses the zero-offset estimator ends every camera,
// blind ones included, on g* to numerical precision, where the paper's observer at the same
// gains keeps an O(k_e/k_s) offset; it is reported as a baseline of a vmo run.
TEST_F(SmallDataset, ZeroOffsetReachesGStarAsABaselineOfARun) {
  auto o = quiet_options();
  o.runner.error_model = "exact";
  o.runner.k_e = 100;  // 12 frames = 0.4 s: e^-(100 * 0.4) of the spread is below round-off
  o.runner.k_s = 300;
  o.runner.compare_estimators = {"zero-offset"};
  auto source = sources::open_dataset_source(*dir_ / "rendered");
  const auto r = run::run_images(*source, o);
  const auto& last = r.history.back();
  ASSERT_TRUE(last.g_star.has_value());
  double zero = 0, vmo = 0;
  for (const auto& c : last.cameras) {
    ASSERT_TRUE(c.compare_w.at(0).has_value());
    const auto e = run::pose_error(*c.compare_w[0], *last.g_star);
    zero = std::max({zero, e.position, e.orientation_deg * M_PI / 180});
    vmo = std::max(vmo, run::pose_error(c.est_w, *last.g_star).position);
  }
  EXPECT_LT(zero, 1e-9);
  EXPECT_GT(vmo, 1e-3);
  const auto s = run::run_summary(*source, o, r);
  EXPECT_TRUE(s["cameras"][4]["compared"]["zero-offset"]["vs_g_star"].is_object());
  EXPECT_LT(s["final"]["U_R_zero-offset"].get<double>(), 1e-15);
}
