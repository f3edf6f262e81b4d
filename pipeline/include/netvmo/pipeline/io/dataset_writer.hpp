// Writes a rendered dataset folder (layout in datasets/README.md):
//   cam_<id>/<frame:06d>.png   8-bit grayscale images
//   calib/cam_<id>.yaml        OpenCV FileStorage: image_width, image_height, camera_matrix,
//                              distortion_coefficients (1x5)
//   network.yaml               fps, frames, target {family, id, size},
//                              cameras [{id, p_wi, r_wi, fps?}] (believed poses), edges
//   timestamps.csv             camera,frame,t (every image's time)
//   truth.csv                  frame,t,camera,in_fov,visible_fraction,u0,v0,...,u3,v3 (per
//                              camera image: its own frame and time)
//   target.csv                 frame,t,px,py,pz,rx,ry,rz (true target pose in the world at
//                              every image time of any camera; frame = index of that time)
//   cameras.csv                camera,frame,t,px,py,pz,rx,ry,rz (believed camera poses g_wi
//                              per camera image; frame 0 is network.yaml's)
//   truth_cameras.csv          camera,frame,t,px,py,pz,rx,ry,rz (true camera poses per image)
// Every file is written to a temporary sibling and renamed into place.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "netvmo/render/renderer.hpp"

namespace netvmo::io {

/// The most frames `netvmo render`, `demo` and `bench` write: 5 cameras of 640x480 PNGs take
/// ~1 MB a frame, so 100,000 frames (55 minutes at 30 frames/s) are ~100 GB.
inline constexpr int kMaxDatasetFrames = 100000;

struct DatasetSettings {
  int frames = 0;        ///< frames to write; 0 = the scene's frame count
  bool progress = true;  ///< progress bar on stderr
};

struct CameraDatasetStats {
  int id = 0;
  int frames_in_fov = 0;   ///< frames with the whole tag inside the field of view
  int frames_visible = 0;  ///< frames with visible_fraction > 0
  int images = 0;          ///< its images (frames, or fewer or more on its own clock)
};

struct DatasetSummary {
  int frames = 0;
  std::vector<CameraDatasetStats> cameras;
};

/// Renders every camera at its image times (render::SceneDescription::image_times: frames
/// 0..N-1 at the scene's fps, or its own fps and start) and writes the dataset folder `out`
/// (created if needed; existing files of the same names are replaced).
DatasetSummary write_dataset(render::Renderer& renderer, const std::filesystem::path& out,
                             const DatasetSettings& options = {});

}  // namespace netvmo::io
