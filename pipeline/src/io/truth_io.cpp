#include "netvmo/pipeline/io/truth_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <type_traits>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/number_text.hpp"

namespace netvmo::io {
namespace fs = std::filesystem;

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : line) {
    if (ch == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (ch != '\r') {
      cur += ch;
    }
  }
  out.push_back(cur);
  return out;
}

/// Reads a CSV whose header is exactly one of `headers` and calls `row(fields, names, where)`
/// (or `row(fields, names, where, line)`, the line number) for each non-empty line, `names`
/// being the matched header's columns.
template <class F>
void read_csv(const fs::path& file, std::initializer_list<const char*> headers, F row) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open (missing or unreadable)");
  std::string line;
  if (!std::getline(in, line)) throw InputError(file.string() + ": empty file, expected header");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const auto match =
      std::find_if(headers.begin(), headers.end(), [&](const char* h) { return line == h; });
  if (match == headers.end()) {
    std::string expected;
    for (const char* h : headers) expected += std::string(expected.empty() ? "" : "' or '") + h;
    throw InputError(file.string() + ":1: unexpected header '" + line + "', expected '" + expected +
                     "'");
  }
  const auto names = split(*match);
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    const auto fields = split(line);
    const std::string where = file.string() + ":" + std::to_string(lineno);
    if (fields.size() != names.size())
      throw InputError(where + ": expected " + std::to_string(names.size()) + " fields, got " +
                       std::to_string(fields.size()));
    if constexpr (std::is_invocable_v<F&, const std::vector<std::string>&,
                                      const std::vector<std::string>&, const std::string&, int>)
      row(fields, names, where, lineno);
    else
      row(fields, names, where);
  }
}

template <class F>
void read_csv(const fs::path& file, const char* header, F row) {
  read_csv(file, {header}, row);
}

double num(const std::vector<std::string>& f, const std::vector<std::string>& names, size_t i,
           const std::string& where) {
  const auto v = parse_finite(f[i]);
  if (!v) throw InputError(where + ": " + names[i] + ": expected a number, got '" + f[i] + "'");
  return *v;
}

int integer(const std::vector<std::string>& f, const std::vector<std::string>& names, size_t i,
            const std::string& where) {
  if (const auto v = parse_int(f[i])) return *v;
  num(f, names, i, where);  // not a number: that error
  throw InputError(where + ": " + names[i] + ": expected an integer, got '" + f[i] + "'");
}

bool flag(const std::vector<std::string>& f, const std::vector<std::string>& names, size_t i,
          const std::string& where) {
  if (f[i] == "1" || f[i] == "true") return true;
  if (f[i] == "0" || f[i] == "false") return false;
  throw InputError(where + ": " + names[i] + ": expected 0 or 1, got '" + f[i] + "'");
}

// Per-image rows (timestamps.csv, cameras.csv): columns 0 and 1 are the camera (> 0) and the
// frame (>= 0); `line` is the row's line in the file.
template <class Row>
void camera_and_frame(Row& r, const std::vector<std::string>& f,
                      const std::vector<std::string>& names, const std::string& where) {
  r.camera = integer(f, names, 0, where);
  if (r.camera <= 0)
    throw InputError(where + ": camera: expected a positive camera id, got '" + f[0] + "'");
  r.frame = integer(f, names, 1, where);
  if (r.frame < 0)
    throw InputError(where + ": frame: expected a frame index >= 0, got '" + f[1] + "'");
  r.line = std::stoi(where.substr(where.rfind(':') + 1));
}

// Sorts per-image rows (each with its place in the file) by camera, then frame; a frame given
// twice for a camera is an error naming both rows.
template <class Row>
void sort_by_camera_and_frame(std::vector<std::pair<Row, std::string>>& rows) {
  std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return std::make_pair(a.first.camera, a.first.frame) <
           std::make_pair(b.first.camera, b.first.frame);
  });
  for (size_t k = 1; k < rows.size(); ++k) {
    const auto& [r, where] = rows[k];
    if (rows[k - 1].first.camera == r.camera && rows[k - 1].first.frame == r.frame)
      throw InputError(where + ": frame: camera " + std::to_string(r.camera) + " frame " +
                       std::to_string(r.frame) + " has a second row (first at " +
                       rows[k - 1].second + ")");
  }
}

std::string fmt_time(double t) {
  char b[40];
  std::snprintf(b, sizeof b, "%.9g", t);
  return b;
}

/// Eight corner fields from index i: all empty -> nullopt, all numbers -> corners.
std::optional<std::array<cv::Point2d, 4>> corners(const std::vector<std::string>& f,
                                                  const std::vector<std::string>& names, size_t i,
                                                  const std::string& where) {
  size_t empty = 0;
  for (size_t k = 0; k < 8; ++k) empty += f[i + k].empty();
  if (empty == 8) return std::nullopt;
  std::array<cv::Point2d, 4> c;
  for (size_t k = 0; k < 4; ++k)
    c[k] = cv::Point2d(num(f, names, i + 2 * k, where), num(f, names, i + 2 * k + 1, where));
  return c;
}

}  // namespace

std::vector<TruthRow> read_truth_csv(const fs::path& file) {
  std::vector<TruthRow> rows;
  read_csv(file, kTruthHeader, [&](const auto& f, const auto& names, const std::string& where) {
    TruthRow r;
    r.frame = integer(f, names, 0, where);
    r.t = num(f, names, 1, where);
    r.camera = integer(f, names, 2, where);
    r.in_fov = flag(f, names, 3, where);
    r.visible_fraction = num(f, names, 4, where);
    r.corners = corners(f, names, 5, where);
    rows.push_back(r);
  });
  return rows;
}

std::vector<TargetTruthRow> read_target_csv(const fs::path& file) {
  std::vector<TargetTruthRow> rows;
  read_csv(file, kTargetHeader, [&](const auto& f, const auto& names, const std::string& where) {
    TargetTruthRow r;
    r.frame = integer(f, names, 0, where);
    r.t = num(f, names, 1, where);
    const obs::Vec3 p(num(f, names, 2, where), num(f, names, 3, where), num(f, names, 4, where));
    const obs::Vec3 w(num(f, names, 5, where), num(f, names, 6, where), num(f, names, 7, where));
    r.g_wo = obs::make_pose(p, w);
    rows.push_back(r);
  });
  return rows;
}

std::vector<TimestampRow> read_timestamps_csv(const fs::path& file) {
  std::vector<std::pair<TimestampRow, std::string>> rows;  // with the line, for messages
  read_csv(file, kTimestampsHeader,
           [&](const auto& f, const auto& names, const std::string& where) {
             TimestampRow r;
             camera_and_frame(r, f, names, where);
             r.t = num(f, names, 2, where);
             rows.emplace_back(r, where);
           });
  sort_by_camera_and_frame(rows);
  std::vector<TimestampRow> out;
  for (size_t k = 0; k < rows.size(); ++k) {
    const auto& [r, where] = rows[k];
    if (k > 0 && rows[k - 1].first.camera == r.camera) {
      const auto& prev = rows[k - 1].first;
      if (!(r.t > prev.t))
        throw InputError(where + ": t: camera " + std::to_string(r.camera) + " frame " +
                         std::to_string(r.frame) + " at t = " + fmt_time(r.t) +
                         " s is not after its frame " + std::to_string(prev.frame) +
                         " at t = " + fmt_time(prev.t) + " s (times must increase with the frame)");
    }
    out.push_back(r);
  }
  return out;
}

std::vector<DetectionRow> read_detections_csv(const fs::path& file) {
  std::vector<DetectionRow> rows;
  read_csv(file, kDetectionsHeader,
           [&](const auto& f, const auto& names, const std::string& where) {
             DetectionRow r;
             r.frame = integer(f, names, 0, where);
             r.camera = integer(f, names, 1, where);
             r.tag_id = f[2].empty() ? -1 : integer(f, names, 2, where);
             r.detected = flag(f, names, 3, where);
             try {
               r.status = frontend::parse_target_status(f[4]);
             } catch (const InputError& e) {
               throw InputError(where + ": " + names[4] + ": " + e.what());
             }
             r.margin = f[5].empty() ? 0.0 : num(f, names, 5, where);
             r.corners = corners(f, names, 6, where);
             r.reason = f[14];
             if (r.detected != r.corners.has_value())
               throw InputError(where + ": corners must be given exactly when detected = 1");
             if (r.detected != (r.status == frontend::TargetStatus::detected))
               throw InputError(where + ": status must be 'detected' exactly when detected = 1");
             rows.push_back(r);
           });
  return rows;
}

namespace {
std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}
std::string pose_fields(const obs::SE3& g) {
  const obs::Vec3 p = g.translation(), r = obs::log_so3(g.linear());
  std::string s;
  for (int i = 0; i < 3; ++i) s += "," + fmt("%.9g", p[i]);
  for (int i = 0; i < 3; ++i) s += "," + fmt("%.9g", r[i]);
  return s;
}
}  // namespace

std::string format_truth_row(const render::FrameTruth& t) {
  std::string row = std::to_string(t.frame) + "," + fmt("%.6f", t.t) + "," +
                    std::to_string(t.camera_id) + "," + (t.in_fov ? "1" : "0") + "," +
                    fmt("%.6f", t.visible_fraction);
  for (const auto& c : t.corners) {
    if (c)
      row += "," + fmt("%.4f", c->x()) + "," + fmt("%.4f", c->y());
    else
      row += ",,";
  }
  return row;
}

std::string format_target_row(int frame, double t, const obs::SE3& g_wo) {
  return std::to_string(frame) + "," + fmt("%.6f", t) + pose_fields(g_wo);
}

std::string format_truth_camera_row(int camera, const obs::SE3& g_wi) {
  return std::to_string(camera) + pose_fields(g_wi);
}

std::string format_detection_row(const DetectionRow& r) {
  char buf[512];
  int n = std::snprintf(buf, sizeof buf, "%d,%d,", r.frame, r.camera);
  std::string s(buf, static_cast<size_t>(n));
  if (r.tag_id >= 0) s += std::to_string(r.tag_id);
  s += r.detected ? ",1," : ",0,";
  s += to_string(r.status);
  s += ',';
  if (r.detected) {
    n = std::snprintf(buf, sizeof buf, "%.2f", r.margin);
    s.append(buf, static_cast<size_t>(n));
  }
  for (size_t k = 0; k < 4; ++k) {
    if (r.corners) {
      n = std::snprintf(buf, sizeof buf, ",%.4f,%.4f", (*r.corners)[k].x, (*r.corners)[k].y);
      s.append(buf, static_cast<size_t>(n));
    } else {
      s += ",,";
    }
  }
  s += ',';
  for (char ch : r.reason) s += ch == ',' ? ';' : (ch == '\n' || ch == '\r') ? ' ' : ch;
  return s;
}

std::string format_timestamp_row(int camera, int frame, double t) {
  return std::to_string(camera) + "," + std::to_string(frame) + "," + exact_text(t);
}

std::string format_camera_pose_row(int camera, int frame, double t, const obs::SE3& g_wi) {
  const obs::Vec3 p = g_wi.translation(), r = obs::log_so3(g_wi.linear());
  std::string s = std::to_string(camera) + "," + std::to_string(frame) + "," + fmt("%.6f", t);
  for (int i = 0; i < 3; ++i) s += "," + fmt("%.12g", p[i]);
  for (int i = 0; i < 3; ++i) s += "," + fmt("%.12g", r[i]);
  return s;
}

std::vector<CameraPoseRow> read_camera_poses_csv(const fs::path& file) {
  std::vector<std::pair<CameraPoseRow, std::string>> rows;  // with the line, for messages
  read_csv(file, kCameraPosesHeader,
           [&](const auto& f, const auto& names, const std::string& where) {
             CameraPoseRow r;
             camera_and_frame(r, f, names, where);
             r.t = num(f, names, 2, where);
             const obs::Vec3 p(num(f, names, 3, where), num(f, names, 4, where),
                               num(f, names, 5, where));
             const obs::Vec3 w(num(f, names, 6, where), num(f, names, 7, where),
                               num(f, names, 8, where));
             r.g_wi = obs::make_pose(p, w);
             rows.emplace_back(r, where);
           });
  sort_by_camera_and_frame(rows);
  std::vector<CameraPoseRow> out;
  for (size_t k = 0; k < rows.size(); ++k) {
    const auto& r = rows[k].first;
    const bool first = k == 0 || rows[k - 1].first.camera != r.camera;
    const int expected = first ? 0 : rows[k - 1].first.frame + 1;
    if (r.frame != expected)
      throw InputError(file.string() + ": camera " + std::to_string(r.camera) +
                       ": no row for frame " + std::to_string(expected) +
                       " (a camera with rows needs one for every frame)");
    out.push_back(r);
  }
  return out;
}

std::vector<CameraPoseRow> read_camera_truth_csv(const fs::path& file) {
  std::ifstream in(file);
  std::string header;
  if (in && std::getline(in, header) && !header.empty() && header.back() == '\r') header.pop_back();
  if (header != kTruthCamerasHeader) return read_camera_poses_csv(file);
  std::vector<CameraPoseRow> out;
  for (const auto& r : read_truth_cameras_csv(file)) {
    CameraPoseRow p;
    p.camera = r.camera;
    p.frame = -1;
    p.g_wi = r.g_wi;
    out.push_back(p);
  }
  return out;
}

std::vector<CameraTruthRow> read_truth_cameras_csv(const fs::path& file) {
  std::vector<CameraTruthRow> rows;
  read_csv(file, kTruthCamerasHeader,
           [&](const auto& f, const auto& names, const std::string& where) {
             CameraTruthRow r;
             r.camera = integer(f, names, 0, where);
             const obs::Vec3 p(num(f, names, 1, where), num(f, names, 2, where),
                               num(f, names, 3, where));
             const obs::Vec3 w(num(f, names, 4, where), num(f, names, 5, where),
                               num(f, names, 6, where));
             r.g_wi = obs::make_pose(p, w);
             rows.push_back(r);
           });
  return rows;
}

std::string target_truth_file(const NetworkConfig& net, size_t target) {
  return target_truth_file(net.targets.at(target).id, target == 0);
}

std::string target_truth_file(int tag_id, bool primary) {
  return primary ? "target.csv" : "target_" + std::to_string(tag_id) + ".csv";
}

std::vector<EstimateRow> read_estimates_csv(const fs::path& file) {
  std::vector<EstimateRow> rows;
  read_csv(
      file, {kEstimatesHeader, kEstimatesTargetsHeader, kSimulationEstimatesHeader},
      [&](const auto& f, const std::vector<std::string>& names, const std::string& where,
          int line) {
        const bool simulation = names.front() == "t", targets = names[2] == "target";
        EstimateRow r;
        size_t i = 0;
        if (!simulation) r.frame = integer(f, names, i++, where);
        r.t = num(f, names, i++, where);
        if (targets) r.target = integer(f, names, i++, where);
        r.camera = integer(f, names, i, where);
        if (r.camera <= 0)
          throw InputError(where + ": camera: expected a positive camera id, got '" + f[i] + "'");
        ++i;
        if (!simulation) r.delta = flag(f, names, i++, where);
        size_t empty = 0;
        for (size_t k = i; k < i + 6; ++k) empty += f[k].empty();
        if (empty > 0 && empty < 6) {
          size_t k = i;
          while (!f[k].empty()) ++k;
          throw InputError(where + ": " + names[k] +
                           ": empty while other columns of the pose are given (all six of px..rz, "
                           "or none)");
        }
        if (empty == 0)
          r.g_w = obs::make_pose(obs::Vec3(num(f, names, i, where), num(f, names, i + 1, where),
                                           num(f, names, i + 2, where)),
                                 obs::Vec3(num(f, names, i + 3, where), num(f, names, i + 4, where),
                                           num(f, names, i + 5, where)));
        r.line = line;
        rows.push_back(r);
      });
  return rows;
}

}  // namespace netvmo::io
