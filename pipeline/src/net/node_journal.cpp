#include "netvmo/pipeline/net/node_journal.hpp"

#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/number_text.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/target_status.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;
using obs::SE3;

namespace {

void put(std::string& s, double v) {
  (s += ',') += io::exact_text(v);
}

void put_flag(std::string& s, bool v) {
  s += v ? ",1" : ",0";
}

void put_pose(std::string& s, const SE3& g) {
  for (int r = 0; r < 3; ++r) put(s, g.translation()(r));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) put(s, g.linear()(r, c));
}

// Every column's name, the header's `name[12]` spelled out as name[0] .. name[11]; computed once.
const std::vector<std::string>& journal_columns() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    std::stringstream s(kNodeJournalHeader);
    for (std::string col; std::getline(s, col, ',');) {
      const auto bracket = col.find('[');
      if (bracket == std::string::npos) {
        out.push_back(col);
        continue;
      }
      const int n = std::stoi(col.substr(bracket + 1));
      for (int k = 0; k < n; ++k)
        out.push_back(col.substr(0, bracket) + "[" + std::to_string(k) + "]");
    }
    return out;
  }();
  return names;
}

// The fields of one row, taken in order; every error names the file, line and field.
class Fields {
 public:
  Fields(const std::string& line, const fs::path& file, int line_no, size_t expected)
      : file_(file), line_no_(line_no) {
    std::stringstream s(line);
    for (std::string f; std::getline(s, f, ',');) f_.push_back(f);
    if (!line.empty() && line.back() == ',') f_.emplace_back();
    if (f_.size() != expected)
      fail(std::to_string(f_.size()) + " fields, expected " + std::to_string(expected));
  }
  double num() {
    const auto v = io::parse_finite(f_[k_]);
    if (!v) fail_field("a finite number");
    return next(*v);
  }
  int integer() {
    const auto v = io::parse_int(f_[k_]);
    if (!v) fail_field("an integer");
    return next(*v);
  }
  bool flag() {
    if (f_[k_] != "0" && f_[k_] != "1") fail_field("0 or 1");
    return next(f_[k_] == "1");
  }
  frontend::TargetStatus status() {
    const auto v = io::parse_int(f_[k_]);
    constexpr auto count = static_cast<int>(std::size(frontend::kAllTargetStatuses));
    if (!v || *v < 0 || *v >= count) fail_field("a status 0.." + std::to_string(count - 1));
    return next(static_cast<frontend::TargetStatus>(*v));
  }
  SE3 pose() {
    const size_t first = k_;
    SE3 g = SE3::Identity();
    for (int r = 0; r < 3; ++r) g.translation()(r) = num();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) g.linear()(r, c) = num();
    // Written from rotations at %.17g: orthonormal to rounding, a right-handed frame.
    const obs::Mat3 R = g.linear();
    if ((R.transpose() * R - obs::Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
        R.determinant() < 0)
      fail(names()[first + 3] + ".." + names()[first + 11] + ": not a rotation matrix");
    return g;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(file_.string() + ":" + std::to_string(line_no_) + ": " + what);
  }

 private:
  static const std::vector<std::string>& names() { return journal_columns(); }
  template <class T>
  T next(T v) {
    ++k_;
    return v;
  }
  [[noreturn]] void fail_field(const std::string& expected) const {
    fail(names()[k_] + ": expected " + expected + ", got '" + f_[k_] + "'");
  }

  std::vector<std::string> f_;
  size_t k_ = 0;
  fs::path file_;
  int line_no_;
};

}  // namespace

std::string node_journal_row(const NodeRow& row) {
  const frontend::Observation& cam = row.cam;
  std::string s = std::to_string(row.frame);
  put(s, row.t);
  put_flag(s, cam.delta);
  put_flag(s, cam.read_failed);
  s += "," + std::to_string(static_cast<int>(cam.status)) + "," + std::to_string(cam.tag_id) + "," +
       std::to_string(cam.hamming);
  put(s, cam.margin);
  for (const auto& c : cam.corners_px) {
    put(s, c.x);
    put(s, c.y);
  }
  for (int a = 0; a < 8; ++a) put(s, cam.f_normalized(a));
  put_flag(s, cam.g_io_pnp.has_value());
  put_pose(s, cam.g_io_pnp ? *cam.g_io_pnp : SE3::Identity());
  put_flag(s, row.initialized);
  put_pose(s, row.est_w);
  put_flag(s, row.indep);
  put_pose(s, row.indep_w);
  return s + "\n";
}

std::vector<NodeRow> read_node_journal(fs::path file, bool allow_missing) {
  if (!fs::exists(file) && allow_missing) {
    file = partial_path(file);
    if (!fs::exists(file)) return {};  // never ran a frame
  }
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": node output not found");
  std::string line;
  if (!std::getline(in, line) || line != kNodeJournalHeader)
    throw InputError(file.string() + ":1: not a node journal (its first line is not the header " +
                     std::string(kNodeJournalHeader) + ")");
  const size_t columns = journal_columns().size();
  std::vector<NodeRow> rows;
  for (int line_no = 2; std::getline(in, line); ++line_no) {
    if (line.empty()) continue;
    if (in.eof() && allow_missing) break;  // a .partial's last line cut off by the kill
    Fields f(line, file, line_no, columns);
    NodeRow r;
    r.frame = f.integer();
    if (r.frame < 0) f.fail("frame: expected a frame index >= 0, got " + std::to_string(r.frame));
    if (!rows.empty() && r.frame <= rows.back().frame)
      f.fail("frame: " + std::to_string(r.frame) + " is not after the previous row's");
    r.t = f.num();
    if (!rows.empty() && r.t < rows.back().t)
      f.fail("t: " + io::exact_text(r.t) + " is before the previous row's");
    r.cam.delta = f.flag();
    r.cam.read_failed = f.flag();
    r.cam.status = f.status();
    r.cam.tag_id = f.integer();
    r.cam.hamming = f.integer();
    r.cam.margin = f.num();
    for (auto& c : r.cam.corners_px) {
      c.x = f.num();
      c.y = f.num();
    }
    for (int a = 0; a < 8; ++a) r.cam.f_normalized(a) = f.num();
    const bool pnp = f.flag();
    const SE3 g_io = f.pose();
    if (pnp) r.cam.g_io_pnp = g_io;
    r.initialized = f.flag();
    r.est_w = f.pose();
    r.indep = f.flag();
    r.indep_w = f.pose();
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace netvmo::net
