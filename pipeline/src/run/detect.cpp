#include "netvmo/pipeline/run/detect.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <opencv2/core.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/resampling.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/image_file.hpp"
#include "netvmo/pipeline/progress.hpp"
#include "netvmo/pipeline/run/camera_step.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::run {
namespace fs = std::filesystem;
using frontend::Observation;

void TruthTally::add(const io::TruthRow& t, const Observation& o) {
  const bool primary = o.delta && o.slots.front() == 0;
  if (primary && t.corners) {
    ++accepted;
    double e = 0.0;
    for (size_t k = 0; k < 4; ++k) e = std::max(e, cv::norm(o.corners_px[k] - (*t.corners)[k]));
    off_1px += e > 1.0;
    max_error = std::max(max_error, e);
  }
  if (!t.in_fov || t.visible_fraction < 0.999 || !t.corners) return;
  const double side = frontend::narrowest_side(*t.corners);
  size_t bin = 0;
  while (bin < std::size(kEdges) && side >= kEdges[bin]) ++bin;
  ++visible[bin];
  detected[bin] += primary;
}

std::string TruthTally::bin_label(size_t b) {
  const auto edge = [](size_t k) {
    char s[32];
    std::snprintf(s, sizeof s, "%g", kEdges[k]);
    return std::string(s);
  };
  const size_t n = std::size(kEdges);
  if (b == 0) return "<" + edge(0);
  if (b >= n) return ">=" + edge(n - 1);
  return edge(b - 1) + "-" + edge(b);
}

DatasetDetections detect_dataset(sources::Dataset& ds, const DetectSettings& s, std::ostream& rows,
                                 const std::function<void(const std::string&)>& warn) {
  frontend::DetectorSettings det = s.detector;
  frontend::set_targets(det, ds.network.targets);
  const auto& target = ds.network.target();
  std::set<int> body_ids;
  for (size_t k = 0; k < target.tag_count(); ++k) body_ids.insert(target.tag_id(k));
  frontend::FrontEnd fe(det, s.tracking);

  DatasetDetections out;
  out.cameras.resize(ds.cameras.size());
  std::vector<frontend::TrackState> tracks(ds.cameras.size());
  std::map<std::pair<int, int>, io::TruthRow> truth;  // (frame, camera) -> row
  if (fs::exists(ds.dir / "truth.csv"))
    for (auto& t : io::read_truth_csv(ds.dir / "truth.csv")) truth[{t.frame, t.camera}] = t;
  out.has_truth = !truth.empty();
  Progress progress("detect", ds.frame_count, s.progress);
  std::vector<Observation> cams;
  for (int f = 0; f < ds.frame_count; ++f) {
    for (size_t c = 0; c < ds.cameras.size(); ++c) {
      CameraDetections& st = out.cameras[c];
      ++st.frames;
      // The per-camera step of run and node, without PnP: an unreadable image is a blind frame.
      cv::Mat img;
      frontend::FrameDetections all;
      double reading = 0.0;
      const auto t0 = Clock::now();
      if (const auto error = observe_camera([&] { return ds.read(c, f); }, ds.cameras[c].calib, fe,
                                            tracks[c], ds.network.targets, s.keep_going, img, cams,
                                            &reading, &all, /*pnp=*/false)) {
        try {
          std::rethrow_exception(error);
        } catch (const InputError& e) {
          ++st.unreadable;
          out.unreadable.push_back(e.what());
          if (s.keep_going) warn(std::string(e.what()) + " (camera blind there)");
        }
      }
      out.front_end_seconds += seconds_since(t0) - reading;
      if (!img.empty()) ++st.images;
      const Observation& obs = cams.front();
      if (const auto it = truth.find({f, ds.cameras[c].id}); it != truth.end())
        out.truth.add(it->second, obs);
      for (const auto& d : all.all)
        if (!body_ids.count(d.id)) st.other_ids.insert(d.id);
      ++st.by_status[obs.status];
      if (obs.delta) {
        ++st.detected;
        st.margin_sum += obs.margin;
      }
      if (!target.bundle.empty()) {
        // A bundle: one row per tag of the body (primary, then bundle order), each with that
        // tag's own decision; the camera's delta is 1 when any of its rows has detected = 1.
        for (size_t k = 0; k < target.tag_count(); ++k) {
          io::DetectionRow row;
          row.frame = f;
          row.camera = ds.cameras[c].id;
          row.tag_id = target.tag_id(k);
          if (k < all.tags.size()) {
            const frontend::TagDecision& d = all.tags[k];
            row.detected = d.index >= 0;
            row.status = d.status;
            row.reason = d.reason;
            if (row.detected) {
              row.margin = all.all[static_cast<size_t>(d.index)].margin;
              row.corners = all.all[static_cast<size_t>(d.index)].corners;
            }
          } else {
            row.status = obs.status;  // not searched (no image)
            row.reason = obs.reason;
          }
          rows << io::format_detection_row(row) << "\n";
        }
        continue;
      }
      io::DetectionRow row;
      row.frame = f;
      row.camera = ds.cameras[c].id;
      row.tag_id = det.target_id;
      row.detected = obs.delta;
      row.status = obs.status;
      row.reason = obs.reason;
      if (obs.delta) {
        row.margin = obs.margin;
        row.corners = obs.corners_px;
      }
      rows << io::format_detection_row(row) << "\n";
    }
    progress.update(f + 1);
  }
  progress.finish();
  for (size_t c = 0; c < ds.cameras.size(); ++c)
    if (tracks[c].resampling)
      if (auto w = frontend::resampling_warning(ds.cameras[c].id, *tracks[c].resampling))
        out.warnings.push_back(*w);
  return out;
}

PhotoDetections detect_photos(
    const fs::path& root, const std::vector<fs::path>& files, const DetectSettings& s,
    const frontend::PhotoRecallSettings& recall, std::ostream& rows,
    const std::function<void(const std::string&)>& warn,
    const std::function<void(const fs::path& photo,
                             const std::vector<frontend::PhotoTagResult>& tags)>& on_photo) {
  // libapriltag's decoding table, built once for every photo (evaluate_photo).
  const auto decoder = std::make_shared<const frontend::TagDecoder>(
      s.detector.family, frontend::kReferenceBitsCorrected);
  std::map<fs::path, io::Calibration> calibs;  // a folder's calib.yaml
  PhotoDetections out;
  for (const fs::path& f : files) {
    const fs::path folder = f.parent_path();
    cv::Mat gray;
    try {
      gray = io::read_gray_image(f);
    } catch (const InputError& e) {
      out.unreadable.push_back(e.what());
      if (s.keep_going) warn(out.unreadable.back());
      continue;
    }
    io::Calibration calib = frontend::nominal_calibration(gray.cols, gray.rows);
    if (const fs::path cf = folder / "calib.yaml"; fs::exists(cf)) {
      if (!calibs.count(folder)) calibs[folder] = io::load_calibration_yaml(cf);
      calib = calibs[folder];
      if (calib.width != gray.cols || calib.height != gray.rows)
        throw InputError(f.string() + ": " + std::to_string(gray.cols) + "x" +
                         std::to_string(gray.rows) + " image, but " + cf.string() + " is for " +
                         std::to_string(calib.width) + "x" + std::to_string(calib.height));
    }
    const auto results =
        frontend::evaluate_photo(gray, calib, s.detector, s.tracking, recall, decoder);
    // Whether the photo was resampled by nearest neighbour (docs/frontend.md, "Resampled images").
    const frontend::Resampling resampling = frontend::measure_resampling(gray);
    out.by_folder[folder].add(results, resampling);
    out.total.add(results, resampling);
    const std::string rel = fs::relative(f, root).string();
    for (const auto& t : results) rows << frontend::format_photo_row(rel, t, resampling) << "\n";
    if (on_photo) on_photo(f, results);
  }
  return out;
}

}  // namespace netvmo::run
