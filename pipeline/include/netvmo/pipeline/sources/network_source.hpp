// Where a run's images come from and what is known of the world they show, as two interfaces:
// ImageStreams (every camera's frames) and World (the camera network, calibrations, believed
// poses, the images' clocks, ground truth when it is known). A NetworkSource is both: a dataset
// folder (rendered or recorded), the live renderer, or live camera topics. A stage takes the
// part it reads.
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"

namespace netvmo::sources {

/// Every camera's images, by frame index.
class ImageStreams {
 public:
  virtual ~ImageStreams() = default;
  virtual int frame_count() const = 0;
  /// The frames of one camera: frame_count(), or its own count when it runs at its own fps.
  virtual int camera_frame_count(size_t camera_index) const {
    (void)camera_index;
    return frame_count();
  }
  /// 8-bit gray image of a camera at a frame; empty when the camera has none there. Throws
  /// InputError naming the file when an image exists but cannot be read. Thread-safe for
  /// different cameras, at any frames (one_frame_at_a_time: of the same frame).
  virtual cv::Mat read(size_t camera_index, int frame) = 0;
  /// Whether reads of different frames at once would only queue (a renderer that holds one
  /// frame's scene at a time): the front end then reads one frame at a time.
  virtual bool one_frame_at_a_time() const { return false; }
};

/// What is known of the world the images show: the camera network (network.yaml: cameras,
/// graph, targets), every camera's calibration and believed pose, the images' clocks, and the
/// ground truth when it is known.
class World {
 public:
  virtual ~World() = default;
  virtual const io::NetworkConfig& network() const = 0;
  virtual const io::Calibration& calibration(size_t camera_index) const = 0;
  /// True pose in the world of target `target` (index in network().targets) at a frame, when
  /// known.
  virtual std::optional<obs::SE3> target_truth(int frame, size_t target = 0) const = 0;
  /// True pose of a camera in the world at a frame, when known.
  virtual std::optional<obs::SE3> camera_truth(size_t camera_index, int frame) const = 0;
  /// Believed pose g_wi of a camera at a frame (cameras.csv, the live renderer); by default
  /// network()'s, the camera being static.
  virtual obs::SE3 camera_believed(size_t camera_index, int frame) const {
    (void)frame;
    return network().cameras.at(camera_index).g_wi;
  }
  /// Whether some camera's believed pose differs from network()'s at some frame (moving
  /// cameras, or a cameras.csv that overrides network.yaml).
  virtual bool cameras_move() const { return false; }
  /// The time [s] of a camera's image (timestamps.csv for dataset folders), by default
  /// frame / the camera's fps.
  virtual double frame_time(size_t camera_index, int frame) const {
    return listed_time(camera_index, frame).value_or(frame / network().camera_fps(camera_index));
  }
  /// The time a dataset's timestamps.csv gives that image, if any (none by default).
  virtual std::optional<double> listed_time(size_t camera_index, int frame) const {
    (void)camera_index;
    (void)frame;
    return std::nullopt;
  }

  // Ground truth and believed poses at any time t [s] (cameras on their own clocks: the run's
  // regular grid falls between images), interpolated on the geodesic between the nearest
  // recorded poses (pose_at).
  /// True pose of target `target` at time t, when known (dataset: target.csv's rows, or
  /// target_<id>.csv's for a later target, by their t).
  virtual std::optional<obs::SE3> target_truth_at(double t, size_t target = 0) const {
    (void)t;
    (void)target;
    return std::nullopt;
  }
  /// True pose of a camera at time t, when known (dataset: truth_cameras.csv by the times of the
  /// camera's images).
  virtual std::optional<obs::SE3> camera_truth_at(size_t camera_index, double t) const {
    (void)camera_index;
    (void)t;
    return std::nullopt;
  }
  /// Believed pose of a camera at time t (dataset: cameras.csv by the times of its images); by
  /// default network()'s.
  virtual obs::SE3 camera_believed_at(size_t camera_index, double t) const {
    (void)t;
    return network().cameras.at(camera_index).g_wi;
  }
};

/// A run's source: its images and their world, from a dataset folder (rendered or recorded),
/// the live renderer, or live camera topics.
class NetworkSource : public ImageStreams, public World {
 public:
  /// A name for messages and summaries.
  virtual std::string name() const = 0;
  /// Warnings found when opening (missing frames, short cameras, ...), one line each.
  virtual std::vector<std::string> warnings() const { return {}; }
  /// Information for the log (e.g. where the image times come from), one line each.
  virtual std::vector<std::string> notes() const { return {}; }
};

/// The pose at time t of a sequence of poses at strictly increasing times: poses[k] where
/// |t - times[k]| <= tol, else g_k exp(s log(g_k^-1 g_k+1)), s = (t - t_k) / (t_k+1 - t_k),
/// between the two around t (the geodesic, as the renderer's keyframes); nothing outside
/// [times.front() - tol, times.back() + tol] or for an empty sequence.
std::optional<obs::SE3> pose_at(const std::vector<double>& times,
                                const std::vector<obs::SE3>& poses, double t, double tol);

/// One camera's images on its clock: (frame, time) in frame order. A camera that
/// timestamps.csv lists (or whose video gives times) has an image at each frame with a time;
/// otherwise at frames 0 .. camera_frame_count - 1, at frame / its fps.
std::vector<std::pair<int, double>> camera_images(const NetworkSource& source, size_t camera_index);

/// Why the cameras do not share one clock (a camera at its own fps, or two cameras whose images
/// of the same frame index have different times: listed in timestamps.csv for both, or for one
/// and frame / fps for the other), or nothing when they do. `netvmo run` and
/// lock-step processes need a common clock.
std::optional<std::string> clock_mismatch(const NetworkSource& source);

/// Why the cameras' common clock is not the dataset's fps (an image whose time, counted from
/// the first image, differs from frame / fps by more than 1 us), or nothing when it is. The
/// synchronised run steps by 1 / fps; `netvmo run` takes the union of timestamps otherwise.
std::optional<std::string> irregular_clock(const NetworkSource& source);

/// Refuses (InputError, one line naming `what`) a source whose cameras move: `what` handles
/// static cameras only.
void require_static_cameras(const NetworkSource& source, const std::string& what);

/// Refuses (InputError, one line naming network.yaml's targets and `what`) a source with several
/// targets: `what` runs one target's observer only.
void require_single_target(const World& world, const std::string& what);

/// A dataset folder (sources/dataset.hpp documents the layout). Ground truth is read from
/// target.csv (true poses of the first target; target_<id>.csv for each later target of
/// network.yaml's `targets:`, id its primary tag's) and truth_cameras.csv (true camera poses per
/// frame, or one per camera in older datasets) when both are present; believed camera poses per
/// frame from cameras.csv when present. `only_camera`, `keep_going`: see open_dataset.
/// `shown_as`: the source's name() (summary.json's `dataset`) when not empty, e.g. the final path
/// of a dataset that is read from an output folder's temporary copy (io::OutputDir) and is
/// renamed when the command ends; empty: `dir`.
std::unique_ptr<NetworkSource> open_dataset_source(const std::filesystem::path& dir,
                                                   std::optional<int> only_camera = {},
                                                   bool keep_going = false,
                                                   const std::filesystem::path& shown_as = {});

}  // namespace netvmo::sources
