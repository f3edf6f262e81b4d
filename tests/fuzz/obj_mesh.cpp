// Fuzz target: the OBJ mesh reader of the renderer (render::parse_obj), straight from the buffer.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "netvmo/render/geometry.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const netvmo::render::Mesh m = netvmo::render::parse_obj(text, "fuzz.obj");
    // Every face must index existing vertices.
    for (const auto& f : m.triangles)
      for (int k = 0; k < 3; ++k)
        if (f[k] >= m.vertices.size()) __builtin_trap();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
