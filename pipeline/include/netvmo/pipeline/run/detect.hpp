// `netvmo detect`'s two jobs: the front end on every camera and frame of a dataset (the
// per-camera step of run and node, without PnP: detections.csv, each camera's figures, and the
// tally against truth.csv where the dataset has one), and the front end on every photo below a
// folder, judged against libapriltag (photos.csv, recall per folder; frontend::evaluate_photo).
// The command prints what these return.
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/photo_recall.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"

namespace netvmo::run {

/// Settings of both jobs.
struct DetectSettings {
  frontend::DetectorSettings detector;  ///< detect_dataset sets the dataset's targets into it
  frontend::TrackingSettings tracking;
  /// An unreadable image is reported through `warn` as it comes (else only collected, for the
  /// caller's error once everything else is written).
  bool keep_going = false;
  bool progress = true;  ///< detect_dataset's progress bar on stderr
};

/// Against a rendered dataset's truth.csv: recall of fully visible tags by the narrowest side of
/// their projected black square, and accepted corners more than 1 px off. truth.csv has the
/// primary tag's corners: with a bundle, the primary's acceptance counts.
struct TruthTally {
  static constexpr double kEdges[] = {18, 24, 30, 40};  ///< bins <18, 18-24, 24-30, 30-40, >=40
  std::array<int, std::size(kEdges) + 1> visible{}, detected{};
  int accepted = 0, off_1px = 0;
  double max_error = 0.0;
  void add(const io::TruthRow& t, const frontend::Observation& o);
  /// Bin b's range of sides [px] from kEdges: "<18", "18-24", ..., ">=40".
  static std::string bin_label(size_t b);
};

/// One camera's figures over a dataset.
struct CameraDetections {
  int frames = 0, images = 0, detected = 0, unreadable = 0;
  std::map<frontend::TargetStatus, int> by_status;  ///< frames per status (detected and reasons)
  double margin_sum = 0;
  std::set<int> other_ids;  ///< decoded ids that are not the target's
};

/// What detect_dataset found.
struct DatasetDetections {
  std::vector<CameraDetections> cameras;  ///< in network.yaml's order
  bool has_truth = false;                 ///< truth.csv had rows: `truth` is their tally
  TruthTally truth;
  double front_end_seconds = 0.0;       ///< the front end's time, reading the images excluded
  std::vector<std::string> unreadable;  ///< one line per unreadable frame (blind there)
  std::vector<std::string> warnings;    ///< after the run: cameras whose images look resampled
};

/// Every camera's every frame of `ds` through the front end, the first target reported (several
/// targets are decided in one pass, as run does). Writes detections.csv's rows (not its header)
/// to `rows`: one per frame and camera, with a bundle one per tag of the body. An unreadable
/// frame leaves its camera blind there.
DatasetDetections detect_dataset(sources::Dataset& ds, const DetectSettings& s, std::ostream& rows,
                                 const std::function<void(const std::string&)>& warn);

/// What detect_photos found.
struct PhotoDetections {
  std::map<std::filesystem::path, frontend::PhotoRecall> by_folder;  ///< each photo's folder
  frontend::PhotoRecall total;
  std::vector<std::string> unreadable;  ///< one line per photo that could not be read (left out)
};

/// Every photo of `files` (below `root`, io::list_images) through frontend::evaluate_photo, with
/// one libapriltag decoding table for all. A folder's calib.yaml is its photos' camera (else a
/// nominal one); a photo of another size than it is an InputError. Writes photos.csv's rows (not
/// its header) to `rows`, each photo named relative to `root`; `on_photo`, when given, gets each
/// photo's results too.
PhotoDetections detect_photos(
    const std::filesystem::path& root, const std::vector<std::filesystem::path>& files,
    const DetectSettings& s, const frontend::PhotoRecallSettings& recall, std::ostream& rows,
    const std::function<void(const std::string&)>& warn,
    const std::function<void(const std::filesystem::path& photo,
                             const std::vector<frontend::PhotoTagResult>& tags)>& on_photo = {});

}  // namespace netvmo::run
