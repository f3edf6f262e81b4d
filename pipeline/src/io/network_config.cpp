#include "netvmo/pipeline/io/network_config.hpp"

#include <set>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::io {

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
    const auto id = c.get("id");
    cam.id = id.integer();
    if (cam.id <= 0) id.fail("camera ids must be positive integers");
    if (!ids.insert(cam.id).second) id.fail("duplicate camera id " + std::to_string(cam.id));
    cam.g_wi = obs::make_pose(c.get("p_wi").vec<3>(), c.get("r_wi").vec<3>());
    c.finish();
    net.cameras.push_back(cam);
  }
  if (net.cameras.empty()) root.get("cameras").fail("at least one camera is required");
  std::set<std::pair<int, int>> seen;
  for (const auto& ev : root.get("edges").sequence()) {
    const auto e = ev.numbers();
    if (e.size() != 2 || e[0] != static_cast<int>(e[0]) || e[1] != static_cast<int>(e[1]))
      ev.fail("expected a pair of camera ids [i, j]");
    const int i = static_cast<int>(e[0]), j = static_cast<int>(e[1]);
    for (int k : {i, j})
      if (!ids.count(k))
        ev.fail("unknown camera id " + std::to_string(k) + " (not listed under cameras)");
    if (i == j) ev.fail("self-loop on camera " + std::to_string(i));
    if (!seen.insert({std::min(i, j), std::max(i, j)}).second)
      ev.fail("duplicate edge between cameras " + std::to_string(i) + " and " + std::to_string(j));
    net.edges.emplace_back(i, j);
  }
  root.finish();
  return net;
}

}  // namespace netvmo::io
