// Dataset folders: image folders and video files give the same detections; the frame-count
// rule (missing frames, shorter cameras, `frames:`) with warnings; errors name the file.
#include <gtest/gtest.h>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpXmlParserCamera.h>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <tuple>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
using namespace io;
using namespace sources;
using namespace frontend;
namespace fs = std::filesystem;

using test::expect_input_error;

bool any_warning_contains(const Dataset& ds, const std::string& a, const std::string& b) {
  for (const auto& w : ds.warnings)
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos) return true;
  return false;
}

/// Runs the front end on every frame of every camera: [camera][frame].
std::vector<std::vector<Observation>> run_all(Dataset& ds) {
  FrontEnd fe(DetectorSettings{});
  std::vector<std::vector<Observation>> out(ds.cameras.size());
  for (int f = 0; f < ds.frame_count; ++f)
    for (size_t c = 0; c < ds.cameras.size(); ++c)
      out[c].push_back(fe.observe(ds.read(c, f), ds.cameras[c].calib));
  return out;
}

TEST(Sources, ImageFolderAndMjpgVideoAgree) {
  const auto spec_img = testing::simple_dataset_spec(2, 4, false);
  const auto spec_vid = testing::simple_dataset_spec(2, 4, true);
  const auto d_img = testing::fresh_dir("src_img"), d_vid = testing::fresh_dir("src_vid");
  const auto truth = testing::write_synth_dataset(d_img, spec_img);
  testing::write_synth_dataset(d_vid, spec_vid);
  Dataset a = open_dataset(d_img), b = open_dataset(d_vid);
  EXPECT_TRUE(a.warnings.empty());
  EXPECT_TRUE(b.warnings.empty());
  ASSERT_EQ(a.frame_count, 4);
  ASSERT_EQ(b.frame_count, 4);
  EXPECT_TRUE(fs::is_regular_file(b.cameras[0].source->path()));
  const auto oa = run_all(a), ob = run_all(b);
  for (size_t c = 0; c < 2; ++c)
    for (size_t f = 0; f < 4; ++f) {
      ASSERT_TRUE(oa[c][f].delta);
      ASSERT_TRUE(ob[c][f].delta) << "video camera " << c << " frame " << f;
      EXPECT_LT(testing::corner_rms(oa[c][f].corners_px, truth[c][f]), 0.1);
      for (size_t k = 0; k < 4; ++k)
        EXPECT_LT(cv::norm(oa[c][f].corners_px[k] - ob[c][f].corners_px[k]), 0.5)
            << "camera " << c << " frame " << f << " corner " << k;
    }
  // random access backwards in a video re-reads the right frame
  const cv::Mat f3 = b.read(0, 3), f1 = b.read(0, 1), f1_again = b.read(0, 1);
  EXPECT_EQ(cv::norm(f1, f1_again, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(f1, f3, cv::NORM_INF), 0.0);
}

// A camera's image folder may hold any image netvmo reads (io::is_image_file), in any case of
// extension, mixed: the frames are the same pixels as the PNGs they were converted from.
TEST(Sources, ImageFolderReadsEveryImageFormat) {
  const auto dir = testing::fresh_dir("src_formats");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(1, 4, false));
  Dataset png = open_dataset(dir);
  ASSERT_EQ(png.frame_count, 4);
  std::vector<cv::Mat> want;
  for (int f = 0; f < 4; ++f) want.push_back(png.read(0, f).clone());
  const fs::path cam = png.cameras[0].source->path();
  const char* exts[] = {".TIF", ".bmp", ".pgm", ".tiff"};
  for (int f = 0; f < 4; ++f) {
    char stem[16];
    std::snprintf(stem, sizeof stem, "%06d", f);
    const fs::path from = cam / (std::string(stem) + ".png");
    ASSERT_TRUE(fs::exists(from)) << from;
    ASSERT_TRUE(cv::imwrite((cam / (stem + std::string(exts[f]))).string(),
                            cv::imread(from.string(), cv::IMREAD_UNCHANGED)));
    fs::remove(from);
  }
  Dataset mixed = open_dataset(dir);
  EXPECT_TRUE(mixed.warnings.empty());
  ASSERT_EQ(mixed.frame_count, 4);
  for (int f = 0; f < 4; ++f)
    EXPECT_EQ(cv::norm(mixed.read(0, f), want[static_cast<size_t>(f)], cv::NORM_INF), 0.0)
        << "frame " << f << " (" << exts[f] << ")";
}

// Other containers/codecs: lossless FFV1 in .avi gives identical detections; mp4v in .mp4
// (lossy) within 0.5 px.
TEST(Sources, Ffv1AviAndMp4VideosAgree) {
  const auto d_img = testing::fresh_dir("src_img2");
  testing::write_synth_dataset(d_img, testing::simple_dataset_spec(1, 3, false));
  Dataset a = open_dataset(d_img);
  const auto oa = run_all(a);
  for (const auto& [ext, fourcc, tol] :
       {std::tuple<std::string, std::string, double>{".avi", "FFV1", 1e-9},
        {".mp4", "mp4v", 0.5}}) {
    auto spec = testing::simple_dataset_spec(1, 3, true);
    spec.video_ext = ext;
    spec.video_fourcc = fourcc;
    const auto dir = testing::fresh_dir("src_" + fourcc);
    testing::write_synth_dataset(dir, spec);
    Dataset b = open_dataset(dir);
    EXPECT_EQ(b.cameras[0].source->path().extension(), ext);
    ASSERT_EQ(b.frame_count, 3) << fourcc;
    const auto ob = run_all(b);
    for (size_t f = 0; f < 3; ++f) {
      ASSERT_TRUE(ob[0][f].delta) << fourcc << " frame " << f;
      for (size_t k = 0; k < 4; ++k)
        EXPECT_LE(cv::norm(oa[0][f].corners_px[k] - ob[0][f].corners_px[k]), tol)
            << fourcc << " frame " << f << " corner " << k;
    }
  }
}

TEST(Sources, MissingFrameIsBlindNotShifted) {
  const auto dir = testing::fresh_dir("src_missing");
  const auto truth = testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 4));
  fs::remove(dir / "cam_1" / "000001.png");
  Dataset ds = open_dataset(dir);
  EXPECT_EQ(ds.frame_count, 4);
  EXPECT_TRUE(any_warning_contains(ds, "cam_1", "missing frame")) << ds.warnings.size();
  EXPECT_TRUE(ds.read(0, 1).empty());
  EXPECT_FALSE(ds.read(1, 1).empty());
  // frames after the gap are still the right frames
  const auto o = run_all(ds);
  EXPECT_FALSE(o[0][1].delta);
  for (size_t f : {0u, 2u, 3u}) {
    ASSERT_TRUE(o[0][f].delta);
    EXPECT_LT(testing::corner_rms(o[0][f].corners_px, truth[0][f]), 0.1) << "frame " << f;
  }
}

TEST(Sources, ShorterCameraBlindAfterItsLastFrame) {
  const auto dir = testing::fresh_dir("src_short");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 3));
  fs::remove(dir / "cam_2" / "000002.png");
  Dataset ds = open_dataset(dir);
  EXPECT_EQ(ds.frame_count, 3);
  EXPECT_TRUE(any_warning_contains(ds, "camera 2", "blind from frame 2"));
  EXPECT_TRUE(ds.read(1, 2).empty());
  EXPECT_FALSE(ds.read(0, 2).empty());
}

TEST(Sources, FramesKeyBoundsTheDataset) {
  const auto dir = testing::fresh_dir("src_frames");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(1, 3));
  { std::ofstream(dir / "network.yaml", std::ios::app) << "frames: 2\n"; }
  Dataset ds = open_dataset(dir);
  EXPECT_EQ(ds.frame_count, 2);
  EXPECT_TRUE(any_warning_contains(ds, "camera 1", "ignored"));
  EXPECT_TRUE(ds.read(0, 2).empty());
}

TEST(Sources, NonNumericNamesInSortedOrder) {
  const auto dir = testing::fresh_dir("src_names");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(1, 3));
  fs::rename(dir / "cam_1" / "000000.png", dir / "cam_1" / "a.png");
  fs::rename(dir / "cam_1" / "000001.png", dir / "cam_1" / "b.png");
  fs::rename(dir / "cam_1" / "000002.png", dir / "cam_1" / "c.png");
  const cv::Mat c = cv::imread((dir / "cam_1" / "c.png").string(), cv::IMREAD_GRAYSCALE);
  Dataset ds = open_dataset(dir);
  EXPECT_EQ(ds.frame_count, 3);
  EXPECT_EQ(cv::norm(ds.read(0, 2), c, cv::NORM_INF), 0.0);
  EXPECT_EQ(ds.cameras[0].source->frame_name(2), (dir / "cam_1" / "c.png").string());
}

TEST(Sources, CorruptImageNamesFileOthersUnaffected) {
  const auto dir = testing::fresh_dir("src_corrupt");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 2));
  const fs::path bad = dir / "cam_2" / "000001.png";
  { std::ofstream(bad, std::ios::binary) << "\x89PNG garbage garbage garbage"; }
  Dataset ds = open_dataset(dir);
  expect_input_error([&] { ds.read(1, 1); }, {bad.string()});
  EXPECT_FALSE(ds.read(0, 1).empty());
  EXPECT_FALSE(ds.read(1, 0).empty());
}

TEST(Sources, DatasetErrorsNameTheFile) {
  const auto dir = testing::fresh_dir("src_errors");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 1));
  // missing calibration
  fs::rename(dir / "calib" / "cam_2.yaml", dir / "cam_2.yaml.bak");
  expect_input_error([&] { open_dataset(dir); },
                     {(dir / "calib" / "cam_2.yaml").string(), "camera 2"});
  fs::rename(dir / "cam_2.yaml.bak", dir / "calib" / "cam_2.yaml");
  // no frames for a declared camera
  fs::rename(dir / "cam_2", dir / "frames_2");
  expect_input_error([&] { open_dataset(dir); }, {"cam_2", "camera 2"});
  // both a folder and a video
  fs::rename(dir / "frames_2", dir / "cam_2");
  { std::ofstream(dir / "cam_2.avi") << "x"; }
  expect_input_error([&] { open_dataset(dir); }, {"cam_2.avi", "both"});
  fs::remove(dir / "cam_2.avi");
  // unreadable video
  fs::rename(dir / "cam_2", dir / "frames_2");
  { std::ofstream(dir / "cam_2.avi") << "not a video at all"; }
  expect_input_error([&] { open_dataset(dir); }, {"cam_2.avi"});
  fs::remove(dir / "cam_2.avi");
  fs::rename(dir / "frames_2", dir / "cam_2");
  // image size differs from the calibration
  cv::imwrite((dir / "cam_1" / "000000.png").string(), cv::Mat(100, 120, CV_8UC1, cv::Scalar(0)));
  Dataset ds = open_dataset(dir);
  expect_input_error([&] { ds.read(0, 0); }, {"000000.png", "120x100", "cam_1.yaml"});
  // two files with the same frame number
  cv::imwrite((dir / "cam_1" / "0.png").string(), cv::Mat(100, 120, CV_8UC1, cv::Scalar(0)));
  expect_input_error([&] { open_dataset(dir); }, {"same frame number"});
  fs::remove(dir / "cam_1" / "0.png");
  // an undeclared camera folder is a warning, not an error
  fs::create_directories(dir / "cam_9");
  EXPECT_TRUE(any_warning_contains(open_dataset(dir), "cam_9", "not in network.yaml"));
  // missing dataset / network.yaml
  expect_input_error([&] { open_dataset(dir / "nope"); }, {"nope"});
  fs::remove(dir / "network.yaml");
  expect_input_error([&] { open_dataset(dir); }, {"network.yaml"});
}

// timestamps.csv gives each image its time; a camera it does not list runs on frame / its own
// fps (network.yaml's per-camera `fps`), and the dataset says so in a note.
TEST(Sources, TimestampsAndPerCameraFps) {
  const auto dir = testing::fresh_dir("src_times");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 4));
  {
    Dataset ds = open_dataset(dir);
    ASSERT_EQ(ds.notes.size(), 2u);  // one per camera
    EXPECT_NE(ds.notes[0].find("no " + (dir / "timestamps.csv").string() + ": camera 1"),
              std::string::npos);
    EXPECT_NE(ds.notes[1].find("camera 2: its times are frame index / its fps"), std::string::npos);
    EXPECT_DOUBLE_EQ(ds.frame_time(1, 3), 3.0 / ds.network.fps);
  }
  auto net = load_network_config(dir / "network.yaml");
  net.cameras[1].fps = net.fps / 2;  // camera 2 at half the rate: its 4 images span 8 frames
  { std::ofstream(dir / "network.yaml") << network_yaml(net); }
  {
    std::ofstream(dir / "timestamps.csv")
        << "camera,frame,t\n1,0,10.5\n1,2,10.6\n1,1,10.55\n1,3,10.7\n";
  }
  Dataset ds = open_dataset(dir);
  EXPECT_TRUE(ds.warnings.empty());  // camera 2 is not "short": it runs on its own clock
  EXPECT_EQ(ds.frame_count, 4);
  EXPECT_EQ(ds.camera_frame_count(0), 4);
  EXPECT_EQ(ds.camera_frame_count(1), 4);
  EXPECT_DOUBLE_EQ(ds.frame_time(0, 1), 10.55);  // rows in any order
  EXPECT_DOUBLE_EQ(ds.frame_time(0, 3), 10.7);
  EXPECT_DOUBLE_EQ(ds.frame_time(1, 3), 3.0 / (net.fps / 2));
  EXPECT_EQ(ds.network.camera_fps(1), net.fps / 2);
  ASSERT_EQ(ds.notes.size(), 1u);
  EXPECT_NE(ds.notes[0].find("lists no image of camera 2"), std::string::npos);
  // A camera's process reads the other cameras' times too (without their images).
  EXPECT_DOUBLE_EQ(open_dataset(dir, 2).frame_time(0, 2), 10.6);
}

// One clock or not (what `run` and lock-step need): frame / fps everywhere; the same listed
// times, a camera blind after its last image included; a time that differs; an own fps.
TEST(Sources, ClockMismatchNamesTheCameras) {
  const auto dir = testing::fresh_dir("src_clock");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 3));
  EXPECT_FALSE(clock_mismatch(*open_dataset_source(dir)));
  fs::remove(dir / "cam_2" / "000002.png");  // camera 2 is blind at frame 2
  {
    std::ofstream(dir / "timestamps.csv")
        << "camera,frame,t\n1,0,5\n1,1,5.1\n1,2,5.2\n2,0,5\n2,1,5.1\n";
  }
  EXPECT_FALSE(clock_mismatch(*open_dataset_source(dir)));
  {
    std::ofstream(dir / "timestamps.csv")
        << "camera,frame,t\n1,0,5\n1,1,5.1\n1,2,5.2\n2,0,5\n2,1,5.15\n";
  }
  const auto m = clock_mismatch(*open_dataset_source(dir));
  ASSERT_TRUE(m);
  EXPECT_NE(m->find("frame 1 is at t = 5.1 s for camera 1 but 5.15 s for camera 2"),
            std::string::npos)
      << *m;
  fs::remove(dir / "timestamps.csv");  // camera 1 on frame / fps, camera 2 on its own
  auto net = load_network_config(dir / "network.yaml");
  net.cameras[1].fps = 2 * net.fps;
  { std::ofstream(dir / "network.yaml") << network_yaml(net); }
  const auto f = clock_mismatch(*open_dataset_source(dir));
  ASSERT_TRUE(f);
  EXPECT_NE(f->find("camera 2 runs at"), std::string::npos) << *f;
}

// Bad timestamps.csv and per-camera fps: one line naming the file, the line and the column.
TEST(Sources, TimestampErrorsNameFileLineAndColumn) {
  const auto dir = testing::fresh_dir("src_times_bad");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 3));
  const auto file = (dir / "timestamps.csv").string();
  const auto with = [&](const std::string& rows) {
    std::ofstream(dir / "timestamps.csv") << "camera,frame,t\n" << rows;
  };
  const std::string cam2 = "2,0,0\n2,1,0.1\n2,2,0.2\n";
  with("1,0,0\n1,1,abc\n1,2,0.2\n" + cam2);
  expect_input_error([&] { open_dataset(dir); }, {file + ":3", "t:", "abc"});
  with("1,0,0\n1,1,0.2\n1,2,0.1\n" + cam2);  // backwards
  expect_input_error([&] { open_dataset(dir); }, {file + ":4", "t:", "not after its frame 1"});
  with("1,0,0\n1,1,0.1\n1,2,0.1\n" + cam2);  // a time repeated
  expect_input_error([&] { open_dataset(dir); },
                     {file + ":4", "t:", "frame 2 at t = 0.1 s is not after its frame 1"});
  with("1,0,0\n1,1,0.1\n1,2,0.2\n2,1,0.1\n2,0,0.15\n2,2,0.2\n");  // backwards, rows out of order
  expect_input_error([&] { open_dataset(dir); },
                     {file + ":5", "t:", "camera 2 frame 1", "not after its frame 0"});
  with("1,0,0\n1,1,inf\n1,2,0.2\n" + cam2);  // not finite
  expect_input_error([&] { open_dataset(dir); }, {file + ":3", "t:", "expected a number"});
  with("1,0,0\n1,1,0.1\n1,1,0.15\n1,2,0.2\n" + cam2);  // a frame twice
  expect_input_error([&] { open_dataset(dir); }, {file + ":4", "frame:", "second row"});
  with("1,0,0\n1,1,0.1\n1,2,0.2\n" + cam2 + "7,0,0\n");  // unknown camera
  expect_input_error([&] { open_dataset(dir); }, {file + ":8", "camera:", "not in network.yaml"});
  with("1,0,0\n1,1,0.1\n1,2,0.2\n1,3,0.3\n" + cam2);  // past the last image
  expect_input_error([&] { open_dataset(dir); }, {file + ":5", "frame:", "past the last image"});
  with("1,0,0\n1,2,0.2\n" + cam2);  // an image without a time
  expect_input_error([&] { open_dataset(dir); }, {file, "camera 1", "no row for frame 1"});
  with("1,-1,0\n");
  expect_input_error([&] { open_dataset(dir); }, {file + ":2", "frame:"});
  { std::ofstream(dir / "timestamps.csv") << "frame,camera,t\n"; }
  expect_input_error([&] { open_dataset(dir); }, {file + ":1", "header"});
  fs::remove(dir / "timestamps.csv");
  auto net = load_network_config(dir / "network.yaml");
  net.cameras[0].fps = -2;
  { std::ofstream(dir / "network.yaml") << network_yaml(net); }
  expect_input_error([&] { open_dataset(dir); }, {"network.yaml", "cameras[0].fps", "positive"});
}

// cameras.csv gives each camera image its believed pose; a camera it does not list is static at
// its network.yaml pose (a note); rows that move make the source a moving-camera one.
TEST(Sources, CameraPosesGiveTheBelievedPosePerFrame) {
  const auto dir = testing::fresh_dir("src_poses");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 3));
  EXPECT_FALSE(open_dataset_source(dir)->cameras_move());
  {
    // Rows that repeat network.yaml's poses (what `render` writes for static cameras) read back
    // to exactly those poses: the cameras are static.
    const auto net = load_network_config(dir / "network.yaml");
    std::ofstream f(dir / "cameras.csv");
    f << kCameraPosesHeader << "\n";
    for (int k = 0; k < 3; ++k)
      for (const auto& c : net.cameras)
        f << format_camera_pose_row(c.id, k, k / net.fps, c.g_wi) << "\n";
  }
  EXPECT_FALSE(open_dataset_source(dir)->cameras_move());
  {
    std::ofstream(dir / "cameras.csv") << kCameraPosesHeader << "\n"
                                       << "1,2,0.2,0.3,0,1,0,0,0.1\n"
                                       << "1,0,0,0.1,0,1,0,0,0\n"
                                       << "1,1,0.1,0.2,0,1,0,0,0.05\n";
  }
  const auto src = open_dataset_source(dir);
  EXPECT_TRUE(src->cameras_move());
  EXPECT_TRUE(src->camera_believed(0, 2).isApprox(obs::make_pose({0.3, 0, 1}, {0, 0, 0.1})));
  EXPECT_TRUE(src->camera_believed(0, 1).isApprox(obs::make_pose({0.2, 0, 1}, {0, 0, 0.05})));
  EXPECT_TRUE(src->camera_believed(1, 1).isApprox(src->network().cameras[1].g_wi, 0.0));
  bool noted = false;
  for (const auto& n : src->notes()) noted |= n.find("lists no pose of camera 2") != n.npos;
  EXPECT_TRUE(noted);
  // Netvmo sweep, launch and node refuse moving cameras with one line.
  expect_input_error([&] { require_static_cameras(*src, "netvmo launch"); },
                     {"cameras.csv", "netvmo launch", "static cameras at their network.yaml"});
}

// truth_cameras.csv: per frame (what `render` writes now) or, in older datasets, one static pose
// per camera, still read.
TEST(Sources, CameraTruthPerFrameOrStatic) {
  const auto dir = testing::fresh_dir("src_cam_truth");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 3));
  { std::ofstream(dir / "target.csv") << kTargetHeader << "\n0,0,0,0,2,0,0,0\n"; }
  {
    std::ofstream(dir / "truth_cameras.csv") << kTruthCamerasHeader << "\n1,0,0,0,0,0,0\n"
                                             << "2,1,0,0,0,0,0.5\n";
  }
  const auto old = open_dataset_source(dir);
  ASSERT_TRUE(old->camera_truth(1, 2));
  EXPECT_TRUE(old->camera_truth(1, 2)->isApprox(obs::make_pose({1, 0, 0}, {0, 0, 0.5})));
  EXPECT_TRUE(old->camera_truth(1, 0)->isApprox(*old->camera_truth(1, 2), 0.0));
  {
    std::ofstream(dir / "truth_cameras.csv") << kCameraPosesHeader << "\n"
                                             << "1,0,0,0,0,0,0,0,0\n1,1,0.1,0.1,0,0,0,0,0\n"
                                             << "2,0,0,1,0,0,0,0,0\n2,1,0.1,1,0,0,0,0,0.1\n";
  }
  const auto moving = open_dataset_source(dir);
  EXPECT_TRUE(moving->camera_truth(0, 1)->isApprox(obs::make_pose({0.1, 0, 0}, {0, 0, 0})));
  EXPECT_TRUE(moving->camera_truth(1, 1)->isApprox(obs::make_pose({1, 0, 0}, {0, 0, 0.1})));
  EXPECT_FALSE(moving->camera_truth(1, 2));  // no true pose: no evaluation there
  { std::ofstream(dir / "truth_cameras.csv") << kCameraPosesHeader << "\n1,0,0,0,0,0,0,0,0\n"; }
  expect_input_error([&] { open_dataset_source(dir); },
                     {"truth_cameras.csv", "no row for camera 2"});
}

// Bad cameras.csv: one line naming the file, the line and the column, or the camera and the
// frame that has no row.
TEST(Sources, CameraPoseErrorsNameFileLineAndColumn) {
  const auto dir = testing::fresh_dir("src_poses_bad");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(2, 3));
  const auto file = (dir / "cameras.csv").string();
  const auto with = [&](const std::string& rows) {
    std::ofstream(dir / "cameras.csv") << kCameraPosesHeader << "\n" << rows;
  };
  const std::string cam2 = "2,0,0,0,0,1,0,0,0\n2,1,0.1,0,0,1,0,0,0\n2,2,0.2,0,0,1,0,0,0\n";
  with("1,0,0,0,0,1,0,0,0\n1,1,0.1,0,0,1,0,0,0\n1,2,0.2,0,0,1,0,0,0\n" + cam2);
  EXPECT_NO_THROW(open_dataset(dir));
  with("1,0,0,0,0,1,0,0,0\n1,2,0.2,0,0,1,0,0,0\n" + cam2);  // a frame missing in between
  expect_input_error([&] { open_dataset(dir); }, {file, "camera 1", "no row for frame 1"});
  with("1,0,0,0,0,1,0,0,0\n1,1,0.1,0,0,1,0,0,0\n" + cam2);  // the last frame missing
  expect_input_error([&] { open_dataset(dir); }, {file, "camera 1", "no row for frame 2"});
  with("1,0,0,0,0,1,0,0,0\n1,1,0.1,0,nan,1,0,0,0\n1,2,0.2,0,0,1,0,0,0\n" + cam2);
  expect_input_error([&] { open_dataset(dir); }, {file + ":3", "py:", "expected a number"});
  with("1,0,0,0,0,1,0,0,0\n1,1,0.1,0,0,1,0,inf,0\n1,2,0.2,0,0,1,0,0,0\n" + cam2);
  expect_input_error([&] { open_dataset(dir); }, {file + ":3", "ry:", "expected a number"});
  with("1,0,0,0,0,1,0,0,0\n1,1,0.1,0,0,1,0,0,0\n1,1,0.1,0,0,1,0,0,0\n1,2,0.2,0,0,1,0,0,0\n" +
       cam2);  // a repeated row
  expect_input_error([&] { open_dataset(dir); }, {file + ":4", "frame:", "second row"});
  with(cam2 + "7,0,0,0,0,1,0,0,0\n");  // unknown camera
  expect_input_error([&] { open_dataset(dir); }, {file + ":5", "camera:", "not in network.yaml"});
  with(cam2 + "2,3,0.3,0,0,1,0,0,0\n");  // past the last image
  expect_input_error([&] { open_dataset(dir); }, {file + ":5", "frame:", "past the last image"});
  with("0,0,0,0,0,1,0,0,0\n");
  expect_input_error([&] { open_dataset(dir); }, {file + ":2", "camera:", "positive"});
  with("1,0,0,0,0,1,0,0\n");
  expect_input_error([&] { open_dataset(dir); }, {file + ":2", "expected 9 fields"});
  { std::ofstream(dir / "cameras.csv") << "camera,px,py,pz,rx,ry,rz\n"; }
  expect_input_error([&] { open_dataset(dir); }, {file + ":1", "header"});
}

TEST(Sources, XmlCalibrationsInDataset) {
  const auto dir = testing::fresh_dir("src_xml");
  testing::write_synth_dataset(dir, testing::simple_dataset_spec(1, 1));
  const Calibration c = load_calibration_opencv(dir / "calib" / "cam_1.yaml");
  fs::remove(dir / "calib" / "cam_1.yaml");
  // An OpenCV FileStorage .xml is recognised as such (ViSP XML is tested in test_io).
  cv::FileStorage fsw((dir / "calib" / "cam_1.xml").string(), cv::FileStorage::WRITE);
  fsw << "image_width" << c.width << "image_height" << c.height << "camera_matrix" << cv::Mat(c.K)
      << "distortion_coefficients" << cv::Mat(cv::Matx<double, 1, 5>(c.dist.val));
  fsw.release();
  Dataset ds = open_dataset(dir);
  EXPECT_EQ(ds.cameras[0].calib.K(0, 0), c.K(0, 0));
  EXPECT_EQ(ds.cameras[0].calib.dist[0], c.dist[0]);
  // ViSP XML written by vpXmlParserCamera, camera name cam_1
  fs::remove(dir / "calib" / "cam_1.xml");
  vpCameraParameters cam;
  cam.initPersProjWithoutDistortion(c.K(0, 0), c.K(1, 1), c.K(0, 2), c.K(1, 2));
  vpXmlParserCamera parser;
  ASSERT_EQ(parser.save(cam, (dir / "calib" / "cam_1.xml").string(), "cam_1", 640, 480),
            vpXmlParserCamera::SEQUENCE_OK);
  Dataset dv = open_dataset(dir);
  EXPECT_EQ(dv.cameras[0].calib.K(1, 2), c.K(1, 2));
  EXPECT_EQ(dv.cameras[0].calib.width, 640);
  FrontEnd fe;
  EXPECT_TRUE(fe.observe(dv.read(0, 0), dv.cameras[0].calib).delta);
}

}  // namespace
}  // namespace netvmo
