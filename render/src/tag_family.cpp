#include "netvmo/render/tag_family.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagCircle49h12.h>
#include <apriltag/tagCustom48h12.h>
#include <apriltag/tagStandard41h12.h>
#include <apriltag/tagStandard52h13.h>

#include <stdexcept>

namespace netvmo::render {

const std::vector<TagFamily>& tag_families() {
  static const std::vector<TagFamily> families = {
      {"tag36h11", tag36h11_create, tag36h11_destroy},
      {"tag25h9", tag25h9_create, tag25h9_destroy},
      {"tag16h5", tag16h5_create, tag16h5_destroy},
      {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy},
      {"tagCircle49h12", tagCircle49h12_create, tagCircle49h12_destroy},
      {"tagCustom48h12", tagCustom48h12_create, tagCustom48h12_destroy},
      {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
      {"tagStandard52h13", tagStandard52h13_create, tagStandard52h13_destroy},
  };
  return families;
}

std::string tag_family_names() {
  std::string out;
  for (const auto& f : tag_families()) out += (out.empty() ? "" : ", ") + std::string(f.name);
  return out;
}

const TagFamily* find_tag_family(const std::string& name) {
  for (const auto& f : tag_families())
    if (name == f.name) return &f;
  return nullptr;
}

TagFamilyPtr create_tag_family(const std::string& name) {
  const TagFamily* f = find_tag_family(name);
  if (!f)
    throw std::invalid_argument("unknown tag family '" + name +
                                "' (supported: " + tag_family_names() + ")");
  TagFamilyPtr p(f->create(), f->destroy);
  if (!p) throw std::runtime_error("libapriltag could not create tag family " + name);
  return p;
}

}  // namespace netvmo::render
