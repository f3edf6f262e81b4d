// network.yaml: the camera network of a dataset folder (rendered or recorded).
//
//   fps: 30                                   # frames per second (> 0)
//   frames: 300                               # optional: the dataset's frame count
//   target: {family: tag36h11, id: 0, size: 0.2}   # size = side of the black border square, m
//     bundle:                                 # optional: the body's other tags (same family)
//       - {id: 1, size: 0.15, p: [x, y, z], r: [rx, ry, rz]}   # pose g_ot in the object frame
//   targets:                                  # or, several tagged bodies (instead of target):
//     - {family: tag36h11, id: 0, size: 0.2}  #   each a map as target (bundle included); one
//     - {family: tag36h11, id: 5, size: 0.1}  #   family for all, no tag id on two targets
//   cameras:                                  # believed camera poses g_wi in the world
//     - {id: 1, p_wi: [x, y, z], r_wi: [rx, ry, rz]}   # r_wi: rotation vector of R_wi
//       fps: 15                               # optional: this camera's own frame rate (> 0;
//                                             #   default: the dataset's fps)
//       image_topic: /cam1/image_raw          # a rosbag2 bag's dataset or a live folder only:
//                                             #   the camera's sensor_msgs Image or
//                                             #   CompressedImage topic
//       camera_info_topic: /cam1/camera_info  # optional, a bag's or a live folder's: its
//                                             #   calibration, where calib/ has none
//   edges: [[1, 2], [2, 3]]                   # undirected communication graph (camera ids)
//
// Read strictly: a misspelt or unknown key anywhere is an InputError naming network.yaml and
// the key path; so are duplicate camera ids, non-positive ids, unknown ids or self-loops or
// duplicates in edges, an unsupported tag family, and non-positive fps or size; in a bundle, an
// id listed twice (the primary's included), a non-positive size, two overlapping tags
// (tags_overlap); both `target` and `targets`, an empty `targets`, a tag id on two targets, or
// targets of different families. `frames` is the only optional top-level key.
#pragma once

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"

namespace netvmo::io {

/// Another tag of the target's body (a tag bundle), of the primary tag's family.
struct BundleTag {
  int id = 0;
  double size = 0.0;                     ///< metres, side of the black border square
  obs::SE3 g_ot = obs::SE3::Identity();  ///< pose of the tag in the object frame
};

/// One tagged rigid body: its primary tag (whose frame is the object frame o) and the other
/// tags it carries. Tags of a body: slot 0 is the primary, slot k >= 1 is bundle[k - 1].
struct TargetConfig {
  std::string family = "tag36h11";
  int id = 0;
  double size = 0.0;              ///< metres, side of the primary tag's black border square
  std::vector<BundleTag> bundle;  ///< empty: a single-tag target

  /// Number of tags of the body (1 + bundle size).
  size_t tag_count() const { return 1 + bundle.size(); }
  /// Tag id, side [m] and pose g_ot of slot k (0: the primary, identity pose).
  int tag_id(size_t k) const { return k == 0 ? id : bundle.at(k - 1).id; }
  double tag_size(size_t k) const { return k == 0 ? size : bundle.at(k - 1).size; }
  obs::SE3 tag_pose(size_t k) const {
    return k == 0 ? obs::SE3::Identity() : bundle.at(k - 1).g_ot;
  }
};

/// Why two tags of a body cannot both be printed where they are, or nullopt. They overlap when
/// their centres are closer than 1e-6 m, or when they are coplanar and facing the same way
/// (normals within 1e-6 rad, the second centre within 1e-6 m of the first tag's plane) and their
/// squares' interiors intersect (separating-axis test on the 4 side directions, overlaps under
/// 1e-9 m are touching edges, allowed).
std::optional<std::string> tags_overlap(double size_a, const obs::SE3& g_oa, double size_b,
                                        const obs::SE3& g_ob);

struct CameraConfig {
  int id = 0;                            ///< positive, unique
  obs::SE3 g_wi = obs::SE3::Identity();  ///< believed pose of camera i in the world
  std::optional<double> fps;             ///< its own frame rate, when it differs from the dataset's
  /// In a rosbag2 bag's dataset (sources/dataset.hpp): the topics of its images and of its
  /// camera info (ROS names: a leading '/', no white space).
  std::optional<std::string> image_topic, camera_info_topic;
};

struct NetworkConfig {
  double fps = 0.0;
  std::optional<int> frames;  ///< optional frame count declared by the dataset
  /// The tagged bodies, at least one (`target:` in network.yaml gives exactly one). Each has
  /// its own networked observer; a target is named by its primary tag's id.
  std::vector<TargetConfig> targets{TargetConfig{}};
  std::vector<CameraConfig> cameras;
  std::vector<std::pair<int, int>> edges;  ///< camera ids
  std::string source;                      ///< file it was read from

  /// The first (for a single-target dataset, the only) target.
  const TargetConfig& target() const { return targets.at(0); }
  TargetConfig& target() { return targets.at(0); }
  /// Index of a camera id in `cameras`, or -1.
  int index_of(int camera_id) const;
  /// The frame rate of camera `index`: its own `fps`, else the dataset's.
  double camera_fps(size_t index) const { return cameras.at(index).fps.value_or(fps); }
};

NetworkConfig load_network_config(const std::filesystem::path& file);
/// The `id` of a `cameras:` entry, in every file that lists cameras (network.yaml, render and
/// simulation scenarios): a positive integer not in `seen` (added to it). Fails naming the key.
int read_camera_id(const Value& id, std::set<int>& seen);
/// An `edges:` list, in every file that has one: pairs [i, j] of camera ids in `ids`, no
/// self-loop, no edge twice. Fails naming the entry.
std::vector<std::pair<int, int>> read_edges(const Value& edges, const std::set<int>& ids);
/// The `family` of a tag, in every file that names tags (network.yaml's targets, a
/// calibration's MAP.yaml): a tag family render supports. Fails naming the key and the supported
/// families.
std::string read_tag_family(const Value& family);
/// The `id` of a tag, in the same files (targets, bundles, MAP.yaml's tags): a non-negative
/// integer. Fails naming the key.
int read_tag_id(const Value& id);

/// The graph alone: cameras `ids` (every pose the identity) joined by `edges` (camera ids), e.g.
/// for a PKI or a benchmark of the exchange.
NetworkConfig graph_network(const std::vector<int>& ids,
                            const std::vector<std::pair<int, int>>& edges);

/// network.yaml text of a configuration (what load_network_config reads back).
std::string network_yaml(const NetworkConfig& net);

}  // namespace netvmo::io
