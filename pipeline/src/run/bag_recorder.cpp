#include "netvmo/pipeline/run/bag_recorder.hpp"

#include <opencv2/imgcodecs.hpp>

#include "netvmo/pipeline/ros/image_msgs.hpp"
#include "netvmo/pipeline/run/overlay.hpp"
#include "netvmo/pipeline/run/ros_frame.hpp"

namespace netvmo::run {

BagRecorder::BagRecorder(const std::filesystem::path& dir, const sources::World& world,
                         BagSettings settings)
    : world_(world), settings_(settings), graph_(network_graph(world.network())), bag_(dir) {
  for (const auto& c : world.network().cameras) {
    const std::string p = "/netvmo/camera_" + std::to_string(c.id);
    Topics t;
    t.overlay = bag_.add_topic(p + "/overlay/compressed", ros::kCompressedImageType);
    t.info = bag_.add_topic(p + "/camera_info", ros::kCameraInfoType);
    t.measurement = bag_.add_topic(p + "/measurement", ros::kPoseWithCovarianceStampedType);
    t.pose = bag_.add_topic(p + "/average_pose", ros::kPoseStampedType);
    t.pose_cov =
        bag_.add_topic(p + "/average_pose_with_covariance", ros::kPoseWithCovarianceStampedType);
    topics_.push_back(t);
  }
  tf_ = bag_.add_topic("/tf", ros::kTfMessageType);
  tf_static_ = bag_.add_topic("/tf_static", ros::kTfMessageType);
}

BagRecorder::~BagRecorder() = default;

void BagRecorder::operator()(int frame, const std::vector<cv::Mat>& images,
                             const std::vector<std::vector<frontend::Observation>>& cams,
                             const std::vector<const run::FrameRecord*>& records) {
  const auto& net = world_.network();
  const FrameRecord& rec = *records.at(0);
  const double t = rec.t;
  const std::int64_t ns = ros::stamp_ns_of(t);
  std::vector<ros::StampedTransform> tf, statics;
  const bool moving = world_.cameras_move();
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    const int id = net.cameras[i].id;
    const Topics& topic = topics_[i];
    const obs::SE3 g_wi = world_.camera_believed(i, frame);
    (moving ? tf : statics).push_back(camera_transform(id, t, g_wi));
    // The overlay, as `run` draws it, and the calibration it was taken with.
    const auto& calib = world_.calibration(i);
    const int width = images[i].empty() ? calib.width : images[i].cols;
    const double scale = settings_.overlay_max_width > 0 && width > settings_.overlay_max_width
                             ? static_cast<double>(settings_.overlay_max_width) / width
                             : 1.0;
    const cv::Mat overlay =
        draw_overlay(images[i], id, calib, g_wi, overlay_layers(net, i, cams, records), scale);
    bag_.write(topic.overlay, ns,
               ros::encode_compressed_image(overlay, "jpeg", ns, ros::camera_frame(id),
                                            settings_.jpeg_quality));
    bag_.write(topic.info, ns, ros::encode_camera_info(calib, ns, ros::camera_frame(id)));
    // The measurement and the estimate with its neighbours' spread.
    const CameraRecord& c = rec.cameras[i];
    std::vector<obs::SE3> neighbours_w;
    for (int j : graph_.neighbors(static_cast<int>(i)))
      if (rec.cameras[static_cast<size_t>(j)].initialized)
        neighbours_w.push_back(rec.cameras[static_cast<size_t>(j)].est_w);
    const RosFrame f =
        ros_frame(id, t, cams.at(0)[i],
                  c.initialized ? std::optional<obs::SE3>(c.est_w) : std::nullopt, neighbours_w);
    if (f.measurement)
      bag_.write(topic.measurement, ns, ros::encode_pose_with_covariance(*f.measurement));
    if (f.average_pose) {
      bag_.write(topic.pose, ns, ros::encode_pose_stamped(*f.average_pose));
      bag_.write(topic.pose_cov, ns, ros::encode_pose_with_covariance(*f.average_pose));
    }
    tf.insert(tf.end(), f.tf.begin(), f.tf.end());
  }
  if (!statics.empty() && !statics_written_) {
    bag_.write(tf_static_, ns, ros::encode_tf_message(statics));
    statics_written_ = true;
  }
  if (!tf.empty()) bag_.write(tf_, ns, ros::encode_tf_message(tf));
}

void BagRecorder::finish() {
  bag_.close();
}

}  // namespace netvmo::run
