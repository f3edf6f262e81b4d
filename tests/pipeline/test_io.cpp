// Calibration, network.yaml and CSV readers: valid files load, bad ones give an InputError
// naming the file (and the key or line).
#include <gtest/gtest.h>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpXmlParserCamera.h>
#include <algorithm>
#include <fstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/io/number_text.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
using namespace io;
using namespace frontend;
namespace fs = std::filesystem;

using test::expect_input_error;

void write(const fs::path& p, const std::string& s) {
  std::ofstream(p) << s;
}

TEST(Calibration, OpenCvYamlRoundTrip) {
  const auto dir = testing::fresh_dir("calib_yaml");
  const Calibration c = testing::test_calibration(true);
  save_calibration_opencv(dir / "cam_1.yaml", c);
  const Calibration r = load_calibration_opencv(dir / "cam_1.yaml");
  EXPECT_EQ(r.width, 640);
  EXPECT_EQ(r.height, 480);
  EXPECT_LT(cv::norm(cv::Mat(r.K), cv::Mat(c.K)), 1e-12);
  EXPECT_LT(cv::norm(r.dist - c.dist), 1e-12);
  EXPECT_EQ(r.source, (dir / "cam_1.yaml").string());
}

TEST(Calibration, OpenCvFileErrorsNameFileAndNode) {
  const auto dir = testing::fresh_dir("calib_err");
  expect_input_error([&] { load_calibration_opencv(dir / "nope.yaml"); },
                     {"nope.yaml", "not found"});
  write(dir / "a.yaml",
        "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
        "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
        "  data: [600, 0, 320, 0, 600, 240, 0, 0, 1]\n");
  expect_input_error([&] { load_calibration_opencv(dir / "a.yaml"); },
                     {"a.yaml", "distortion_coefficients"});
  write(dir / "b.yaml",
        "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
        "camera_matrix: !!opencv-matrix\n  rows: 2\n  cols: 2\n  dt: d\n"
        "  data: [600, 0, 0, 600]\n"
        "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 5\n"
        "  dt: d\n  data: [0, 0, 0, 0, 0]\n");
  expect_input_error([&] { load_calibration_opencv(dir / "b.yaml"); }, {"b.yaml", "camera_matrix"});
  write(dir / "c.yaml", "this is : not : yaml [");
  expect_input_error([&] { load_calibration_opencv(dir / "c.yaml"); }, {"c.yaml"});
}

// Found by fuzzing (tests/fuzz/corpus/calibration_opencv/cols_not_a_number_oom): OpenCV allocates
// rows x cols before reading the data, so the declared size is checked first.
TEST(Calibration, OpenCvMatrixSizeCheckedBeforeReading) {
  const auto dir = testing::fresh_dir("calib_size");
  const std::string K =
      "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
      "  data: [600, 0, 320, 0, 600, 240, 0, 0, 1]\n";
  const std::string head = "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  write(dir / "a.yaml", head + K +
                            "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: /\n"
                            "  dt: d\n  data: [0, 0, 0, 0, 0]\n");
  expect_input_error([&] { load_calibration_opencv(dir / "a.yaml"); },
                     {"a.yaml", "distortion_coefficients", "rows and cols must be integers"});
  write(dir / "b.yaml", head +
                            "camera_matrix: !!opencv-matrix\n  rows: 100000\n  cols: 100000\n"
                            "  dt: d\n  data: [1]\n");
  expect_input_error([&] { load_calibration_opencv(dir / "b.yaml"); },
                     {"b.yaml", "camera_matrix", "at most 9 numbers", "rows 100000 x cols 100000"});
  // corpus calibration_opencv/empty_key_length_error: OpenCV's YAML parser throws
  // std::length_error (not a cv::Exception) on this line; it is now refused before OpenCV sees
  // it, as not well-formed YAML.
  write(dir / "c.yaml", head + K +
                            "distortion_coefficients: !!opencv-matrix\n  rows: 1\n"
                            "  cols: 5\n   :t: d\n  * data: [0, 0, 0, 0, 0]\n");
  expect_input_error([&] { load_calibration_opencv(dir / "c.yaml"); },
                     {"c.yaml:13", "not well-formed YAML"});
  // corpus calibration_opencv/nul_byte_hang: OpenCV's parser did not return on this file.
  write(dir / "d.yaml", std::string("%YAML:1.0\n cols:age_width:i640\nim") + '\0' +
                            "%YAML:1.0\n---\nimage_width: 640\n");
  expect_input_error([&] { load_calibration_opencv(dir / "d.yaml"); },
                     {"d.yaml", "not a text file"});
  // corpus calibration_opencv/document_marker_hang: OpenCV's parser did not return on a
  // document marker followed by text and a later line ending in "---" (both forms).
  write(dir / "e.yaml", "%YAML:1.0\n-----mage_width: v40\nim---\nimage_width: 640\n");
  expect_input_error([&] { load_calibration_opencv(dir / "e.yaml"); },
                     {"e.yaml:2", "'---' must stand alone"});
  write(dir / "f.yaml", "%YAML:1.0\n--- a: v\nb---\n");
  expect_input_error([&] { load_calibration_opencv(dir / "f.yaml"); },
                     {"f.yaml:2", "'---' must stand alone"});
  // corpus calibration_opencv/dedent_hang: OpenCV's parser did not return on a line dedented to
  // a column no enclosing line starts at (2 spaces under 3), followed by a line "-".
  write(dir / "g.yaml", "%YAML:1.0\n   rows: 6\n  1.0\n-\n");
  expect_input_error([&] { load_calibration_opencv(dir / "g.yaml"); },
                     {"g.yaml:3", "indentation of 2 spaces matches no enclosing line"});
  // corpus calibration_opencv/indented_root_hang: nor on an indented first key followed by a line
  // at column 0; and corpus dedent_hang_xml: the dedent in a file named .xml (OpenCV goes by the
  // "%YAML" content).
  write(dir / "i.yaml", "%YAML:1.0\n   cols: 3\n, %\n--)\n");
  expect_input_error([&] { load_calibration_opencv(dir / "i.yaml"); },
                     {"i.yaml:3", "indentation of 0 spaces matches no enclosing line"});
  write(dir / "j.xml", "%YAML:1.0\n   rows: 6\n  1.0\n-\n");
  expect_input_error([&] { load_calibration_opencv(dir / "j.xml"); },
                     {"j.xml:3", "indentation of 2 spaces matches no enclosing line"});
  // corpus calibration_opencv/bracket_in_key_hang: a '[' inside a key opens no flow collection,
  // so the dedent after it is still found (OpenCV's parser did not return on this file).
  write(dir / "k.yaml", "%YAML:1.0 !!%opex\n   rows: 6\n   cols\xdb[\xdb: 3\n  1.0\n--\n-\nim");
  expect_input_error([&] { load_calibration_opencv(dir / "k.yaml"); },
                     {"k.yaml:4", "indentation of 2 spaces matches no enclosing line"});
  // corpus calibration_opencv/flow_map_dedent_hang: a '{' opening a flow mapping that is never
  // closed, then a dedent (OpenCV's parser did not return): not well-formed YAML (yaml-cpp).
  write(dir / "l.yaml", "%YAML:1.0 !!opex\n   rows: 6\n   {ols: 3\n  1.0\n--\n-\nim");
  expect_input_error([&] { load_calibration_opencv(dir / "l.yaml"); },
                     {"l.yaml:", "not well-formed YAML"});
  // corpus calibration_opencv/scalar_root_hang: yaml-cpp reads this as one multi-line scalar,
  // OpenCV as keys and an unclosed flow mapping (it did not return): the top level must be a map.
  write(dir / "s.yaml", "%YAML:1.0 !!opex\n   rows:\x83\x83\x83 6\n   {ol:s 3\n  1.0\n--\n-\nim");
  expect_input_error([&] { load_calibration_opencv(dir / "s.yaml"); },
                     {"s.yaml", "top level is not a mapping"});
  // One document: a second '---', a '---' after the first key, or a '...' is refused.
  write(dir / "m.yaml", head + "---\n" + K);
  expect_input_error([&] { load_calibration_opencv(dir / "m.yaml"); },
                     {"m.yaml:5", "one YAML document expected"});
  write(dir / "n.yaml", "%YAML:1.0\nimage_width: 640\n---\n");
  expect_input_error([&] { load_calibration_opencv(dir / "n.yaml"); },
                     {"n.yaml:3", "one YAML document expected"});
  write(dir / "o.yaml", head + "...\n" + K);
  expect_input_error([&] { load_calibration_opencv(dir / "o.yaml"); },
                     {"o.yaml:5", "one YAML document expected"});
  // corpus calibration_opencv/xml_attribute_at_end_segv: OpenCV's XML parser dereferenced a
  // null pointer on a file ending after an attribute's '=' (also behind a quoted '>').
  write(dir / "p.xml", "<?xml version=");
  expect_input_error([&] { load_calibration_opencv(dir / "p.xml"); },
                     {"p.xml", "ends inside a tag"});
  write(dir / "q.xml", "<?xml version=\"1.0\"?>\n<opencv_storage>\n<a c=\">\" b=  \n");
  expect_input_error([&] { load_calibration_opencv(dir / "q.xml"); },
                     {"q.xml", "ends inside a tag"});
  write(dir / "r.xml", "<?xml version=\"1.0\"?>\n<opencv_storage>\n<!-- it's <a b=");
  expect_input_error([&] { load_calibration_opencv(dir / "r.xml"); },
                     {"r.xml", "ends inside a comment"});
  // What OpenCV writes still loads: a `data:` list continued on a line indented deeper than any
  // key, then a key back at column 0 (flow lines are not checked).
  write(dir / "h.yaml", head +
                            "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                            "   data: [ 600., 0., 320., 0., 600., 240., 0., 0.,\n       1. ]\n"
                            "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n"
                            "   dt: d\n   data: [ 0., 0., 0., 0., 0. ]\n");
  const Calibration h = load_calibration_opencv(dir / "h.yaml");
  EXPECT_EQ(h.K(0, 0), 600.0);
  EXPECT_EQ(h.K(2, 2), 1.0);
}

// A ROS camera_info file as ROS's camera_calibration writes it (monocular: identity
// rectification; P is the rectified images' matrix, different from K).
std::string ros_camera_info(const std::string& model = "plumb_bob",
                            const std::string& D = "[-0.12, 0.05, 0.0004, -0.0003, 0.0021]",
                            const std::string& R = "[1, 0, 0, 0, 1, 0, 0, 0, 1]",
                            const std::string& K = "[610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]",
                            const std::string& extra = "") {
  const int n = static_cast<int>(std::count(D.begin(), D.end(), ',')) + 1;
  return "image_width: 640\nimage_height: 480\ncamera_name: narrow_stereo\n"
         "camera_matrix:\n  rows: 3\n  cols: 3\n  data: " +
         K + "\ndistortion_model: " + model +
         "\ndistortion_coefficients:\n  rows: 1\n  cols: " + std::to_string(n) + "\n  data: " + D +
         "\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: " + R +
         "\nprojection_matrix:\n  rows: 3\n  cols: 4\n"
         "  data: [590.1, 0, 322.4, 0, 0, 596.3, 237.9, 0, 0, 0, 1, 0]\n" +
         extra;
}

// The same camera as a ROS camera_info and as an OpenCV FileStorage file: identical intrinsics.
TEST(Calibration, RosCameraInfoEqualsOpenCv) {
  const auto dir = testing::fresh_dir("calib_ros");
  write(dir / "ros.yaml", ros_camera_info());
  write(dir / "cv.yaml",
        "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
        "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
        "  data: [610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]\n"
        "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 5\n  dt: d\n"
        "  data: [-0.12, 0.05, 0.0004, -0.0003, 0.0021]\n");
  EXPECT_TRUE(looks_like_ros_camera_info(dir / "ros.yaml"));
  EXPECT_FALSE(looks_like_ros_camera_info(dir / "cv.yaml"));
  const Calibration r = load_calibration_ros(dir / "ros.yaml");
  const Calibration c = load_calibration_opencv(dir / "cv.yaml");
  EXPECT_EQ(r.width, c.width);
  EXPECT_EQ(r.height, c.height);
  EXPECT_EQ(cv::norm(cv::Mat(r.K), cv::Mat(c.K)), 0.0);
  EXPECT_EQ(cv::norm(r.dist - c.dist), 0.0);
  EXPECT_FALSE(r.is_rational());
  EXPECT_DOUBLE_EQ(r.K(1, 1), 605.5);
  EXPECT_DOUBLE_EQ(r.dist[4], 0.0021);
  EXPECT_EQ(r.source, (dir / "ros.yaml").string());
  // save_calibration_ros writes what load_calibration_ros reads, to the last bit.
  save_calibration_ros(dir / "saved.yaml", c, "cam_1");
  const Calibration s = load_calibration_ros(dir / "saved.yaml");
  EXPECT_EQ(cv::norm(cv::Mat(s.K), cv::Mat(c.K)), 0.0);
  EXPECT_EQ(cv::norm(s.dist - c.dist), 0.0);
}

// An OpenCV FileStorage file that also carries ROS's distortion_model key (as some converters
// write) is read as what it is, OpenCV's, with the key checked against its coefficients; the
// camera_info form of the same camera reads the same. The file's format is picked by content.
TEST(Calibration, OpenCvFileWithDistortionModelIsReadAsOpenCv) {
  const auto dir = testing::fresh_dir("calib_cv_model");
  const std::string cv_head =
      "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
      "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
      "  data: [610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]\n";
  const std::string cv_dist =
      "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 5\n  dt: d\n"
      "  data: [-0.12, 0.05, 0.0004, -0.0003, 0.0021]\n";
  write(dir / "cv.yaml", cv_head + "distortion_model: plumb_bob\n" + cv_dist);
  write(dir / "ros.yaml", ros_camera_info());
  const CalibrationFormat f = detect_yaml_calibration_format(dir / "cv.yaml");
  EXPECT_EQ(f.kind, CalibrationFormat::opencv) << f.why;
  EXPECT_NE(f.why.find("%YAML:1.0 (line 1)"), std::string::npos) << f.why;
  EXPECT_NE(f.why.find("distortion_model (line 10)"), std::string::npos) << f.why;
  EXPECT_FALSE(looks_like_ros_camera_info(dir / "cv.yaml"));
  EXPECT_EQ(detect_yaml_calibration_format(dir / "ros.yaml").kind,
            CalibrationFormat::ros_camera_info);
  const Calibration c = load_calibration_yaml(dir / "cv.yaml");
  const Calibration r = load_calibration_yaml(dir / "ros.yaml");
  EXPECT_EQ(c.width, r.width);
  EXPECT_EQ(c.height, r.height);
  EXPECT_EQ(cv::norm(cv::Mat(c.K), cv::Mat(r.K)), 0.0);
  EXPECT_EQ(cv::norm(c.dist - r.dist), 0.0);
  EXPECT_DOUBLE_EQ(c.dist[0], -0.12);
  EXPECT_FALSE(c.fisheye);
  // Without the header, the tag alone marks it as OpenCV's (whose parser then wants the
  // header, and the message says which format it was read as); equidistant makes it fisheye.
  const std::string tagged =
      "image_width: 640\nimage_height: 480\ndistortion_model: equidistant\n"
      "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
      "  data: [610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]\n"
      "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 4\n  dt: d\n"
      "  data: [0.1, -0.02, 0.003, -0.0004]\n";
  write(dir / "tag.yaml", tagged);
  EXPECT_EQ(detect_yaml_calibration_format(dir / "tag.yaml").kind, CalibrationFormat::opencv);
  expect_input_error([&] { load_calibration_yaml(dir / "tag.yaml"); },
                     {"tag.yaml",
                      "read as an OpenCV FileStorage file: it has OpenCV's "
                      "!!opencv-matrix tag (line 4)"});
  write(dir / "tag.yaml", "%YAML:1.0\n" + tagged);
  const Calibration e = load_calibration_yaml(dir / "tag.yaml");
  EXPECT_TRUE(e.fisheye);
  EXPECT_DOUBLE_EQ(e.dist[3], -0.0004);
}

// A file that is neither form (OpenCV's header and matrix, but a camera_info matrix for the
// coefficients), or whose distortion_model disagrees with its coefficients, is refused with one
// line naming the file and the key, and saying which format it was read as and why.
TEST(Calibration, MixedOrContradictoryCalibrationNamesFileKeyAndFormat) {
  const auto dir = testing::fresh_dir("calib_mixed");
  const std::string head =
      "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
      "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
      "  data: [610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]\ndistortion_model: plumb_bob\n";
  write(dir / "mixed.yaml", head +
                                "distortion_coefficients:\n  rows: 1\n  cols: 5\n"
                                "  data: [-0.12, 0.05, 0.0004, -0.0003, 0.0021]\n");
  expect_input_error([&] { load_calibration_yaml(dir / "mixed.yaml"); },
                     {"mixed.yaml: distortion_coefficients: no dt", "ROS camera_info matrix",
                      "read as an OpenCV FileStorage file", "%YAML:1.0 (line 1)"});
  write(dir / "count.yaml",
        head +
            "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 8\n"
            "  dt: d\n  data: [-0.12, 0.05, 0.0004, -0.0003, 0.0021, 0.1, 0, 0]\n");
  expect_input_error([&] { load_calibration_yaml(dir / "count.yaml"); },
                     {"count.yaml: distortion_coefficients: distortion_model plumb_bob takes",
                      "got 8", "read as an OpenCV FileStorage file"});
  write(dir / "model.yaml",
        std::string(head).replace(head.find("plumb_bob"), 9, "kannala_brandt") +
            "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 5\n  dt: d\n"
            "  data: [-0.12, 0.05, 0.0004, -0.0003, 0.0021]\n");
  expect_input_error([&] { load_calibration_yaml(dir / "model.yaml"); },
                     {"model.yaml: distortion_model: 'kannala_brandt' is not supported"});
  // A camera_info with an OpenCV key in it is refused as a camera_info, saying why it was one.
  write(dir / "ros.yaml",
        ros_camera_info("plumb_bob", "[-0.12, 0.05, 0.0004, -0.0003, 0.0021]",
                        "[1, 0, 0, 0, 1, 0, 0, 0, 1]",
                        "[610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]", "lens_model: pinhole\n"));
  expect_input_error([&] { load_calibration_yaml(dir / "ros.yaml"); },
                     {"ros.yaml", "lens_model", "read as a ROS camera_info file",
                      "distortion_model key (line 8)"});
}

// rational_polynomial (8 coefficients) is OpenCV's rational model: the same as an OpenCV file
// with 8 coefficients, and undistortion inverts it.
TEST(Calibration, RosRationalPolynomial) {
  const auto dir = testing::fresh_dir("calib_ros_rat");
  const std::string D = "[0.31, -0.12, 0.0004, -0.0003, 0.02, 0.65, -0.05, 0.07]";
  write(dir / "ros.yaml", ros_camera_info("rational_polynomial", D));
  write(dir / "cv.yaml",
        "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
        "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
        "  data: [610.25, 0, 321.7, 0, 605.5, 238.4, 0, 0, 1]\n"
        "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 8\n  dt: d\n  data: " +
            D + "\n");
  const Calibration r = load_calibration_ros(dir / "ros.yaml");
  const Calibration c = load_calibration_opencv(dir / "cv.yaml");
  ASSERT_TRUE(r.is_rational());
  EXPECT_EQ(cv::norm(r.dist - c.dist), 0.0);
  EXPECT_EQ(cv::norm(r.rational - c.rational), 0.0);
  EXPECT_DOUBLE_EQ(r.rational[0], 0.65);
  EXPECT_EQ(r.distortion().cols, 8);
  const std::vector<cv::Point2d> xy = {{0.4, -0.3}, {-0.5, 0.38}, {0.01, 0.02}};
  const auto px = denormalize_points(xy, r);
  // Not the 5-coefficient model: k4..k6 move the points.
  Calibration five = r;
  five.rational = {0, 0, 0};
  EXPECT_GT(cv::norm(denormalize_points(xy, five)[0] - px[0]), 1.0);
  const auto back = normalize_points(px, r);
  for (size_t i = 0; i < xy.size(); ++i) EXPECT_LT(cv::norm(back[i] - xy[i]), 1e-9);
  save_calibration_opencv(dir / "saved_cv.yaml", r);
  EXPECT_EQ(cv::norm(load_calibration_opencv(dir / "saved_cv.yaml").rational - r.rational), 0.0);
  save_calibration_ros(dir / "saved_ros.yaml", r, "cam_1");
  EXPECT_EQ(cv::norm(load_calibration_ros(dir / "saved_ros.yaml").rational - r.rational), 0.0);
}

TEST(Calibration, RosErrorsNameFileAndField) {
  const auto dir = testing::fresh_dir("calib_ros_err");
  const auto fails = [&](const std::string& text, std::initializer_list<std::string> needles) {
    write(dir / "cam_1.yaml", text);
    try {
      load_calibration_ros(dir / "cam_1.yaml");
      ADD_FAILURE() << "no InputError for\n" << text;
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos) << "one line: " << m;
      EXPECT_EQ(m.rfind((dir / "cam_1.yaml").string(), 0), 0u) << m;
      for (const auto& n : needles) EXPECT_NE(m.find(n), std::string::npos) << m << " lacks " << n;
    }
  };
  fails(ros_camera_info("kannala_brandt", "[0.1, 0.01, 0.001, 0.0001]"),
        {"distortion_model", "'kannala_brandt' is not supported"});
  fails(ros_camera_info("equidistant", "[0.1, 0.01, 0.001, 0.0001, 0.0]"),
        {"distortion_coefficients", "expected a 1x4 matrix", "cols 5"});
  fails(ros_camera_info("plumb_bob", "[-0.12, 0.05, 0.0004, -0.0003]"),
        {"distortion_coefficients", "expected a 1x5 matrix", "cols 4"});
  fails(ros_camera_info("rational_polynomial"), {"distortion_coefficients", "1x8"});
  fails(ros_camera_info("plumb_bob", "[-0.12, 0.05, .nan, -0.0003, 0.0021]"),
        {"distortion_coefficients.data[2]", "not finite"});
  fails(ros_camera_info("plumb_bob", "[-0.12, 0.05, 0.0004, -0.0003, 0.0021]",
                        "[1, 0, 0, 0, 1, 0, 0, 0, 1]", "[610, 0, 321, 0, 605, 238, 0, 0, .inf]"),
        {"camera_matrix.data[8]", "not finite"});
  fails(ros_camera_info("plumb_bob", "[-0.12, 0.05, 0.0004, -0.0003, 0.0021]",
                        "[1, 0, 0, 0, 1, 0, 0, 0, 1]", "[610, 0, 321, 0, 605, 238, 0, 0]"),
        {"camera_matrix.data", "expected 9 numbers", "got 8"});
  fails(ros_camera_info("plumb_bob", "[-0.12, 0.05, 0.0004, -0.0003, 0.0021]",
                        "[0.999, 0.04, 0, -0.04, 0.999, 0, 0, 0, 1]"),
        {"rectification_matrix", "not the identity"});
  fails(ros_camera_info("plumb_bob", "[-0.12, 0.05, 0.0004, -0.0003, 0.0021]",
                        "[1, 0, 0, 0, 1, 0, 0, 0, 1]", "[-610, 0, 321, 0, 605, 238, 0, 0, 1]"),
        {"camera_matrix", "focal lengths"});
  fails(ros_camera_info() + "binning_x: 1\n", {"binning_x"});
  std::string no_width = ros_camera_info();
  no_width.erase(0, no_width.find('\n') + 1);
  fails(no_width, {"image_width", "missing"});
  std::string bad_proj = ros_camera_info();
  bad_proj.replace(bad_proj.find("cols: 4"), 7, "cols: 3");
  fails(bad_proj, {"projection_matrix", "expected a 3x4 matrix"});
}

TEST(Calibration, VispXml) {
  const auto dir = testing::fresh_dir("calib_xml");
  {
    vpCameraParameters cam;
    cam.initPersProjWithDistortion(600.5, 601.5, 322.25, 241.75, -0.08, 0.081);
    vpXmlParserCamera p;
    ASSERT_EQ(p.save(cam, (dir / "cam_2.xml").string(), "cam_2", 640, 480),
              vpXmlParserCamera::SEQUENCE_OK);
    vpCameraParameters nodist;
    nodist.initPersProjWithoutDistortion(600.5, 601.5, 322.25, 241.75);
    vpXmlParserCamera p2;
    ASSERT_EQ(p2.save(nodist, (dir / "cam_3.xml").string(), "cam_3", 800, 600),
              vpXmlParserCamera::SEQUENCE_OK);
  }
  const Calibration c = load_calibration_visp_xml(dir / "cam_2.xml", "cam_2");
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_DOUBLE_EQ(c.K(0, 0), 600.5);
  EXPECT_DOUBLE_EQ(c.K(1, 1), 601.5);
  EXPECT_DOUBLE_EQ(c.K(0, 2), 322.25);
  EXPECT_DOUBLE_EQ(c.K(1, 2), 241.75);
  EXPECT_DOUBLE_EQ(c.dist[0], -0.08);  // ViSP kud = OpenCV k1
  EXPECT_EQ(c.dist[1], 0.0);
  const Calibration d = load_calibration_visp_xml(dir / "cam_3.xml", "cam_3");
  EXPECT_EQ(d.width, 800);
  EXPECT_FALSE(d.has_distortion());
  expect_input_error([&] { load_calibration_visp_xml(dir / "cam_2.xml", "cam_9"); },
                     {"cam_2.xml", "cam_9"});
}

// ViSP's radial model u = u0 + px x (1 + kud r^2) equals OpenCV's with k1 = kud.
TEST(Calibration, NormalizeInvertsDistortion) {
  const Calibration c = testing::test_calibration(true);
  const std::vector<cv::Point2d> xy = {{0.4, -0.3}, {-0.5, 0.38}, {0.01, 0.02}};
  const auto px = denormalize_points(xy, c);
  const auto back = normalize_points(px, c);
  for (size_t i = 0; i < xy.size(); ++i) EXPECT_LT(cv::norm(back[i] - xy[i]), 1e-9);
}

const char* kNetwork =
    "fps: 30\n"
    "frames: 10\n"
    "target: {family: tag36h11, id: 3, size: 0.2}\n"
    "cameras:\n"
    "  - {id: 1, p_wi: [0, 0, 0], r_wi: [0, 0, 0]}\n"
    "  - {id: 4, p_wi: [1, 2, 3], r_wi: [0, 0.5, 0]}\n"
    "edges: [[1, 4]]\n";

TEST(NetworkConfig, ReadsValidFile) {
  const auto dir = testing::fresh_dir("net_ok");
  write(dir / "network.yaml", kNetwork);
  const NetworkConfig n = load_network_config(dir / "network.yaml");
  EXPECT_EQ(n.fps, 30);
  ASSERT_TRUE(n.frames.has_value());
  EXPECT_EQ(*n.frames, 10);
  EXPECT_EQ(n.target().id, 3);
  EXPECT_EQ(n.target().size, 0.2);
  ASSERT_EQ(n.cameras.size(), 2u);
  EXPECT_EQ(n.cameras[1].id, 4);
  EXPECT_LT((n.cameras[1].g_wi.translation() - obs::Vec3(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT((obs::rotvec(n.cameras[1].g_wi) - obs::Vec3(0, 0.5, 0)).norm(), 1e-12);
  EXPECT_EQ(n.edges, (std::vector<std::pair<int, int>>{{1, 4}}));
  EXPECT_EQ(n.index_of(4), 1);
  EXPECT_EQ(n.index_of(2), -1);
}

TEST(NetworkConfig, ErrorsNameFileAndKey) {
  const auto dir = testing::fresh_dir("net_err");
  const fs::path f = dir / "network.yaml";
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = kNetwork;
    s.replace(s.find(from), from.size(), to);
    write(f, s);
  };
  with("[[1, 4]]", "[[1, 7]]");
  expect_input_error([&] { load_network_config(f); },
                     {"network.yaml", "edges[0]", "unknown camera id 7"});
  with("id: 4,", "id: 1,");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "duplicate camera id 1"});
  with("fps: 30", "fsp: 30");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "fps"});
  with("frames: 10", "frame: 10");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "frame", "unknown key"});
  with("tag36h11", "tag99h9");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "target.family"});
  with("size: 0.2", "size: -1");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "target.size"});
  with("[[1, 4]]", "[[4, 4]]");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "self-loop"});
  with("r_wi: [0, 0.5, 0]", "r_wi: [0, 0.5]");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "cameras[1].r_wi"});
  with("id: 4,", "id: 0,");
  expect_input_error([&] { load_network_config(f); }, {"network.yaml", "positive"});
}

// Found by fuzzing (corpus truth_csv/frame_out_of_int_range, network_config/edge_id_1e10):
// integer fields outside int's range were converted before being checked (undefined behaviour,
// reported by the sanitizer build); they are errors naming the field.
TEST(NetworkConfig, EdgeIdOutOfIntRange) {
  const auto dir = testing::fresh_dir("net_edge_range");
  std::string s = kNetwork;
  s.replace(s.find("[[1, 4]]"), 8, "[[1, 1e10]]");
  write(dir / "network.yaml", s);
  expect_input_error([&] { load_network_config(dir / "network.yaml"); },
                     {"network.yaml", "edges[0]", "expected a pair of camera ids"});
}

TEST(TruthIo, IntegerOutOfIntRange) {
  const auto dir = testing::fresh_dir("truth_int_range");
  write(dir / "target.csv",
        std::string(kTargetHeader) + "\n2147483648,0,0,0,0,0,0,0\n-3e9,0,0,0,0,0,0,0\n");
  expect_input_error([&] { read_target_csv(dir / "target.csv"); },
                     {"target.csv:2", "frame", "expected an integer"});
  write(dir / "truth_cameras.csv", std::string(kTruthCamerasHeader) + "\n1e300,0,0,0,0,0,0\n");
  expect_input_error([&] { read_truth_cameras_csv(dir / "truth_cameras.csv"); },
                     {"truth_cameras.csv:2", "camera", "expected an integer"});
}

TEST(TruthIo, ReadsSynthesizedTruthAndTarget) {
  const auto dir = testing::fresh_dir("truth");
  auto spec = testing::simple_dataset_spec(2, 2);
  spec.g_wo[1] = testing::facing_pose(-1.0);  // behind the cameras: empty corners
  const auto corners = testing::write_synth_dataset(dir, spec);
  const auto rows = read_truth_csv(dir / "truth.csv");
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& r : rows) {
    const size_t ci = static_cast<size_t>(r.camera - 1);
    if (r.frame == 0) {
      ASSERT_TRUE(r.corners.has_value());
      EXPECT_TRUE(r.in_fov);
      EXPECT_LT(testing::corner_rms(*r.corners, corners[ci][0]), 1e-6);
    } else {
      EXPECT_FALSE(r.corners.has_value());
      EXPECT_FALSE(r.in_fov);
    }
  }
  const auto target = read_target_csv(dir / "target.csv");
  ASSERT_EQ(target.size(), 2u);
  EXPECT_LT((target[0].g_wo.matrix() - spec.g_wo[0].matrix()).norm(), 1e-9);
  EXPECT_NEAR(target[1].t, 1.0 / 30.0, 1e-9);
}

TEST(TruthIo, BadFilesNameFileAndLine) {
  const auto dir = testing::fresh_dir("truth_bad");
  write(dir / "truth.csv", "frame,t,cam\n");
  expect_input_error([&] { read_truth_csv(dir / "truth.csv"); }, {"truth.csv", "header"});
  write(dir / "target.csv", std::string(kTargetHeader) + "\n0,0,1,2,3,0,0,0\n1,0.1,x,2,3,0,0,0\n");
  expect_input_error([&] { read_target_csv(dir / "target.csv"); }, {"target.csv:3", "px"});
  expect_input_error([&] { read_target_csv(dir / "missing.csv"); }, {"missing.csv"});
}

TEST(DetectionsIo, FormatAndReadBack) {
  const auto dir = testing::fresh_dir("det_io");
  DetectionRow a;
  a.frame = 3;
  a.camera = 2;
  a.tag_id = 0;
  a.detected = true;
  a.status = TargetStatus::detected;
  a.margin = 87.123;
  a.corners = std::array<cv::Point2d, 4>{{{1.5, 2.25}, {3, 4}, {5, 6}, {7.12345, 8}}};
  DetectionRow b;
  b.frame = 3;
  b.camera = 5;
  b.tag_id = 0;
  b.status = TargetStatus::border_mismatch;
  b.reason = "side 1, corners 1-2";
  EXPECT_EQ(format_detection_row(b), "3,5,0,0,border_mismatch,,,,,,,,,,side 1; corners 1-2");
  write(dir / "d.csv", std::string(kDetectionsHeader) + "\n" + format_detection_row(a) + "\n" +
                           format_detection_row(b) + "\n");
  const auto rows = read_detections_csv(dir / "d.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_TRUE(rows[0].detected);
  EXPECT_EQ(rows[0].status, TargetStatus::detected);
  EXPECT_NEAR(rows[0].margin, 87.12, 1e-9);
  EXPECT_NEAR((*rows[0].corners)[3].x, 7.1235, 1e-9);
  EXPECT_FALSE(rows[1].detected);
  EXPECT_EQ(rows[1].status, TargetStatus::border_mismatch);
  EXPECT_FALSE(rows[1].corners.has_value());
  EXPECT_EQ(rows[1].reason, "side 1; corners 1-2");
  EXPECT_EQ(rows[0].reason, "");
}

// Every status token reads back as itself; an unknown token or a status that contradicts the
// detected flag is an error naming the file, line and column.
TEST(DetectionsIo, StatusColumn) {
  const auto dir = testing::fresh_dir("det_status");
  std::string csv = std::string(kDetectionsHeader) + "\n";
  for (TargetStatus st : kAllTargetStatuses) {
    DetectionRow r;
    r.camera = 1;
    r.tag_id = 0;
    r.status = st;
    r.detected = st == TargetStatus::detected;
    if (r.detected) r.corners = std::array<cv::Point2d, 4>{};
    csv += format_detection_row(r) + "\n";
    EXPECT_EQ(parse_target_status(to_string(st)), st);
  }
  write(dir / "d.csv", csv);
  const auto rows = read_detections_csv(dir / "d.csv");
  ASSERT_EQ(rows.size(), std::size(kAllTargetStatuses));
  for (size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i].status, kAllTargetStatuses[i]);

  const std::string header = std::string(kDetectionsHeader) + "\n";
  write(dir / "bad.csv", header + "0,1,0,0,occluded,,,,,,,,,,\n");
  expect_input_error([&] { read_detections_csv(dir / "bad.csv"); },
                     {"bad.csv:2", "status", "occluded", "border_mismatch"});
  write(dir / "bad2.csv", header + "0,1,0,0,detected,,,,,,,,,,\n");
  expect_input_error([&] { read_detections_csv(dir / "bad2.csv"); }, {"bad2.csv:2", "status"});
}

// One rule for what a number is, shared by every reader: the whole token, finite.
TEST(NumberText, AWholeFiniteTokenIsANumber) {
  EXPECT_EQ(io::parse_finite("2.5"), 2.5);
  EXPECT_EQ(io::parse_finite("-1e-3"), -1e-3);
  EXPECT_EQ(io::parse_finite("+4"), 4.0);
  EXPECT_EQ(io::parse_finite(" 7"), 7.0);  // leading white space, as strtod reads it
  // What io::exact_text writes reads back as itself, subnormal numbers included (strtod flags
  // them as ERANGE); below them, as strtod rounds (0).
  for (const double v : {0.3, -1.0 / 3.0, 1e-300, 4.9406564584124654e-324, -2.5e-310, 1.7e308})
    EXPECT_EQ(io::parse_finite(io::exact_text(v)), v) << io::exact_text(v);
  EXPECT_EQ(io::parse_finite("1e-999"), 0.0);
  for (const char* bad :
       {"", " ", "x", "2.5 ", "2.5x", "1,5", "nan", "inf", "-inf", "1e999", "-1e999", "0x"})
    EXPECT_FALSE(io::parse_finite(bad).has_value()) << "'" << bad << "'";
  EXPECT_EQ(io::parse_int("3"), 3);
  EXPECT_EQ(io::parse_int("3.0"), 3);
  EXPECT_EQ(io::parse_int("1e2"), 100);
  EXPECT_EQ(io::parse_int("-2147483648"), -2147483647 - 1);
  EXPECT_EQ(io::parse_int("2147483647"), 2147483647);
  for (const char* bad : {"3.5", "2147483648", "-2147483649", "1e10", "x", "", "nan"})
    EXPECT_FALSE(io::parse_int(bad).has_value()) << "'" << bad << "'";
}

}  // namespace
}  // namespace netvmo
