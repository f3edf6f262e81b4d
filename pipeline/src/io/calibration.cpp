#include "netvmo/pipeline/io/calibration.hpp"

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpException.h>
#include <visp3/core/vpXmlParserCamera.h>
#include <yaml-cpp/yaml.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <opencv2/calib3d.hpp>
#include <string>
#include <utility>
#include <vector>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"

namespace netvmo::io {
namespace fs = std::filesystem;

namespace {

void validate(const Calibration& c, const std::string& file) {
  if (c.width <= 0 || c.height <= 0)
    throw InputError(file + ": image_width/image_height: must be positive (got " +
                     std::to_string(c.width) + "x" + std::to_string(c.height) + ")");
  const cv::Matx33d& K = c.K;
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0))
    throw InputError(file + ": camera_matrix: focal lengths fx, fy must be positive");
  if (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0 || K(2, 2) != 1)
    throw InputError(file + ": camera_matrix: expected [fx s cx; 0 fy cy; 0 0 1]");
  for (int i = 0; i < 5; ++i)
    if (!std::isfinite(c.dist[i])) throw InputError(file + ": distortion_coefficients: not finite");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(c.rational[i]))
      throw InputError(file + ": distortion_coefficients: not finite");
  if (c.fisheye && (c.dist[4] != 0 || c.is_rational()))
    throw InputError(file + ": distortion_coefficients: the fisheye model takes 4 (k1..k4)");
}

// An opencv-matrix node, its declared size checked first: OpenCV allocates rows x cols before
// reading the data, so a damaged size (e.g. `cols: /`) would ask for gigabytes.
cv::Mat read_matrix(const cv::FileNode& n, const std::string& file, const char* key,
                    int max_elements) {
  const std::string what = file + ": " + key + ": ";
  if (!n.isMap()) throw InputError(what + "expected an opencv-matrix (rows, cols, dt, data)");
  const cv::FileNode rows = n["rows"], cols = n["cols"];
  if (!rows.isInt() || !cols.isInt()) throw InputError(what + "rows and cols must be integers");
  const long long r = static_cast<int>(rows), c = static_cast<int>(cols);
  if (r < 1 || c < 1 || r * c > max_elements)
    throw InputError(what + "expected at most " + std::to_string(max_elements) +
                     " numbers, got rows " + std::to_string(r) + " x cols " + std::to_string(c));
  // A matrix without its element type is a ROS camera_info matrix (rows, cols, data) in a file
  // that is otherwise OpenCV's: OpenCV would read it as a plain map and fail on the conversion.
  if (const cv::FileNode dt = n["dt"]; dt.empty() || dt.isNone())
    throw InputError(what +
                     "no dt: a ROS camera_info matrix (rows, cols, data) in an OpenCV "
                     "FileStorage file (an opencv-matrix has rows, cols, dt and data)");
  cv::Mat m;
  n >> m;
  return m;
}

// OpenCV's YAML parser also loops for ever on a block line dedented to a column that no
// enclosing line starts at ("   rows: 6", "  1.0", then a line "-"), and on an indented first key
// followed by a line at column 0 ("   cols: 3", then ", %"; both found by fuzzing). YAML requires
// a dedent to return to an enclosing indentation, and nothing of a document's root may stand left
// of its first line (OpenCV writes its files so), so such a file is refused with its line. Lines
// that continue a flow collection ([ ] or { }, e.g. a long `data:` list) are not checked; blank,
// comment and directive lines neither.
void check_yaml_indentation(const std::string& text, const std::string& file) {
  std::vector<size_t> levels;  // the first content line's column, then every open block's
  int depth = 0;               // open [ and { at the start of the line
  size_t line_no = 1;
  for (size_t at = 0; at < text.size(); ++line_no) {
    const size_t end = std::min(text.find('\n', at), text.size());
    const std::string line = text.substr(at, end - at);
    at = end + 1;
    const size_t first = line.find_first_not_of(' ');
    if (first == std::string::npos || line[first] == '#' || line[first] == '\r' || line[0] == '%')
      continue;
    if (depth == 0) {
      if (levels.empty() || first > levels.back()) {
        levels.push_back(first);
      } else {
        while (!levels.empty() && levels.back() > first) levels.pop_back();
        if (levels.empty() || levels.back() != first)
          throw InputError(file + ":" + std::to_string(line_no) + ": indentation of " +
                           std::to_string(first) +
                           " spaces matches no enclosing line (YAML block structure)");
      }
    }
    // Outside a flow collection a '[' or '{' opens one only where a value starts (the line's
    // first character, after "- " or after ": "); inside a key or a plain scalar it is text (a
    // key "cols[" followed by a dedent hung OpenCV's parser; found by fuzzing).
    char quote = 0;
    bool value_start = true;
    for (size_t k = first; k < line.size(); ++k) {
      const char ch = line[k];
      const bool blank_next = k + 1 == line.size() || line[k + 1] == ' ';
      if (quote) {
        if (ch == quote) quote = 0;
      } else if (ch == ' ') {
        continue;
      } else if (ch == '"' || ch == '\'') {
        quote = ch;
      } else if (ch == '#' && (k == 0 || line[k - 1] == ' ')) {
        break;
      } else if (ch == '[' || ch == '{') {
        if (depth > 0 || value_start) ++depth;
      } else if ((ch == ']' || ch == '}') && depth > 0) {
        --depth;
      } else if (depth == 0 && (ch == '-' || ch == ':') && blank_next) {
        value_start = true;
        continue;
      }
      value_start = false;
    }
  }
}

// OpenCV's XML parser reads past the end of the text (a null pointer dereference, found by
// fuzzing) when the file ends inside a tag after an attribute's '=' (`<a b=` and only spaces
// after it). A well-formed file never ends inside a tag; one that does is refused, whatever
// precedes the end (quoted attribute values, which may hold '<' or '>', comments and CDATA
// sections are skipped).
void check_xml_ends_outside_tags(const std::string& text, const std::string& file) {
  bool in_tag = false;
  char quote = 0;
  for (size_t k = 0; k < text.size(); ++k) {
    const char ch = text[k];
    if (!in_tag) {
      if (ch != '<') continue;
      for (const auto& [open, close] :
           {std::pair<const char*, const char*>{"<!--", "-->"}, {"<![CDATA[", "]]>"}}) {
        if (text.compare(k, std::strlen(open), open) != 0) continue;
        const size_t end = text.find(close, k + std::strlen(open));
        if (end == std::string::npos)
          throw InputError(file + ": the XML file ends inside a comment or CDATA section");
        k = end + std::strlen(close) - 1;
        break;
      }
      in_tag = text[k] == '<';
    } else if (quote) {
      if (ch == quote) quote = 0;
    } else if (ch == '"' || ch == '\'') {
      quote = ch;
    } else if (ch == '>') {
      in_tag = false;
    }
  }
  if (in_tag) throw InputError(file + ": the XML file ends inside a tag (truncated?)");
}

// The checks a calibration file's text passes before OpenCV's FileStorage parses it: inputs on
// which that parser loops for ever or does not return (found by fuzzing).
void check_calibration_text(const fs::path& path, const std::string& file) {
  // OpenCV's FileStorage parser can loop for ever on a NUL byte inside the text (found by
  // fuzzing); calibration files are text.
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.find('\0') != std::string::npos)
    throw InputError(file + ": not a text file (it contains a NUL byte)");
  // It also loops for ever on a YAML document marker with text after it ("--- a: 1" or
  // "-----a: 1", then a later line ending in "---"; found by fuzzing). OpenCV writes the marker
  // alone on its line, so only that form is accepted.
  // OpenCV reads a file as YAML by its content whatever its name (a "cam_1.xml" starting with
  // "%YAML" is parsed as YAML), so the checks go by the content: not XML ('<'), not JSON ('{').
  const size_t lead = text.find_first_not_of(" \t\r\n");
  const bool yaml = lead != std::string::npos && text[lead] != '<' && text[lead] != '{';
  size_t line_no = 1;
  int markers = 0;
  bool content = false;  // a line of the document seen
  for (size_t at = 0; at < text.size(); ++line_no) {
    const size_t end = std::min(text.find('\n', at), text.size());
    const bool alone = text.find_first_not_of(" \t\r", at + 3) >= end;
    if (text.compare(at, 3, "---") == 0 && !alone)
      throw InputError(file + ":" + std::to_string(line_no) +
                       ": a YAML document marker '---' must stand alone on its line");
    if (yaml && ((text.compare(at, 3, "---") == 0 && (++markers > 1 || content)) ||
                 (text.compare(at, 3, "...") == 0 && alone)))
      throw InputError(file + ":" + std::to_string(line_no) +
                       ": one YAML document expected (a calibration file has at most one '---', "
                       "before its first key, and no '...')");
    const size_t first = text.find_first_not_of(" \t\r", at);
    if (first < end && text[first] != '#' && text[at] != '%' && text.compare(at, 3, "---") != 0)
      content = true;
    at = end + 1;
  }
  if (lead != std::string::npos && text[lead] == '<') check_xml_ends_outside_tags(text, file);
  if (yaml) {
    check_yaml_indentation(text, file);
    // Then the whole file must be well-formed YAML (yaml-cpp; the single document the checks
    // above leave, so its single-document Load sees all of it): OpenCV's own parser does not
    // return on some malformed files (three kinds found by fuzzing, and more may exist).
    // OpenCV's "%YAML:1.0" first line is not a YAML 1.2 directive: blanked, keeping line numbers.
    std::string doc = text;
    if (!doc.empty() && doc[0] == '%') doc.replace(0, std::min(doc.find('\n'), doc.size()), "");
    try {
      // A calibration file's top level is a mapping of keys: a text that yaml-cpp reads as one
      // multi-line scalar (a first line without ": ", the rest continuing it) hung OpenCV's
      // parser, which reads the same text as keys and flow collections (found by fuzzing).
      if (!YAML::Load(doc).IsMap())
        throw InputError(file +
                         ": not a calibration file: its top level is not a mapping of keys "
                         "(e.g. image_width: 640)");
    } catch (const YAML::Exception& e) {
      const std::string at = e.mark.is_null() ? "" : ":" + std::to_string(e.mark.line + 1);
      throw InputError(file + at + ": not well-formed YAML: " + e.msg);
    }
  }
}

// distortion_coefficients (`D`, as read) with lens_model and distortion_model, into c.dist,
// c.rational and c.fisheye, each checked against the others.
void read_distortion(const cv::FileStorage& fsr, cv::Mat D, const std::string& file,
                     Calibration& c) {
  D.convertTo(D, CV_64F);
  D = D.reshape(1, 1);
  const int n = D.empty() ? 0 : D.cols;
  // lens_model: pinhole (default) or fisheye (cv::fisheye's k1..k4).
  if (const cv::FileNode lm = fsr["lens_model"]; !lm.empty() && !lm.isNone()) {
    const std::string model = lm.isString() ? std::string(lm) : std::string("(not a string)");
    if (model == "fisheye")
      c.fisheye = true;
    else if (model != "pinhole")
      throw InputError(file + ": lens_model: '" + model +
                       "' is not supported (supported: pinhole, fisheye)");
    if (c.fisheye && n != 4)
      throw InputError(file +
                       ": distortion_coefficients: the fisheye model takes 4 (k1..k4), got " +
                       std::to_string(n));
  }
  if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
    throw InputError(file + ": distortion_coefficients: expected 4, 5 or 8 numbers, got " +
                     std::to_string(n));
  // distortion_model (ROS camera_info's key, which some converters also write into OpenCV
  // files): must agree with the coefficients and lens_model.
  if (const cv::FileNode dm = fsr["distortion_model"]; !dm.empty() && !dm.isNone()) {
    const std::string model = dm.isString() ? std::string(dm) : std::string("(not a string)");
    const char* expected = nullptr;
    bool ok = false;
    if (model == "plumb_bob") {
      ok = !c.fisheye && (n == 4 || n == 5);
      expected = "4 or 5 pinhole coefficients (k1 k2 p1 p2 [k3])";
    } else if (model == "rational_polynomial") {
      ok = !c.fisheye && n == 8;
      expected = "8 pinhole coefficients (k1 k2 p1 p2 k3 k4 k5 k6)";
    } else if (model == "equidistant") {
      ok = n == 4;
      expected = "4 fisheye coefficients (k1..k4)";
      if (ok && !c.fisheye && !fsr["lens_model"].empty())
        throw InputError(file + ": distortion_model: equidistant contradicts lens_model: pinhole");
      c.fisheye = true;
    } else {
      throw InputError(file + ": distortion_model: '" + model +
                       "' is not supported (supported: plumb_bob, rational_polynomial, "
                       "equidistant)");
    }
    if (!ok)
      throw InputError(file + ": distortion_coefficients: distortion_model " + model + " takes " +
                       expected + ", got " + std::to_string(n) +
                       (c.fisheye && model != "equidistant" ? " with lens_model: fisheye" : ""));
  }
  for (int i = 0; i < n; ++i) {
    const double v = D.at<double>(0, i);
    if (i < 5)
      c.dist[i] = v;
    else if (i < 8)
      c.rational[i - 5] = v;
    else if (v != 0.0)
      throw InputError(file +
                       ": distortion_coefficients: only the models with 5 (k1 k2 p1 p2 k3) "
                       "or 8 (+ k4 k5 k6) coefficients are supported; coefficient " +
                       std::to_string(i) + " is non-zero");
  }
}

}  // namespace

Calibration load_calibration_opencv(const fs::path& path) {
  const std::string file = path.string();
  if (!fs::is_regular_file(path)) throw InputError(file + ": calibration file not found");
  check_calibration_text(path, file);
  Calibration c;
  c.source = file;
  try {
    cv::FileStorage fsr(file, cv::FileStorage::READ);
    if (!fsr.isOpened()) throw InputError(file + ": cannot open as an OpenCV FileStorage file");
    auto need = [&](const char* key) {
      cv::FileNode n = fsr[key];
      if (n.empty() || n.isNone()) throw InputError(file + ": " + key + ": missing");
      return n;
    };
    cv::FileNode w = need("image_width"), h = need("image_height");
    if (!w.isInt() || !h.isInt())
      throw InputError(file + ": image_width/image_height: expected integers");
    c.width = static_cast<int>(w);
    c.height = static_cast<int>(h);
    cv::Mat K = read_matrix(need("camera_matrix"), file, "camera_matrix", 9);
    if (K.rows != 3 || K.cols != 3)
      throw InputError(file + ": camera_matrix: expected a 3x3 matrix");
    K.convertTo(K, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) c.K(r, col) = K.at<double>(r, col);
    read_distortion(
        fsr, read_matrix(need("distortion_coefficients"), file, "distortion_coefficients", 14),
        file, c);
  } catch (const cv::Exception& e) {
    throw InputError(file + ": cannot parse calibration: " + e.err);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    // OpenCV's parsers let some standard exceptions through (e.g. std::length_error on a key
    // made of nothing but a colon).
    throw InputError(file + ": cannot parse calibration: " + e.what());
  }
  validate(c, file);
  return c;
}

namespace {

// A ROS camera_info matrix {rows, cols, data}: the declared size must be the expected one and
// match the data, and every entry must be finite.
std::vector<double> ros_matrix(MapReader& parent, const std::string& key, int rows, int cols) {
  MapReader m = parent.get(key).map();
  const Value r = m.get("rows"), c = m.get("cols"), d = m.get("data");
  const int nr = r.integer(), nc = c.integer();
  if (nr != rows || nc != cols)
    m.fail("expected a " + std::to_string(rows) + "x" + std::to_string(cols) +
           " matrix, got rows " + std::to_string(nr) + " x cols " + std::to_string(nc));
  const std::vector<double> v = d.numbers();
  if (static_cast<long long>(v.size()) != static_cast<long long>(rows) * cols)
    d.fail("expected " + std::to_string(rows * cols) + " numbers (rows x cols), got " +
           std::to_string(v.size()));
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      Value(d.node()[i], d.file(), d.path() + "[" + std::to_string(i) + "]").fail("not finite");
  m.finish();
  return v;
}

}  // namespace

CalibrationFormat detect_yaml_calibration_format(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  // line[at..] starts with key, then optional blanks and ':'.
  const auto is_key = [](const std::string& l, size_t at, const char* key) {
    const size_t len = std::strlen(key);
    if (l.compare(at, len, key) != 0) return false;
    const size_t colon = l.find_first_not_of(" \t", at + len);
    return colon != std::string::npos && l[colon] == ':';
  };
  std::string opencv_mark;
  size_t ros_line = 0;
  for (size_t line_no = 1; std::getline(in, line); ++line_no) {
    const std::string where = " (line " + std::to_string(line_no) + ")";
    if (line_no == 1 && line.rfind("%YAML:", 0) == 0 && opencv_mark.empty())
      opencv_mark =
          "it starts with OpenCV's " + line.substr(0, std::min<size_t>(line.size(), 9)) + where;
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    if (opencv_mark.empty() && line.find("!!opencv-matrix") != std::string::npos)
      opencv_mark = "it has OpenCV's !!opencv-matrix tag" + where;
    if (opencv_mark.empty() && first > 0 && is_key(line, first, "dt"))
      opencv_mark = "it has an OpenCV matrix's dt key" + where;
    if (!ros_line && first == 0 && is_key(line, 0, "distortion_model")) ros_line = line_no;
  }
  if (!opencv_mark.empty())
    return {
        CalibrationFormat::opencv,
        opencv_mark + (ros_line ? ", so its distortion_model (line " + std::to_string(ros_line) +
                                      ") is read as OpenCV's, checked against the coefficients"
                                : std::string())};
  if (ros_line)
    return {CalibrationFormat::ros_camera_info,
            "it has a top-level distortion_model key (line " + std::to_string(ros_line) +
                ") and no mark of OpenCV FileStorage (%YAML:1.0, !!opencv-matrix, dt)"};
  return {CalibrationFormat::opencv,
          "it has no top-level distortion_model key (ROS camera_info's)"};
}

bool looks_like_ros_camera_info(const fs::path& path) {
  return detect_yaml_calibration_format(path).kind == CalibrationFormat::ros_camera_info;
}

Calibration load_calibration_yaml(const fs::path& path) {
  if (!fs::is_regular_file(path)) throw InputError(path.string() + ": calibration file not found");
  const CalibrationFormat format = detect_yaml_calibration_format(path);
  try {
    return format.kind == CalibrationFormat::ros_camera_info ? load_calibration_ros(path)
                                                             : load_calibration_opencv(path);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + " [read as " + format.name() + ": " + format.why +
                     "]");
  }
}

Calibration load_calibration_ros(const fs::path& path) {
  const std::string file = path.string();
  if (!fs::is_regular_file(path)) throw InputError(file + ": calibration file not found");
  MapReader root = MapReader::from_file(path);
  Calibration c;
  c.source = file;
  c.width = root.get("image_width").integer();
  c.height = root.get("image_height").integer();
  if (auto name = root.find("camera_name")) (void)name->string();
  const std::vector<double> K = ros_matrix(root, "camera_matrix", 3, 3);
  c.K = cv::Matx33d(K.data());
  const Value model_value = root.get("distortion_model");
  const std::string model = model_value.string();
  int n = 0;
  if (model == "plumb_bob")
    n = 5;
  else if (model == "rational_polynomial")
    n = 8;
  else if (model == "equidistant")
    n = 4;
  else
    model_value.fail("'" + model +
                     "' is not supported (supported: plumb_bob, rational_polynomial, "
                     "equidistant; the images are undistorted with OpenCV's pinhole or fisheye "
                     "model)");
  c.fisheye = n == 4;
  const std::vector<double> D = ros_matrix(root, "distortion_coefficients", 1, n);
  for (int i = 0; i < std::min(n, 5); ++i) c.dist[i] = D[static_cast<size_t>(i)];
  for (int i = 5; i < n; ++i) c.rational[i - 5] = D[static_cast<size_t>(i)];
  if (root.has("rectification_matrix")) {
    const std::vector<double> R = ros_matrix(root, "rectification_matrix", 3, 3);
    for (int i = 0; i < 9; ++i)
      if (R[static_cast<size_t>(i)] != (i % 4 == 0 ? 1.0 : 0.0))
        throw InputError(file +
                         ": rectification_matrix: not the identity (a stereo camera's "
                         "rectification); netvmo uses raw images with camera_matrix and "
                         "distortion_coefficients, which a monocular camera_info describes");
  }
  if (root.has("projection_matrix")) (void)ros_matrix(root, "projection_matrix", 3, 4);
  root.finish();
  validate(c, file);
  return c;
}

Calibration load_calibration_visp_xml(const fs::path& path, const std::string& camera_name) {
  const std::string file = path.string();
  if (!fs::is_regular_file(path)) throw InputError(file + ": calibration file not found");
  Calibration c;
  c.source = file;
  try {
    for (auto model : {vpCameraParameters::perspectiveProjWithDistortion,
                       vpCameraParameters::perspectiveProjWithoutDistortion}) {
      vpXmlParserCamera parser;
      vpCameraParameters cam;
      if (parser.parse(cam, file, camera_name, model) != vpXmlParserCamera::SEQUENCE_OK) continue;
      c.width = static_cast<int>(parser.getWidth());
      c.height = static_cast<int>(parser.getHeight());
      c.K = cv::Matx33d(cam.get_px(), 0, cam.get_u0(), 0, cam.get_py(), cam.get_v0(), 0, 0, 1);
      c.dist = {0, 0, 0, 0, 0};
      if (model == vpCameraParameters::perspectiveProjWithDistortion) c.dist[0] = cam.get_kud();
      validate(c, file + ": camera " + camera_name);
      return c;
    }
  } catch (const vpException& e) {
    throw InputError(file + ": cannot parse ViSP camera XML: " + e.getStringMessage());
  }
  throw InputError(file + ": no camera named '" + camera_name +
                   "' with a perspective projection (with or without distortion)");
}

void save_calibration_opencv(const fs::path& path, const Calibration& c) {
  std::string text;
  try {
    cv::FileStorage fsw(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    fsw << "image_width" << c.width << "image_height" << c.height;
    fsw << "camera_matrix" << cv::Mat(c.K);
    fsw << "distortion_coefficients" << c.distortion();
    if (c.fisheye)
      fsw << "lens_model"
          << "fisheye";
    text = fsw.releaseAndGetString();
  } catch (const cv::Exception& e) {
    throw InputError(path.string() + ": cannot write calibration: " + e.err);
  }
  write_file_atomic(path, text);  // appears only when complete
}

void save_calibration_ros(const fs::path& path, const Calibration& c,
                          const std::string& camera_name) {
  const auto matrix = [&](const char* key, int rows, int cols, const std::vector<double>& v) {
    std::string s = std::string(key) + ":\n  rows: " + std::to_string(rows) +
                    "\n  cols: " + std::to_string(cols) + "\n  data: [";
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + exact_text(v[i]);
    return s + "]\n";
  };
  const cv::Matx33d& K = c.K;
  const cv::Mat D = c.distortion();
  std::string text = "image_width: " + std::to_string(c.width) +
                     "\nimage_height: " + std::to_string(c.height) +
                     "\ncamera_name: " + camera_name + "\n";
  text += matrix("camera_matrix", 3, 3, std::vector<double>(K.val, K.val + 9));
  text += std::string("distortion_model: ") +
          (c.fisheye         ? "equidistant"
           : c.is_rational() ? "rational_polynomial"
                             : "plumb_bob") +
          "\n";
  text += matrix("distortion_coefficients", 1, D.cols,
                 std::vector<double>(D.begin<double>(), D.end<double>()));
  text += matrix("rectification_matrix", 3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  text += matrix("projection_matrix", 3, 4,
                 {K(0, 0), K(0, 1), K(0, 2), 0, K(1, 0), K(1, 1), K(1, 2), 0, 0, 0, 1, 0});
  write_file_atomic(path, text);
}

cv::Mat Calibration::distortion() const {
  if (fisheye) return (cv::Mat_<double>(1, 4) << dist[0], dist[1], dist[2], dist[3]);
  if (!is_rational()) return cv::Mat(cv::Matx<double, 1, 5>(dist.val)).clone();
  return (cv::Mat_<double>(1, 8) << dist[0], dist[1], dist[2], dist[3], dist[4], rational[0],
          rational[1], rational[2]);
}

std::vector<cv::Point2d> normalize_points(const std::vector<cv::Point2d>& px,
                                          const Calibration& calib) {
  std::vector<cv::Point2d> out;
  if (px.empty()) return out;
  if (calib.fisheye) {
    cv::fisheye::undistortPoints(
        px, out, cv::Mat(calib.K), calib.distortion(), cv::noArray(), cv::noArray(),
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
    return out;
  }
  cv::undistortPoints(
      px, out, cv::Mat(calib.K), calib.distortion(), cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  return out;
}

std::vector<cv::Point2d> denormalize_points(const std::vector<cv::Point2d>& xy,
                                            const Calibration& calib) {
  std::vector<cv::Point2d> out;
  if (xy.empty()) return out;
  if (calib.fisheye) {
    cv::fisheye::distortPoints(xy, out, cv::Mat(calib.K), calib.distortion());
    return out;
  }
  std::vector<cv::Point3d> rays;
  rays.reserve(xy.size());
  for (const auto& p : xy) rays.emplace_back(p.x, p.y, 1.0);
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(calib.K),
                    calib.distortion(), out);
  return out;
}

std::vector<cv::Point2d> ideal_pixels(const std::vector<cv::Point2d>& px,
                                      const Calibration& calib) {
  std::vector<cv::Point2d> out = normalize_points(px, calib);
  for (auto& p : out) {
    const cv::Vec3d q = calib.K * cv::Vec3d(p.x, p.y, 1.0);
    p = cv::Point2d(q[0] / q[2], q[1] / q[2]);
  }
  return out;
}

std::vector<cv::Point2d> distorted_pixels(const std::vector<cv::Point2d>& ideal,
                                          const Calibration& calib) {
  std::vector<cv::Point2d> xy;
  xy.reserve(ideal.size());
  const cv::Matx33d Kinv = calib.K.inv();
  for (const auto& p : ideal) {
    const cv::Vec3d q = Kinv * cv::Vec3d(p.x, p.y, 1.0);
    xy.emplace_back(q[0] / q[2], q[1] / q[2]);
  }
  return denormalize_points(xy, calib);
}

}  // namespace netvmo::io
