// The dataset writer behind `netvmo render`: a small scenario (2 cameras, 3 frames, 80x60)
// produces exactly the documented files with the documented headers and node names.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "netvmo/pipeline/io/dataset_writer.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/pipeline/sources/network_source.hpp"
#include "netvmo/pipeline/sources/render_source.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

// The scenario, kept as a data file next to this test.
const std::string kScenario =
    netvmo::test::slurp(fs::path(NETVMO_SOURCE_DIR) / "tests/pipeline/data/writer_scenario.yaml");

std::vector<std::string> lines(const fs::path& f) {
  std::ifstream in(f);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

int fields(const std::string& line) {
  return int(std::count(line.begin(), line.end(), ',')) + 1;
}

TEST(DatasetWriter, WritesDocumentedLayout) {
  const fs::path dir = netvmo::test::scratch_dir("dataset_writer");
  std::ofstream(dir / "scenario.yaml") << kScenario;
  const auto scene = netvmo::io::load_render_scenario(dir / "scenario.yaml");
  netvmo::render::Renderer r(scene);
  const fs::path out = dir / "dataset";
  netvmo::io::DatasetSettings opt;
  opt.progress = false;
  const auto summary = netvmo::io::write_dataset(r, out, opt);
  EXPECT_EQ(summary.frames, 3);
  ASSERT_EQ(summary.cameras.size(), 2u);
  EXPECT_EQ(summary.cameras[0].frames_in_fov, 3);   // camera 3 faces the tag
  EXPECT_EQ(summary.cameras[1].frames_visible, 0);  // camera 7 sees its back

  for (int id : {3, 7})
    for (int f = 0; f < 3; ++f) {
      char name[16];
      std::snprintf(name, sizeof name, "%06d.png", f);
      const cv::Mat img =
          cv::imread((out / ("cam_" + std::to_string(id)) / name).string(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(img.empty()) << id << " " << name;
      EXPECT_EQ(img.type(), CV_8UC1);
      EXPECT_EQ(img.cols, 80);
      EXPECT_EQ(img.rows, 60);
    }
  EXPECT_FALSE(fs::exists(out / "cam_3" / "000003.png"));

  {
    cv::FileStorage fsr((out / "calib" / "cam_3.yaml").string(), cv::FileStorage::READ);
    ASSERT_TRUE(fsr.isOpened());
    EXPECT_EQ(int(fsr["image_width"]), 80);
    EXPECT_EQ(int(fsr["image_height"]), 60);
    cv::Mat K, d;
    fsr["camera_matrix"] >> K;
    fsr["distortion_coefficients"] >> d;
    ASSERT_EQ(K.rows, 3);
    ASSERT_EQ(K.cols, 3);
    EXPECT_DOUBLE_EQ(K.at<double>(0, 0), 70);
    EXPECT_DOUBLE_EQ(K.at<double>(1, 1), 71);
    EXPECT_DOUBLE_EQ(K.at<double>(0, 2), 39);
    EXPECT_DOUBLE_EQ(K.at<double>(1, 2), 29);
    EXPECT_DOUBLE_EQ(K.at<double>(2, 2), 1);
    ASSERT_EQ(d.rows, 1);
    ASSERT_EQ(d.cols, 5);
    cv::FileStorage fs7((out / "calib" / "cam_7.yaml").string(), cv::FileStorage::READ);
    fs7["distortion_coefficients"] >> d;
    EXPECT_DOUBLE_EQ(d.at<double>(0, 0), -0.05);
    EXPECT_DOUBLE_EQ(d.at<double>(0, 3), 0.002);
  }

  {
    const YAML::Node n = YAML::LoadFile((out / "network.yaml").string());
    EXPECT_DOUBLE_EQ(n["fps"].as<double>(), 15);
    EXPECT_EQ(n["target"]["family"].as<std::string>(), "tag36h11");
    EXPECT_EQ(n["target"]["id"].as<int>(), 1);
    EXPECT_DOUBLE_EQ(n["target"]["size"].as<double>(), 0.2);
    ASSERT_EQ(n["cameras"].size(), 2u);
    EXPECT_EQ(n["cameras"][0]["id"].as<int>(), 3);
    EXPECT_EQ(n["cameras"][1]["id"].as<int>(), 7);
    // Believed pose: true eye + dp.
    const auto p = n["cameras"][0]["p_wi"].as<std::vector<double>>();
    ASSERT_EQ(p.size(), 3u);
    EXPECT_NEAR(p[0], 0.01, 1e-9);
    EXPECT_NEAR(p[1], -1.48, 1e-9);
    EXPECT_NEAR(p[2], 1.03, 1e-9);
    EXPECT_EQ(n["cameras"][0]["r_wi"].as<std::vector<double>>().size(), 3u);
    ASSERT_EQ(n["edges"].size(), 1u);
    EXPECT_EQ(n["edges"][0].as<std::vector<int>>(), (std::vector<int>{3, 7}));
  }

  {
    const auto t = lines(out / "truth.csv");
    ASSERT_EQ(t.size(), 1u + 3 * 2);
    EXPECT_EQ(t[0], "frame,t,camera,in_fov,visible_fraction,u0,v0,u1,v1,u2,v2,u3,v3");
    for (size_t i = 1; i < t.size(); ++i) EXPECT_EQ(fields(t[i]), 13) << t[i];
    EXPECT_EQ(t[1].rfind("0,0.000000,3,1,1.000000,", 0), 0u) << t[1];
    // Camera 7 looks at the back of the tag: inside its field of view, but not visible.
    EXPECT_EQ(t[2].rfind("0,0.000000,7,1,0.000000,", 0), 0u) << t[2];
    const auto g = lines(out / "target.csv");
    ASSERT_EQ(g.size(), 4u);
    EXPECT_EQ(g[0], "frame,t,px,py,pz,rx,ry,rz");
    EXPECT_EQ(fields(g[2]), 8);
    // Frame 2 at 15 fps: t = 0.1333 s, moved 0.3 m/s along the tag's x (world x).
    std::stringstream row(g[3]);
    std::string cell;
    std::vector<double> v;
    while (std::getline(row, cell, ',')) v.push_back(std::stod(cell));
    EXPECT_NEAR(v[1], 2.0 / 15, 1e-6);
    EXPECT_NEAR(v[2], 0.3 * 2 / 15, 1e-6);
  }
  // Rewriting with fewer frames removes the old run's extra images.
  opt.frames = 2;
  netvmo::io::write_dataset(r, out, opt);
  EXPECT_TRUE(fs::exists(out / "cam_7" / "000001.png"));
  EXPECT_FALSE(fs::exists(out / "cam_7" / "000002.png"));
  EXPECT_EQ(lines(out / "truth.csv").size(), 1u + 2 * 2);
  // No temporary files left behind.
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_EQ(e.path().string().find(".partial"), std::string::npos) << e.path();
}

// sensor.jpeg_quality: the camera's frames are JPEG files at that quality, which the dataset
// reader takes, and the live renderer gives the same decoded bytes.
TEST(DatasetWriter, JpegFramesAtTheSensorsQuality) {
  const fs::path dir = netvmo::test::scratch_dir("dataset_writer_jpeg");
  std::ofstream(dir / "scenario.yaml")
      << netvmo::test::replaced(kScenario, "fx: 70, fy: 71, cx: 39, cy: 29}",
                                "fx: 70, fy: 71, cx: 39, cy: 29}\n    sensor: {jpeg_quality: 60}");
  const auto scene = netvmo::io::load_render_scenario(dir / "scenario.yaml");
  ASSERT_EQ(scene.cameras[0].sensor.jpeg_quality, 60);
  netvmo::render::Renderer r(scene);
  netvmo::io::DatasetSettings opt;
  opt.progress = false;
  netvmo::io::write_dataset(r, dir / "dataset", opt);
  EXPECT_TRUE(fs::exists(dir / "dataset" / "cam_3" / "000001.jpg"));
  EXPECT_FALSE(fs::exists(dir / "dataset" / "cam_3" / "000001.png"));
  EXPECT_TRUE(fs::exists(dir / "dataset" / "cam_7" / "000001.png"));
  auto recorded = netvmo::sources::open_dataset_source(dir / "dataset");
  auto live = netvmo::sources::make_render_source(scene);
  const cv::Mat a = recorded->read(0, 1), b = live->read(0, 1);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::countNonZero(a != b), 0);
  EXPECT_GT(cv::countNonZero(a != r.render(0, 1)), 0);  // compressed, not the rendered bytes
}

}  // namespace
