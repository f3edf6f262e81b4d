// The registry of camera stream kinds. Adding a kind: a file in this folder that defines a
// function returning its StreamKind, and one line in the table below (with its declaration).
#include "netvmo/pipeline/sources/camera_stream.hpp"

namespace netvmo::sources {

namespace kinds {
const StreamKind& image_folder();  // image_folder.cpp
const StreamKind& video();         // video.cpp
}  // namespace kinds

const obs::Registry<StreamKind>& stream_kinds() {
  static const obs::Registry<StreamKind> table{"camera stream kind",
                                               {
                                                   &kinds::image_folder(),
                                                   &kinds::video(),
                                               }};
  return table;
}

}  // namespace netvmo::sources
