#include "netvmo/pipeline/frontend/photo_recall.hpp"

#include <apriltag/apriltag.h>

#include <algorithm>
#include <map>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::frontend {

std::vector<ReferenceTag> reference_detections(const cv::Mat& gray, const std::string& family) {
  CV_Assert(gray.type() == CV_8UC1);
  const render::TagFamilyPtr fam = render::create_tag_family(family);
  DetectorSettings reference;  // libapriltag's defaults but for quad_decimate
  reference.bits_corrected = 2;
  reference.quad_decimate = 1.0;
  reference.quad_sigma = 0.0;
  reference.nthreads = 1;
  reference.refine_edges = true;
  reference.decode_sharpening = 0.25;
  reference.min_white_black_diff = 5;
  apriltag_detector_t* td = create_apriltag_detector(fam.get(), reference);
  image_u8_t im{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]),
                const_cast<uint8_t*>(gray.ptr<uint8_t>())};
  zarray_t* dets = apriltag_detector_detect(td, &im);
  std::vector<ReferenceTag> out;
  const int border = fam->width_at_border;
  for (int i = 0; dets && i < zarray_size(dets); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(dets, i, &det);
    const TagDetection d = to_tag_detection(*det);
    ReferenceTag r;
    r.id = d.id;
    r.hamming = d.hamming;
    r.margin = d.margin;
    r.corners = d.corners;
    r.narrowest = narrowest_side(r.corners);
    // The quiet zone is one cell beyond each side: every corner pushed one cell outwards from
    // the centre (along the diagonal, sqrt(2) cells) must lie in the image.
    const cv::Point2d c = 0.25 * (r.corners[0] + r.corners[1] + r.corners[2] + r.corners[3]);
    r.fully_visible = true;
    for (const auto& p : r.corners) {
      const cv::Point2d q = p + (p - c) * (2.0 / border);
      r.fully_visible = r.fully_visible && q.x >= 0 && q.y >= 0 && q.x <= gray.cols - 1.0 &&
                        q.y <= gray.rows - 1.0;
    }
    out.push_back(r);
  }
  if (dets) apriltag_detections_destroy(dets);
  apriltag_detector_destroy(td);
  std::sort(out.begin(), out.end(),
            [](const ReferenceTag& a, const ReferenceTag& b) { return a.id < b.id; });
  return out;
}

io::Calibration nominal_calibration(int width, int height) {
  io::Calibration c;
  c.width = width;
  c.height = height;
  const double f = std::max(width, height);
  c.K = cv::Matx33d(f, 0, 0.5 * (width - 1), 0, f, 0.5 * (height - 1), 0, 0, 1);
  c.source = "nominal";
  return c;
}

std::vector<PhotoTagResult> evaluate_photo(const cv::Mat& gray, const io::Calibration& calib,
                                           const DetectorSettings& settings,
                                           const TrackingSettings& tracking,
                                           const PhotoRecallSettings& recall) {
  const std::vector<ReferenceTag> refs = reference_detections(gray, settings.family);
  std::vector<PhotoTagResult> out;
  if (refs.empty()) return out;
  std::map<int, int> count;
  for (const auto& r : refs) ++count[r.id];
  // Every decoded id a target of its own, decided in one pass.
  DetectorSettings s = settings;
  s.bundle_ids.clear();
  s.tags_per_target.clear();
  std::vector<int> ids;
  for (const auto& [id, n] : count) ids.push_back(id);
  s.target_id = ids[0];
  for (size_t k = 1; k < ids.size(); ++k) s.bundle_ids.push_back(ids[k]);
  if (ids.size() > 1) s.tags_per_target.assign(ids.size(), 1);
  FrontEnd fe(s, tracking);
  TrackState track;
  const std::vector<Observation> obs = fe.observe_targets(gray, calib, nullptr, &track);
  for (const auto& r : refs) {
    PhotoTagResult t;
    t.ref = r;
    t.eligible =
        r.hamming == 0 && r.fully_visible && r.narrowest >= recall.min_side_px && count[r.id] == 1;
    const size_t k =
        static_cast<size_t>(std::lower_bound(ids.begin(), ids.end(), r.id) - ids.begin());
    const Observation& o = obs.at(k);
    t.status = o.status;
    t.reason = o.reason;
    if (o.delta) {
      t.corners_px = o.corners_px;
      for (size_t c = 0; c < 4; ++c)
        t.corner_difference =
            std::max(t.corner_difference, cv::norm(o.corners_px[c] - r.corners[c]));
    }
    std::array<cv::Point2d, 4> refined = r.corners;
    EdgeSamples edges;
    refine_corners(gray, refined, s.refinement, fe.detector().border_cells(), &calib, &edges);
    t.check = check_border(gray, refined, tag_pattern(s.family, r.id), fe.detector().border_cells(),
                           s, &calib, &edges);
    out.push_back(t);
  }
  return out;
}

void PhotoRecall::add(const std::vector<PhotoTagResult>& photo, const Resampling& resampling) {
  ++photos;
  resampled += resampling.nearest_neighbour;
  for (const auto& t : photo) {
    ++references;
    if (!t.eligible) continue;
    ++eligible;
    if (t.status == TargetStatus::detected) {
      ++kept;
      corner_differences.push_back(t.corner_difference);
    } else {
      ++lost[t.status];
    }
  }
}

}  // namespace netvmo::frontend
