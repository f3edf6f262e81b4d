// Images resampled by nearest neighbour: an image enlarged or rectified by copying, for each
// output pixel, the nearest pixel of its source (cv::INTER_NEAREST, as some published datasets
// are rectified) repeats source pixels. On such images every edge is placed only to within half
// a source pixel, independently at a border's outer and inner edges, and the frame check keeps
// some quads with a side 1-1.5 px off (docs/frontend.md, "Resampled images"). netvmo takes raw
// frames with their calibration; this tells a user when a camera's frames were not.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace netvmo::frontend {

struct ResamplingSettings {
  /// A pair of neighbouring pixels along a row or column lies on a steep edge when the pixel
  /// before it and the pixel after it each step the same way by at least this many grey levels.
  int min_step = 8;
  /// The image looks resampled by nearest neighbour when more than this fraction of those pairs
  /// are exactly equal. A nearest-neighbour copy at magnification m repeats about 1 - 1/m of its
  /// pixels (0.25 at m = 1.33); in a camera's own image an equal pair on a steep edge needs the
  /// noise to cancel the slope: at most 0.020 in each of 82 real photos of the corpus, 0.70-0.74
  /// in each of its 15 nearest-neighbour-rectified ones (magnification about 1.65).
  double max_repeated = 0.25;
  /// Fewer such pairs than this decide nothing (an image with hardly an edge).
  int min_pairs = 200;
};

/// What measure_resampling() found in one image.
struct Resampling {
  long pairs = 0;                  ///< pairs of neighbouring pixels on steep edges
  double repeated = 0.0;           ///< the fraction of them exactly equal (0 without pairs)
  bool nearest_neighbour = false;  ///< repeated > max_repeated over at least min_pairs pairs
};

/// Counts the pairs of neighbouring pixels on steep edges, along rows and columns, and how many
/// are exactly equal. `gray`: CV_8UC1.
Resampling measure_resampling(const cv::Mat& gray, const ResamplingSettings& s = {});

/// What nearest-neighbour resampling does to the front end: the end of every warning about it
/// (a camera's, below; `netvmo detect --photos`'s).
inline constexpr const char* kResamplingConsequence =
    "edges are placed only to half a source pixel there and the frame check may keep a quad with "
    "a side 1-1.5 px off (docs/frontend.md, \"Resampled images\")";

/// The warning for camera `camera_id` whose first image measured `r`; none unless it looks
/// resampled by nearest neighbour.
std::optional<std::string> resampling_warning(int camera_id, const Resampling& r);

}  // namespace netvmo::frontend
