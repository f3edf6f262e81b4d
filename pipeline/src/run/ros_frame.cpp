#include "netvmo/pipeline/run/ros_frame.hpp"

#include "netvmo/observer/metrics.hpp"

namespace netvmo::run {

RosFrame ros_frame(int camera_id, double t, const frontend::Observation& cam,
                   const std::optional<obs::SE3>& estimate_w,
                   const std::vector<obs::SE3>& neighbours_w) {
  RosFrame out;
  const std::int64_t ns = ros::stamp_ns_of(t);
  if (cam.delta && cam.g_io_pnp)
    out.measurement =
        ros::StampedPose{ns, ros::camera_frame(camera_id), *cam.g_io_pnp, cam.pnp_covariance};
  if (estimate_w) {
    out.average_pose = ros::StampedPose{ns, ros::kWorldFrame, *estimate_w,
                                        obs::neighbour_spread(*estimate_w, neighbours_w)};
    out.tf.push_back({ns, ros::kWorldFrame, ros::estimate_frame(camera_id), *estimate_w});
  }
  return out;
}

ros::StampedTransform camera_transform(int camera_id, double t, const obs::SE3& g_wi) {
  return {ros::stamp_ns_of(t), ros::kWorldFrame, ros::camera_frame(camera_id), g_wi};
}

}  // namespace netvmo::run
