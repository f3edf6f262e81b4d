#include "netvmo/pipeline/frontend/photo_recall.hpp"

#include <apriltag/apriltag.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/frontend/tag_detector.hpp"

namespace netvmo::frontend {

std::vector<ReferenceTag> reference_detections(const cv::Mat& gray, const TagDecoder& decoder) {
  CV_Assert(gray.type() == CV_8UC1);
  DetectorSettings reference;  // libapriltag's defaults but for quad_decimate
  reference.bits_corrected = kReferenceBitsCorrected;
  reference.quad_decimate = 1.0;
  reference.quad_sigma = 0.0;
  reference.nthreads = 1;
  reference.refine_edges = true;
  reference.decode_sharpening = 0.25;
  reference.min_white_black_diff = 5;
  const ApriltagDetectorPtr td = create_apriltag_detector(decoder, reference);
  image_u8_t im{gray.cols, gray.rows, static_cast<int32_t>(gray.step[0]),
                const_cast<uint8_t*>(gray.ptr<uint8_t>())};
  zarray_t* dets = apriltag_detector_detect(td.get(), &im);
  std::vector<ReferenceTag> out;
  const int border = decoder.family()->width_at_border;
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
                                           const PhotoRecallSettings& recall,
                                           std::shared_ptr<const TagDecoder> decoder) {
  decoder = TagDecoder::shared_or_new(std::move(decoder), settings.family, kReferenceBitsCorrected);
  const std::vector<ReferenceTag> refs = reference_detections(gray, *decoder);
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
  FrontEnd fe(s, tracking, decoder);  // (its own decoder where s corrects other bits)
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

const char* const kPhotosHeader =
    "file,id,hamming,libapriltag_margin,narrowest_px,fully_visible,eligible,status,"
    "corner_difference_px,reason,check_e0,check_e1,check_e2,check_e3,expected_e0,expected_e1,"
    "expected_e2,expected_e3,edge_bias_x,edge_bias_y,edge_blur,scatter_x,scatter_y,se0,se1,se2,"
    "se3,shared_deviation,bow_px,bow_se,bent,inner_bow,inner_bow_se,apriltag_x0,apriltag_y0,"
    "apriltag_x1,apriltag_y1,"
    "apriltag_x2,apriltag_y2,apriltag_x3,apriltag_y3,x0,y0,x1,y1,x2,y2,x3,y3,check_reason,"
    "edge_pairs,repeated_pairs";

std::string format_photo_row(const std::string& file, const PhotoTagResult& t,
                             const Resampling& resampling) {
  std::string row = file + ",";
  char buf[160];
  std::snprintf(buf, sizeof buf, "%d,%d,%.2f,%.2f,%d,%d,%s,", t.ref.id, t.ref.hamming, t.ref.margin,
                t.ref.narrowest, t.ref.fully_visible, t.eligible, to_string(t.status));
  row += buf;
  if (t.status == TargetStatus::detected) {
    std::snprintf(buf, sizeof buf, "%.3f", t.corner_difference);
    row += buf;
  }
  std::string reason = t.reason, check_reason = t.check.reason;
  std::replace(reason.begin(), reason.end(), ',', ';');
  std::replace(check_reason.begin(), check_reason.end(), ',', ';');
  row += "," + reason;
  // The frame check on libapriltag's own (refined) quad.
  const BorderCheck& b = t.check;
  std::snprintf(buf, sizeof buf,
                ",%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,",
                b.thickness_error[0], b.thickness_error[1], b.thickness_error[2],
                b.thickness_error[3], b.expected_thickness_error[0], b.expected_thickness_error[1],
                b.expected_thickness_error[2], b.expected_thickness_error[3], b.edge_bias[0],
                b.edge_bias[1], b.edge_blur, b.edge_bias_scatter[0], b.edge_bias_scatter[1]);
  row += buf;
  std::snprintf(buf, sizeof buf, "%.3f,%.3f,%.3f,%.3f,%.3f,", b.thickness_se[0], b.thickness_se[1],
                b.thickness_se[2], b.thickness_se[3], b.shared_deviation);
  row += buf;
  // The bow of the same quad's sides (where the other tests passed): the largest shift of a
  // corner and its standard error (empty where not measured).
  if (b.bow.measured) {
    size_t w = 0;
    for (size_t k = 1; k < 4; ++k)
      if (cv::norm(b.bow.corner_shift[k]) > cv::norm(b.bow.corner_shift[w])) w = k;
    std::snprintf(buf, sizeof buf, "%.3f,%.3f,", cv::norm(b.bow.corner_shift[w]),
                  b.bow.corner_se[w]);
    row += buf;
  } else {
    row += ",,";
  }
  // Kept as a bent print (BorderCheck::bent), and how far the border's inner edge bows with its
  // outer one where that was measured (BorderCheck::inner_bow, its standard error; else empty).
  row += b.bent ? "1," : "0,";
  if (!std::isnan(b.inner_bow)) {
    std::snprintf(buf, sizeof buf, "%.3f,%.3f,", b.inner_bow, b.inner_bow_se);
    row += buf;
  } else {
    row += ",,";
  }
  // The corners [OpenCV pixels, libapriltag's order]: libapriltag's, then the front end's
  // (empty unless it kept the tag).
  const auto corners = [&](const std::array<cv::Point2d, 4>& c) {
    std::snprintf(buf, sizeof buf, "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,", c[0].x, c[0].y,
                  c[1].x, c[1].y, c[2].x, c[2].y, c[3].x, c[3].y);
    row += buf;
  };
  corners(t.ref.corners);
  if (t.status == TargetStatus::detected)
    corners(t.corners_px);
  else
    row += ",,,,,,,,";
  std::snprintf(buf, sizeof buf, ",%ld,%.4f", resampling.pairs, resampling.repeated);
  return row + check_reason + buf;
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
