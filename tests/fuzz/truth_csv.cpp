// Fuzz target: the dataset's CSV readers (io/truth_io): the first byte picks truth.csv,
// target.csv, detections.csv, truth_cameras.csv or timestamps.csv; the rest is the file. Accepted
// detection rows are formatted back (what `netvmo detect` writes).
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const int which = data[0] % 5;
  static const char* const kNames[] = {"truth.csv", "target.csv", "detections.csv",
                                       "truth_cameras.csv", "timestamps.csv"};
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
      default:
        (void)io::read_timestamps_csv(path);
    }
  } catch (const InputError&) {
  }
  return 0;
}
