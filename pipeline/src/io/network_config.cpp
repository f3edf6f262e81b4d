#include "netvmo/pipeline/io/network_config.hpp"

#include <climits>
#include <cmath>
#include <set>

#include <yaml-cpp/yaml.h>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::io {

int read_camera_id(const Value& id, std::set<int>& seen) {
  const int v = id.integer();
  if (v <= 0) id.fail("camera ids must be positive integers");
  if (!seen.insert(v).second) id.fail("duplicate camera id " + std::to_string(v));
  return v;
}

std::vector<std::pair<int, int>> read_edges(const Value& edges, const std::set<int>& ids) {
  std::vector<std::pair<int, int>> out;
  std::set<std::pair<int, int>> seen;
  for (const auto& ev : edges.sequence()) {
    const auto e = ev.numbers();
    // Range first: converting a double outside int's range is undefined behaviour.
    const auto is_int = [](double v) { return v >= INT_MIN && v <= INT_MAX && v == std::floor(v); };
    if (e.size() != 2 || !is_int(e[0]) || !is_int(e[1]))
      ev.fail("expected a pair of camera ids [i, j]");
    const int i = static_cast<int>(e[0]), j = static_cast<int>(e[1]);
    for (int k : {i, j})
      if (!ids.count(k))
        ev.fail("unknown camera id " + std::to_string(k) + " (not listed under cameras)");
    if (i == j) ev.fail("self-loop on camera " + std::to_string(i));
    if (!seen.insert({std::min(i, j), std::max(i, j)}).second)
      ev.fail("duplicate edge between cameras " + std::to_string(i) + " and " + std::to_string(j));
    out.emplace_back(i, j);
  }
  return out;
}

int NetworkConfig::index_of(int camera_id) const {
  for (size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].id == camera_id) return static_cast<int>(i);
  return -1;
}

NetworkConfig load_network_config(const std::filesystem::path& file) {
  auto root = io::MapReader::from_file(file);
  NetworkConfig net;
  net.source = file.string();
  {
    const auto v = root.get("fps");
    net.fps = v.number();
    if (!(net.fps > 0)) v.fail("must be positive");
  }
  if (auto v = root.find("frames")) {
    net.frames = v->integer();
    if (*net.frames < 0) v->fail("must not be negative");
  }
  {
    auto t = root.get("target").map();
    const auto fam = t.get("family");
    net.target.family = fam.string();
    if (!render::find_tag_family(net.target.family))
      fam.fail("unsupported tag family '" + net.target.family +
               "' (supported: " + render::tag_family_names() + ")");
    const auto id = t.get("id");
    net.target.id = id.integer();
    if (net.target.id < 0) id.fail("must not be negative");
    const auto size = t.get("size");
    net.target.size = size.number();
    if (!(net.target.size > 0)) size.fail("must be positive (metres)");
    t.finish();
  }
  std::set<int> ids;
  for (const auto& cv : root.get("cameras").sequence()) {
    auto c = cv.map();
    CameraConfig cam;
    cam.id = read_camera_id(c.get("id"), ids);
    cam.g_wi = obs::make_pose(c.get("p_wi").vec<3>(), c.get("r_wi").vec<3>());
    if (auto f = c.find("fps")) {
      cam.fps = f->number();
      if (!(*cam.fps > 0)) f->fail("must be positive");
    }
    c.finish();
    net.cameras.push_back(cam);
  }
  if (net.cameras.empty()) root.get("cameras").fail("at least one camera is required");
  net.edges = read_edges(root.get("edges"), ids);
  root.finish();
  return net;
}

std::string network_yaml(const NetworkConfig& net) {
  YAML::Emitter y;
  y.SetDoublePrecision(12);
  y << YAML::BeginMap;
  y << YAML::Key << "fps" << YAML::Value << net.fps;
  if (net.frames) y << YAML::Key << "frames" << YAML::Value << *net.frames;
  y << YAML::Key << "target" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "family" << YAML::Value << net.target.family;
  y << YAML::Key << "id" << YAML::Value << net.target.id;
  y << YAML::Key << "size" << YAML::Value << net.target.size;
  y << YAML::EndMap;
  y << YAML::Key << "cameras" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : net.cameras) {
    const obs::Vec3 p = c.g_wi.translation();
    const obs::Vec3 r = obs::log_so3(c.g_wi.linear());
    y << YAML::BeginMap;
    y << YAML::Key << "id" << YAML::Value << c.id;
    y << YAML::Key << "p_wi" << YAML::Value << YAML::Flow
      << std::vector<double>{p.x(), p.y(), p.z()};
    y << YAML::Key << "r_wi" << YAML::Value << YAML::Flow
      << std::vector<double>{r.x(), r.y(), r.z()};
    if (c.fps) y << YAML::Key << "fps" << YAML::Value << *c.fps;
    y << YAML::EndMap;
  }
  y << YAML::EndSeq;
  y << YAML::Key << "edges" << YAML::Value << YAML::BeginSeq;
  for (const auto& e : net.edges) y << YAML::Flow << std::vector<int>{e.first, e.second};
  y << YAML::EndSeq;
  y << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

}  // namespace netvmo::io
