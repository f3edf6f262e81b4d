#include "netvmo/pipeline/net/play.hpp"

#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>
#include <tuple>
#include <vector>

#include "dds_util.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/ros/pose_msgs.hpp"

namespace netvmo::net {

namespace {

using detail::check;

// A participant that deletes itself (and every entity under it).
struct Participant {
  dds_entity_t id;
  Participant(int domain, const SecurityIdentity* security)
      : id(create_participant(domain, security, "create participant (check CYCLONEDDS_URI)")) {}
  ~Participant() { dds_delete(id); }
};

dds_entity_t writer(dds_entity_t participant, const std::string& name,
                    const dds_topic_descriptor_t& type, bool reliable) {
  const dds_entity_t topic =
      check(dds_create_topic(participant, &type, name.c_str(), nullptr, nullptr), "topic");
  dds_qos_t* q = dds_create_qos();
  if (reliable)
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  else
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 5);
  const dds_entity_t w = dds_create_writer(participant, topic, q, nullptr);
  dds_delete_qos(q);
  return check(w, "create writer");
}

}  // namespace

PlayStats play(sources::NetworkSource& source, const PlaySettings& s,
               const std::function<void(int, int)>& progress) {
  const bool raw = s.encoding == "mono8" || s.encoding == "rgb8";
  if (!raw && s.encoding != "jpeg" && s.encoding != "png")
    throw InputError("--encoding " + s.encoding + ": expected mono8, rgb8, jpeg or png");
  if (!(s.rate >= 0.0)) throw InputError("--rate must be >= 0");
  if (!(s.settle_s >= 0.0) || !(s.linger_s >= 0.0))
    throw InputError("--settle and --linger must be >= 0");
  const auto& net = source.network();
  Participant p(s.domain, s.security ? &*s.security : nullptr);
  std::vector<dds_entity_t> images, infos;
  for (const auto& c : net.cameras) {
    const std::string prefix = "rt/cam_" + std::to_string(c.id);
    images.push_back(raw ? writer(p.id, prefix + "/image_raw", ros::image_descriptor(), s.reliable)
                         : writer(p.id, prefix + "/image_raw/compressed",
                                  ros::compressed_image_descriptor(), s.reliable));
    if (s.camera_info)
      infos.push_back(
          writer(p.id, prefix + "/camera_info", ros::camera_info_descriptor(), s.reliable));
  }
  if (s.wait_readers > 0 && !detail::wait_for_readers(images, s.wait_readers, s.timeout_s)) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "--wait-readers %d: fewer readers of every camera's image topic within %g s",
                  s.wait_readers, s.timeout_s);
    throw InputError(buf);
  }
  const auto best_effort_reader = [&] {
    for (const auto* writers : {&images, &infos})
      for (dds_entity_t w : *writers)
        if (detail::has_best_effort_reader(w)) return true;
    return false;
  };
  // A reader takes a writer's samples only once it has itself discovered the writer, and a
  // best-effort reader tells play nothing (no acknowledgements): play's side of a match can come
  // before the reader's. A live node's reader missed the first image in 4 of 40 plays at --rate
  // 0 without load and 8 of 40 under stress-ng --cpu 4 when play wrote right after its match;
  // 10 ms later, none of 40 without load. So where a best-effort reader matches, the first image
  // waits settle_s.
  if (s.settle_s > 0.0 && best_effort_reader())
    std::this_thread::sleep_for(std::chrono::duration<double>(s.settle_s));
  // Every image in time order (ties: camera order).
  std::vector<std::tuple<double, size_t, int>> order;
  for (size_t i = 0; i < net.cameras.size(); ++i)
    for (int f = 0; f < source.camera_frame_count(i); ++f)
      order.emplace_back(source.frame_time(i, f), i, f);
  std::sort(order.begin(), order.end());
  PlayStats stats;
  if (order.empty()) return stats;
  const double t0 = std::get<0>(order.front());
  const auto start = std::chrono::steady_clock::now();
  for (const auto& [t, i, f] : order) {
    if (s.rate > 0) {
      const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>((t - t0) / s.rate));
      std::this_thread::sleep_until(due);
      stats.late_s =
          std::max(stats.late_s,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - due).count());
    }
    const cv::Mat gray = source.read(i, f);
    const std::int64_t ns = ros::stamp_ns_of(t);
    const std::string frame_id = ros::camera_frame(net.cameras[i].id);
    const auto write = [&](dds_entity_t w) {
      return [w](const void* m) { check(dds_write(w, m), "write"); };
    };
    if (raw)
      ros::with_image(gray, s.encoding, ns, frame_id, write(images[i]));
    else
      ros::with_compressed_image(gray, s.encoding, ns, frame_id, 95, write(images[i]));
    if (s.camera_info) ros::with_camera_info(source.calibration(i), ns, frame_id, write(infos[i]));
    ++stats.images;
    if (progress) progress(stats.images, static_cast<int>(order.size()));
  }
  const auto last = std::chrono::steady_clock::now();
  stats.seconds = std::chrono::duration<double>(last - start).count();
  // The writers stay until their readers have the last images. Reliable readers acknowledge
  // (each writer waits up to linger_s). A best-effort reader does not, and deleting a writer
  // right after its last write can leave that reader with part of the last image only (its
  // first fragments, measured with Cyclone DDS's trace), i.e. without it: the last of 30 images
  // was lost in 13 of 64 plays at --rate 0, without load. So with a best-effort reader on any
  // topic, the writers stay linger_s after the last image.
  if (s.reliable)
    for (const auto* writers : {&images, &infos})
      for (dds_entity_t w : *writers)
        dds_wait_for_acks(w, static_cast<dds_duration_t>(s.linger_s * 1e9));
  if (best_effort_reader())
    std::this_thread::sleep_until(last +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(s.linger_s)));
  return stats;
}

}  // namespace netvmo::net
