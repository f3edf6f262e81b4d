// Fuzz target: the dataset's CSV readers (io/truth_io): the first byte picks truth.csv,
// target.csv, detections.csv, truth_cameras.csv (one static pose per camera), timestamps.csv,
// cameras.csv (poses per frame) or truth_cameras.csv in either form; the rest is the file.
// Accepted detection rows are formatted back (what `netvmo detect` writes), and so are accepted
// camera poses (what `netvmo render` writes).
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const int which = data[0] % 7;
  static const char* const kNames[] = {"truth.csv",         "target.csv",     "detections.csv",
                                       "truth_cameras.csv", "timestamps.csv", "cameras.csv",
                                       "truth_cameras.csv"};
  const auto path = fuzz::write_input(data + 1, size - 1, kNames[which]);
  try {
    switch (which) {
      case 0:
        (void)io::read_truth_csv(path);
        break;
      case 1:
        (void)io::read_target_csv(path);
        break;
      case 2:
        for (const auto& r : io::read_detections_csv(path)) (void)io::format_detection_row(r);
        break;
      case 3:
        (void)io::read_truth_cameras_csv(path);
        break;
      case 4:
        (void)io::read_timestamps_csv(path);
        break;
      case 5:
        for (const auto& r : io::read_camera_poses_csv(path))
          (void)io::format_camera_pose_row(r.camera, r.frame, r.t, r.g_wi);
        break;
      default:
        (void)io::read_camera_truth_csv(path);
    }
  } catch (const InputError&) {
  }
  return 0;
}
