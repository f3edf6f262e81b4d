#include "netvmo/pipeline/sources/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/ros/rosbag.hpp"
#include "stream_util.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;
using detail::all_digits;

namespace {

bool looks_like_opencv_storage(const fs::path& xml) {
  std::ifstream in(xml);
  std::string head(512, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  return head.find("<opencv_storage>") != std::string::npos;
}

std::string list_frames(const std::vector<int>& v) {
  std::string s;
  for (size_t i = 0; i < v.size() && i < 5; ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  if (v.size() > 5) s += ", ...";
  return s;
}

// A camera whose stream could not be opened (with keep_going): blind at every frame.
class UnreadableStream : public CameraStream {
 public:
  explicit UnreadableStream(fs::path p) : path_(std::move(p)) {}
  int frame_count() const override { return 0; }
  bool has_frame(int) const override { return false; }
  cv::Mat read(int) override { return {}; }
  std::string frame_name(int f) const override {
    return path_.string() + " frame " + std::to_string(f);
  }
  const fs::path& path() const override { return path_; }

 private:
  fs::path path_;
};

// A camera whose images can be read (not another camera's process, not an unreadable stream).
bool readable(const DatasetCamera& cam) {
  return cam.source && !dynamic_cast<const UnreadableStream*>(cam.source.get());
}

// The index in network.yaml of the camera of a per-image row of `file` (timestamps.csv,
// cameras.csv), or an error naming the row.
template <class Row>
size_t listed_camera(const Dataset& ds, const fs::path& file, const Row& r) {
  const int i = ds.index_of(r.camera);
  if (i < 0)
    throw InputError(file.string() + ":" + std::to_string(r.line) + ": camera: camera " +
                     std::to_string(r.camera) + " is not in network.yaml");
  return static_cast<size_t>(i);
}

// A camera that timestamps.csv does not list takes its stream's own times (a video's
// timestamps), else frame / its fps; the notes say which.
void own_or_index_times(Dataset& ds, const std::set<int>& listed, const fs::path& file) {
  const bool bag = ros::RosBag::is_bag(ds.dir);
  const std::string own = bag ? "its bag topic's header.stamp times" : "its video's own timestamps";
  const std::string own_on_fps =
      bag ? "its bag topic's header.stamp times" : "its video's timestamps";
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    auto& cam = ds.cameras[i];
    if (listed.count(cam.id)) continue;
    const std::string why = (fs::exists(file) ? file.string() + " lists no image of camera "
                                              : "no " + file.string() + ": camera ") +
                            std::to_string(cam.id);
    std::string why_not;
    auto t = readable(cam) ? cam.source->own_times(why_not) : std::vector<double>{};
    // Containers round times to their time base (Matroska: 1 ms): a video within 1 ms of
    // frame / fps at every frame is on that clock, and keeps the exact times.
    const double fps = ds.network.camera_fps(i);
    bool on_fps_clock = !t.empty();
    for (size_t k = 0; k < t.size() && on_fps_clock; ++k)
      on_fps_clock = std::abs(t[k] - static_cast<double>(k) / fps) <= 1e-3;
    if (on_fps_clock) {
      ds.notes.push_back(why + ": " + own_on_fps + " are frame index / its fps (" +
                         io::format_number(fps) + " frames/s) within 1 ms, taken exactly (" +
                         cam.source->path().string() + ")");
      continue;
    }
    if (!t.empty()) {
      ds.notes.push_back(why + ": its times are " + own + " (" + cam.source->path().string() + ")");
      cam.times = std::move(t);
      continue;
    }
    ds.notes.push_back(why + ": its times are frame index / its fps (" +
                       io::format_number(ds.network.camera_fps(i)) + " frames/s)" +
                       (why_not.empty() ? ""
                                        : "; " + cam.source->path().string() +
                                              ": its timestamps are not used: " + why_not));
  }
}

// timestamps.csv (io::read_timestamps_csv checks the file itself): every listed camera is in
// network.yaml, and an opened camera it lists has a row for each of its images and none past
// its last. Cameras it does not list: own_or_index_times.
void read_timestamps(Dataset& ds) {
  const fs::path file = ds.dir / "timestamps.csv";
  std::set<int> listed;
  if (!fs::exists(file)) {
    own_or_index_times(ds, listed, file);
    return;
  }
  const auto rows = io::read_timestamps_csv(file);
  for (const auto& r : rows) {
    auto& cam = ds.cameras[listed_camera(ds, file, r)];
    const std::string where = file.string() + ":" + std::to_string(r.line);
    listed.insert(r.camera);
    // A camera that was not opened (another camera's process) or cannot be read keeps its
    // times unchecked.
    const int n = readable(cam) ? cam.source->frame_count() : r.frame + 1;
    if (!readable(cam) && cam.times.size() < static_cast<size_t>(n))
      cam.times.resize(static_cast<size_t>(n), std::nan(""));
    if (r.frame >= n)
      throw InputError(where + ": frame: " + std::to_string(r.frame) +
                       " is past the last image of camera " + std::to_string(r.camera) +
                       ", which has " + std::to_string(n) + " (" + cam.source->path().string() +
                       ")");
    if (cam.times.empty()) cam.times.assign(static_cast<size_t>(n), std::nan(""));
    cam.times[static_cast<size_t>(r.frame)] = r.t;
  }
  for (auto& cam : ds.cameras) {
    if (!readable(cam) || !listed.count(cam.id)) continue;
    for (int k = 0; k < cam.source->frame_count(); ++k)
      if (cam.source->has_frame(k) && std::isnan(cam.times[static_cast<size_t>(k)]))
        throw InputError(file.string() + ": camera " + std::to_string(cam.id) +
                         ": no row for frame " + std::to_string(k) + " (" +
                         cam.source->frame_name(k) + ")");
  }
  own_or_index_times(ds, listed, file);
}

// cameras.csv (io::read_camera_poses_csv checks the file itself): every listed camera is in
// network.yaml, and an opened camera it lists has a row for each of its frames and none past
// its last image.
void read_camera_poses(Dataset& ds) {
  const fs::path file = ds.dir / "cameras.csv";
  if (!fs::exists(file)) return;
  const auto rows = io::read_camera_poses_csv(file);
  for (const auto& r : rows) {
    auto& cam = ds.cameras[listed_camera(ds, file, r)];
    const std::string where = file.string() + ":" + std::to_string(r.line);
    if (readable(cam) && r.frame >= cam.source->frame_count())
      throw InputError(where + ": frame: " + std::to_string(r.frame) +
                       " is past the last image of camera " + std::to_string(r.camera) +
                       ", which has " + std::to_string(cam.source->frame_count()) + " (" +
                       cam.source->path().string() + ")");
    cam.poses.push_back(r.g_wi);  // rows come by camera, then frame, from 0 without a gap
  }
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    const auto& cam = ds.cameras[i];
    const int need =
        std::min(ds.camera_frame_count(i), readable(cam) ? cam.source->frame_count() : 0);
    if (!cam.poses.empty() && static_cast<int>(cam.poses.size()) < need)
      throw InputError(file.string() + ": camera " + std::to_string(cam.id) +
                       ": no row for frame " + std::to_string(cam.poses.size()) +
                       " (a camera with rows needs one for every frame)");
    if (cam.poses.empty())
      ds.notes.push_back(file.string() + " lists no pose of camera " + std::to_string(cam.id) +
                         ": it is static at its network.yaml pose");
  }
}

// A rosbag2 bag's dataset: every camera of network.yaml names an image topic of the bag, of an
// image type, and a camera_info_topic, where it names one, of CameraInfo. Returns the origin of
// the dataset's times: the earliest header.stamp of the cameras' first images [ns].
std::int64_t check_bag_topics(const fs::path& dir, const io::NetworkConfig& net) {
  const ros::RosBag bag(dir);
  const std::string file = (dir / "network.yaml").string();
  std::string images;
  for (const auto& t : bag.topics())
    if (t.type == ros::kImageType || t.type == ros::kCompressedImageType)
      images += (images.empty() ? "" : ", ") + t.name;
  std::optional<std::int64_t> origin;
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    const auto& cc = net.cameras[i];
    const std::string key = file + ": cameras[" + std::to_string(i) + "].";
    if (!cc.image_topic)
      throw InputError(key + "image_topic: missing (" + dir.string() +
                       " is a rosbag2 bag, metadata.yaml: each camera names its image topic; "
                       "the bag's: " +
                       (images.empty() ? "none" : images) + ")");
    const ros::BagTopic* t = bag.find_topic(*cc.image_topic);
    if (!t)
      throw InputError(key + "image_topic: " + *cc.image_topic + " is not in the bag (its image " +
                       "topics: " + (images.empty() ? "none" : images) + ")");
    if (t->type != ros::kImageType && t->type != ros::kCompressedImageType)
      throw InputError(key + "image_topic: " + *cc.image_topic + " is " + t->type + ", not " +
                       ros::kImageType + " or " + ros::kCompressedImageType);
    if (cc.camera_info_topic) {
      const ros::BagTopic* ci = bag.find_topic(*cc.camera_info_topic);
      if (!ci || ci->type != ros::kCameraInfoType || ci->message_count == 0)
        throw InputError(key + "camera_info_topic: " + *cc.camera_info_topic +
                         (ci ? " is " + ci->type + " with " + std::to_string(ci->message_count) +
                                   " message(s), not a " + ros::kCameraInfoType + " topic"
                             : " is not in the bag"));
    }
    if (const auto first = bag_topic_first_stamp(dir, *cc.image_topic))
      origin = std::min(origin.value_or(*first), *first);
  }
  return origin.value_or(0);
}

// The calibration a bag's camera_info_topic gives: its first message's.
io::Calibration bag_calibration(const fs::path& dir, const std::string& topic) {
  const ros::RosBag bag(dir);
  const auto msgs = bag.messages(topic);
  return ros::decode_camera_info(bag.read(msgs.at(0)), dir.string() + ":" + topic + " message 0 (" +
                                                           bag.where(msgs.at(0)) + ")");
}

}  // namespace

std::optional<io::Calibration> find_calibration(const fs::path& dir, int camera_id) {
  const std::string name = "cam_" + std::to_string(camera_id);
  const fs::path cdir = dir / "calib";
  for (const char* ext : {".yaml", ".yml"})
    if (fs::exists(cdir / (name + ext))) return io::load_calibration_yaml(cdir / (name + ext));
  const fs::path xml = cdir / (name + ".xml");
  if (fs::exists(xml))
    return looks_like_opencv_storage(xml) ? io::load_calibration_opencv(xml)
                                          : io::load_calibration_visp_xml(xml, name);
  return std::nullopt;
}

std::string calibration_not_found(const fs::path& dir, int camera_id) {
  const std::string name = "cam_" + std::to_string(camera_id);
  return (dir / "calib" / (name + ".yaml")).string() + ": calibration not found for camera " +
         std::to_string(camera_id) + " (also looked for " + name + ".yml and " + name + ".xml)";
}

obs::SE3 Dataset::camera_pose(size_t camera_index, int frame) const {
  const DatasetCamera& cam = cameras.at(camera_index);
  if (cam.poses.empty()) return network.cameras.at(camera_index).g_wi;
  return cam.poses[static_cast<size_t>(std::clamp(frame, 0, int(cam.poses.size()) - 1))];
}

int Dataset::camera_frame_count(size_t camera_index) const {
  const DatasetCamera& cam = cameras.at(camera_index);
  if (!network.cameras.at(camera_index).fps || network.camera_fps(camera_index) == network.fps)
    return frame_count;
  return cam.source ? cam.source->frame_count() : 0;
}

std::optional<double> Dataset::listed_time(size_t camera_index, int frame) const {
  const DatasetCamera& cam = cameras.at(camera_index);
  if (frame < 0 || static_cast<size_t>(frame) >= cam.times.size() ||
      std::isnan(cam.times[static_cast<size_t>(frame)]))
    return std::nullopt;
  return cam.times[static_cast<size_t>(frame)];
}

double Dataset::frame_time(size_t camera_index, int frame) const {
  return listed_time(camera_index, frame).value_or(frame / network.camera_fps(camera_index));
}

cv::Mat Dataset::read(size_t camera_index, int frame) {
  DatasetCamera& cam = cameras.at(camera_index);
  if (!cam.source)
    throw InputError(dir.string() + ": camera " + std::to_string(cam.id) + " was not opened");
  if (frame >= camera_frame_count(camera_index)) return {};
  cv::Mat m = cam.source->read(frame);
  if (!m.empty() && (m.cols != cam.calib.width || m.rows != cam.calib.height))
    throw InputError(cam.source->frame_name(frame) + ": image is " + std::to_string(m.cols) + "x" +
                     std::to_string(m.rows) + " but " + cam.calib.source + " says " +
                     std::to_string(cam.calib.width) + "x" + std::to_string(cam.calib.height));
  return m;
}

namespace {

// A bag's note on its clock (`origin`, ns); topics in network.yaml refused for a folder that is
// not a bag.
void check_topics(Dataset& ds, bool bag, std::int64_t origin) {
  if (bag)
    ds.notes.push_back(ds.dir.string() + " is a rosbag2 bag: every camera's images are its " +
                       "image_topic's messages, their times header.stamp less " +
                       std::to_string(origin / 1'000'000'000) + "." +
                       std::to_string(1'000'000'000 + origin % 1'000'000'000).substr(1) +
                       " s (the earliest first image's)");
  for (size_t i = 0; i < ds.network.cameras.size() && !bag; ++i)
    for (const auto& [key, topic] :
         {std::pair{"image_topic", ds.network.cameras[i].image_topic},
          std::pair{"camera_info_topic", ds.network.cameras[i].camera_info_topic}})
      if (topic)
        throw InputError((ds.dir / "network.yaml").string() + ": cameras[" + std::to_string(i) +
                         "]." + key + ": only a rosbag2 bag's dataset (" + ds.dir.string() +
                         " has no metadata.yaml) or a live folder (launch, node --live) names "
                         "topics");
}

// What open_camera needs of the dataset.
struct CameraOpening {
  const fs::path& dir;
  bool bag = false;
  std::int64_t origin = 0;  ///< a bag's time origin (ns)
  bool keep_going = false;
  std::vector<std::string>& warnings;
};

// Called in the handler of a stream's InputError `e`: with keep_going a blind camera (a
// warning), otherwise the error rethrown as it was.
std::unique_ptr<CameraStream> blind_or_throw(const InputError& e, int id, const fs::path& what,
                                             const CameraOpening& o) {
  if (!o.keep_going) throw;
  o.warnings.push_back(std::string(e.what()) + "; camera " + std::to_string(id) +
                       " is blind for the whole run (--keep-going)");
  return std::make_unique<UnreadableStream>(what);
}

// Camera cc's calibration and frames: a bag's image topic, or exactly one entry cam_<id> of one
// registered stream kind (image folder, video, ...).
DatasetCamera open_camera(const io::CameraConfig& cc, const CameraOpening& o) {
  const fs::path& dir = o.dir;
  const std::string name = "cam_" + std::to_string(cc.id);
  DatasetCamera cam;
  cam.id = cc.id;
  if (auto calib = find_calibration(dir, cc.id)) {
    cam.calib = std::move(*calib);
  } else if (o.bag && cc.camera_info_topic) {
    cam.calib = bag_calibration(dir, *cc.camera_info_topic);
  } else {
    throw InputError(calibration_not_found(dir, cc.id) +
                     (o.bag ? "; network.yaml names no camera_info_topic for it" : ""));
  }
  std::vector<std::pair<const StreamKind*, fs::path>> found;
  for (const auto* kind : stream_kinds())
    for (const auto& p : kind->entries(dir, name)) found.emplace_back(kind, p);
  if (o.bag) {
    if (!found.empty())
      throw InputError(found[0].second.string() + ": camera " + std::to_string(cc.id) +
                       " has both this " + std::string(found[0].first->name()) +
                       " and the bag's topic " + *cc.image_topic + "; keep one");
    try {
      cam.source = open_bag_topic(dir, *cc.image_topic, o.origin);
    } catch (const InputError& e) {
      cam.source = blind_or_throw(e, cc.id, dir.string() + ":" + *cc.image_topic, o);
    }
    return cam;
  }
  if (found.empty()) {
    std::string kinds;
    for (const auto* kind : stream_kinds())
      kinds += std::string(kinds.empty() ? "" : " or ") + std::string(kind->description());
    throw InputError((dir / name).string() + ": no frames for camera " + std::to_string(cc.id) +
                     " of network.yaml (expected " + kinds + ")");
  }
  if (found.size() > 1)
    throw InputError(found[1].second.string() + ": camera " + std::to_string(cc.id) + " has both " +
                     found[0].second.filename().string() + " (" +
                     std::string(found[0].first->name()) + ") and " +
                     found[1].second.filename().string() + " (" +
                     std::string(found[1].first->name()) + "); keep one");
  try {
    cam.source = found[0].first->open(found[0].second);
  } catch (const InputError& e) {
    cam.source = blind_or_throw(e, cc.id, found[0].second, o);
    return cam;
  }
  const auto missing = cam.source->missing_frames();
  if (!missing.empty())
    o.warnings.push_back(cam.source->path().string() + ": " + std::to_string(missing.size()) +
                         " missing frame(s) (" + list_frames(missing) + "); camera " +
                         std::to_string(cc.id) + " is blind there");
  return cam;
}

// Entries for cameras network.yaml does not declare are ignored, with a warning.
void warn_undeclared(Dataset& ds) {
  std::set<std::string> declared;
  for (const auto& cc : ds.network.cameras) declared.insert("cam_" + std::to_string(cc.id));
  for (const auto& e : fs::directory_iterator(ds.dir)) {
    const std::string stem = e.path().stem().string();
    if (stem.rfind("cam_", 0) == 0 && all_digits(stem.substr(4)) && !declared.count(stem))
      ds.warnings.push_back(e.path().string() + ": camera " + stem.substr(4) +
                            " is not in network.yaml; ignored");
  }
}

// The frame count rule (dataset.hpp), over the cameras at the dataset's fps (the others keep
// their own count), and a warning for each of those with fewer or more frames.
void set_frame_count(Dataset& ds) {
  const auto own_clock = [&](size_t i) { return ds.network.camera_fps(i) != ds.network.fps; };
  int longest = 0, longest_any = 0;
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    const auto& c = ds.cameras[i];
    if (!c.source) continue;
    longest_any = std::max(longest_any, c.source->frame_count());
    if (!own_clock(i)) longest = std::max(longest, c.source->frame_count());
  }
  if (longest == 0) longest = longest_any;
  ds.frame_count = ds.network.frames ? *ds.network.frames : longest;
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    const auto& c = ds.cameras[i];
    if (!readable(c) || own_clock(i)) continue;
    const int n = c.source->frame_count();
    if (n < ds.frame_count)
      ds.warnings.push_back(c.source->path().string() + ": camera " + std::to_string(c.id) +
                            " has " + std::to_string(n) + " frames, the dataset " +
                            std::to_string(ds.frame_count) + "; it is blind from frame " +
                            std::to_string(n) + " on");
    else if (n > ds.frame_count)
      ds.warnings.push_back(c.source->path().string() + ": camera " + std::to_string(c.id) +
                            " has " + std::to_string(n) + " frames but network.yaml says frames: " +
                            std::to_string(ds.frame_count) + "; the extra frames are ignored");
  }
}

}  // namespace

Dataset open_dataset(const fs::path& dir, std::optional<int> only_camera, bool keep_going) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": dataset folder not found");
  Dataset ds;
  ds.dir = dir;
  ds.network = io::load_network_config(dir / "network.yaml");
  const bool bag = ros::RosBag::is_bag(dir);
  const std::int64_t origin = bag ? check_bag_topics(dir, ds.network) : 0;
  check_topics(ds, bag, origin);
  const CameraOpening opening{dir, bag, origin, keep_going, ds.warnings};
  for (const auto& cc : ds.network.cameras) {
    if (only_camera && cc.id != *only_camera) {  // another process's camera: its id alone
      DatasetCamera other;
      other.id = cc.id;
      ds.cameras.push_back(std::move(other));
    } else {
      ds.cameras.push_back(open_camera(cc, opening));
    }
  }
  if (!only_camera) warn_undeclared(ds);
  set_frame_count(ds);
  read_timestamps(ds);
  read_camera_poses(ds);
  return ds;
}

}  // namespace netvmo::sources
