#include "fuzz_input.hpp"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <system_error>

namespace netvmo::fuzz {
namespace fs = std::filesystem;

namespace {

struct Scratch {
  fs::path dir;
  Scratch() {
    const char* t = std::getenv("TMPDIR");
    std::string pattern = std::string(t && *t ? t : "/tmp") + "/netvmo_fuzz.XXXXXX";
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed: " + pattern);
    dir = pattern;
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

}  // namespace

const fs::path& scratch_dir() {
  static const Scratch s;
  return s.dir;
}

fs::path write_input(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const fs::path p = scratch_dir() / name;
  std::FILE* f = std::fopen(p.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + p.string());
  const bool ok = size == 0 || std::fwrite(data, 1, size, f) == size;
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error("cannot write " + p.string());
  return p;
}

}  // namespace netvmo::fuzz
