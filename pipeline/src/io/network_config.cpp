#include "netvmo/pipeline/io/network_config.hpp"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <map>
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

std::string read_tag_family(const Value& family) {
  std::string name = family.string();
  if (!render::find_tag_family(name))
    family.fail("unsupported tag family '" + name + "' (supported: " + render::tag_family_names() +
                ")");
  return name;
}

int read_tag_id(const Value& id) {
  const int v = id.integer();
  if (v < 0) id.fail("must not be negative");
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

std::optional<std::string> tags_overlap(double size_a, const obs::SE3& g_oa, double size_b,
                                        const obs::SE3& g_ob) {
  const obs::Vec3 d = g_ob.translation() - g_oa.translation();
  if (d.norm() < 1e-6) return std::string("its centre coincides with");
  const obs::Vec3 na = g_oa.linear().col(2), nb = g_ob.linear().col(2);
  const bool coplanar =
      std::acos(std::clamp(na.dot(nb), -1.0, 1.0)) < 1e-6 && std::abs(na.dot(d)) < 1e-6;
  if (!coplanar) return std::nullopt;
  // Separating axes of two squares in one plane: their side directions (x and y of each tag).
  const auto corners = [](double s, const obs::SE3& g) {
    std::vector<obs::Vec3> c;
    for (const auto& [x, y] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
      c.push_back(g * obs::Vec3(x * s / 2, y * s / 2, 0.0));
    return c;
  };
  const auto ca = corners(size_a, g_oa), cb = corners(size_b, g_ob);
  for (const obs::Vec3 axis :
       {g_oa.linear().col(0), g_oa.linear().col(1), g_ob.linear().col(0), g_ob.linear().col(1)}) {
    double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
    for (const auto& c : ca) a0 = std::min(a0, axis.dot(c)), a1 = std::max(a1, axis.dot(c));
    for (const auto& c : cb) b0 = std::min(b0, axis.dot(c)), b1 = std::max(b1, axis.dot(c));
    if (std::min(a1, b1) - std::max(a0, b0) < 1e-9) return std::nullopt;  // separated or touching
  }
  return std::string("its square overlaps, in the same plane,");
}

namespace {

// One `target:` map (or `targets:` entry): primary tag and bundle.
TargetConfig read_target(const Value& v) {
  auto t = v.map();
  TargetConfig target;
  target.family = read_tag_family(t.get("family"));
  target.id = read_tag_id(t.get("id"));
  const auto size = t.get("size");
  target.size = size.number();
  if (!(target.size > 0)) size.fail("must be positive (metres)");
  if (auto b = t.find("bundle")) {
    std::set<int> tag_ids{target.id};
    for (const auto& bv : b->sequence()) {
      auto m = bv.map();
      BundleTag tag;
      const auto bid = m.get("id");
      tag.id = read_tag_id(bid);
      if (!tag_ids.insert(tag.id).second)
        bid.fail("tag id " + std::to_string(tag.id) + " listed twice in the target" +
                 (tag.id == target.id ? " (it is the primary tag's id)" : ""));
      const auto bsize = m.get("size");
      tag.size = bsize.number();
      if (!(tag.size > 0)) bsize.fail("must be positive (metres)");
      tag.g_ot = obs::make_pose(m.get("p").vec<3>(), m.get("r").vec<3>());
      m.finish();
      target.bundle.push_back(tag);
      const size_t k = target.tag_count() - 1;
      for (size_t j = 0; j < k; ++j)
        if (auto why = tags_overlap(target.tag_size(j), target.tag_pose(j), tag.size, tag.g_ot))
          bv.fail("tag " + std::to_string(tag.id) + ": " + *why + " tag " +
                  std::to_string(target.tag_id(j)) +
                  (j == 0 ? " (the primary)" : " (bundle[" + std::to_string(j - 1) + "])") +
                  "; tags of a body must not overlap");
    }
  }
  t.finish();
  return target;
}

void emit_target(YAML::Emitter& y, const TargetConfig& target) {
  y << YAML::BeginMap;
  y << YAML::Key << "family" << YAML::Value << target.family;
  y << YAML::Key << "id" << YAML::Value << target.id;
  y << YAML::Key << "size" << YAML::Value << target.size;
  if (!target.bundle.empty()) {
    y << YAML::Key << "bundle" << YAML::Value << YAML::BeginSeq;
    for (const auto& b : target.bundle) {
      const obs::Vec3 p = b.g_ot.translation();
      const obs::Vec3 r = obs::log_so3(b.g_ot.linear());
      y << YAML::Flow << YAML::BeginMap;
      y << YAML::Key << "id" << YAML::Value << b.id;
      y << YAML::Key << "size" << YAML::Value << b.size;
      y << YAML::Key << "p" << YAML::Value << YAML::Flow
        << std::vector<double>{p.x(), p.y(), p.z()};
      y << YAML::Key << "r" << YAML::Value << YAML::Flow
        << std::vector<double>{r.x(), r.y(), r.z()};
      y << YAML::EndMap;
    }
    y << YAML::EndSeq;
  }
  y << YAML::EndMap;
}

}  // namespace

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
  if (root.has("targets")) {
    if (root.has("target")) root.get("target").fail("give either target or targets, not both");
    const auto list = root.get("targets");
    net.targets.clear();
    for (const auto& tv : list.sequence()) net.targets.push_back(read_target(tv));
    if (net.targets.empty()) list.fail("at least one target is required");
    // Tags are told apart by id alone: no id may appear on two bodies.
    std::map<int, size_t> owner;
    const auto seq = list.sequence();
    for (size_t j = 0; j < net.targets.size(); ++j) {
      const auto& t = net.targets[j];
      if (t.family != net.targets[0].family)
        seq[j].fail("family " + t.family + ": every target must use the first target's family (" +
                    net.targets[0].family + ")");
      for (size_t k = 0; k < t.tag_count(); ++k) {
        const auto [it, fresh] = owner.emplace(t.tag_id(k), j);
        if (!fresh)
          seq[j].fail("tag id " + std::to_string(t.tag_id(k)) + " is already on targets[" +
                      std::to_string(it->second) + "]; a tag id may appear on one target only");
      }
    }
  } else {
    net.targets = {read_target(root.get("target"))};
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
    for (const char* key : {"image_topic", "camera_info_topic"})
      if (auto t = c.find(key)) {
        const std::string name = t->string();
        if (name.size() < 2 || name[0] != '/' ||
            std::any_of(name.begin(), name.end(),
                        [](unsigned char ch) { return std::isspace(ch); }))
          t->fail("'" + name + "' is not a ROS topic name (a leading '/', no white space)");
        (std::string(key) == "image_topic" ? cam.image_topic : cam.camera_info_topic) = name;
      }
    c.finish();
    net.cameras.push_back(cam);
  }
  if (net.cameras.empty()) root.get("cameras").fail("at least one camera is required");
  net.edges = read_edges(root.get("edges"), ids);
  root.finish();
  return net;
}

NetworkConfig graph_network(const std::vector<int>& ids,
                            const std::vector<std::pair<int, int>>& edges) {
  NetworkConfig net;
  for (int id : ids) {
    CameraConfig c;
    c.id = id;
    net.cameras.push_back(c);
  }
  net.edges = edges;
  return net;
}

std::string network_yaml(const NetworkConfig& net) {
  YAML::Emitter y;
  y.SetDoublePrecision(12);
  y << YAML::BeginMap;
  y << YAML::Key << "fps" << YAML::Value << net.fps;
  if (net.frames) y << YAML::Key << "frames" << YAML::Value << *net.frames;
  if (net.targets.size() == 1) {  // the single-target form
    y << YAML::Key << "target" << YAML::Value;
    emit_target(y, net.targets[0]);
  } else {
    y << YAML::Key << "targets" << YAML::Value << YAML::BeginSeq;
    for (const auto& t : net.targets) emit_target(y, t);
    y << YAML::EndSeq;
  }
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
    if (c.image_topic) y << YAML::Key << "image_topic" << YAML::Value << *c.image_topic;
    if (c.camera_info_topic)
      y << YAML::Key << "camera_info_topic" << YAML::Value << *c.camera_info_topic;
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
