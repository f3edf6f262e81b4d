// The AprilTag families netvmo knows: one table from a family's name to libapriltag's create
// and destroy functions, used to print tags (render/, TagTexture) and to detect them
// (pipeline/, TagDetector and the network.yaml check).
#pragma once

#include <memory>
#include <string>
#include <vector>

// libapriltag's family struct (apriltag_family_t); include <apriltag/apriltag.h> to use it.
struct apriltag_family;

namespace netvmo::render {

struct TagFamily {
  const char* name;
  apriltag_family* (*create)();
  void (*destroy)(apriltag_family*);
};

/// Every supported family: tag36h11, tag25h9, tag16h5, tagCircle21h7, tagCircle49h12,
/// tagCustom48h12, tagStandard41h12, tagStandard52h13.
const std::vector<TagFamily>& tag_families();
/// The names of tag_families(), comma-separated, for messages.
std::string tag_family_names();
/// The family called `name`, or nullptr.
const TagFamily* find_tag_family(const std::string& name);

/// A libapriltag family, destroyed with its family's destroy function.
using TagFamilyPtr = std::unique_ptr<apriltag_family, void (*)(apriltag_family*)>;
/// Creates the family called `name`. Throws std::invalid_argument "unknown tag family 'NAME'
/// (supported: ...)" for a name not in the table, std::runtime_error if libapriltag fails.
TagFamilyPtr create_tag_family(const std::string& name);

}  // namespace netvmo::render
