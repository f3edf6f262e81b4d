// Fuzz target: OpenCV FileStorage calibration files (io::load_calibration_opencv). The first byte
// picks the file's extension (.yaml, .xml, .json); the rest is the file. An accepted calibration
// must be usable: its normalisation of the image corners is computed.
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kNames[] = {"cam_1.yaml", "cam_1.xml", "cam_1.json"};
  const auto path = fuzz::write_input(data + 1, size - 1, kNames[data[0] % 3]);
  try {
    const io::Calibration c = io::load_calibration_opencv(path);
    const std::vector<cv::Point2d> px = {{0, 0}, {c.width - 1.0, c.height - 1.0}};
    (void)io::normalize_points(px, c);
  } catch (const InputError&) {
  }
  return 0;
}
