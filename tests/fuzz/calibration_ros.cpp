// Fuzz target: ROS camera_info calibration files (io::load_calibration_ros, after the content
// check io::looks_like_ros_camera_info that picks the format in a dataset folder). An accepted
// calibration must be usable: its normalisation of the image corners is computed.
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "cam_1.yaml");
  (void)io::looks_like_ros_camera_info(path);
  try {
    const io::Calibration c = io::load_calibration_ros(path);
    const std::vector<cv::Point2d> px = {{0, 0}, {c.width - 1.0, c.height - 1.0}};
    (void)io::normalize_points(px, c);
  } catch (const InputError&) {
  }
  return 0;
}
