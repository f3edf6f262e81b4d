// Fuzz target: ViSP XML calibration files (io::load_calibration_visp_xml, camera "cam_1").
#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "cam_1.xml");
  try {
    (void)io::load_calibration_visp_xml(path, "cam_1");
  } catch (const InputError&) {
  }
  return 0;
}
