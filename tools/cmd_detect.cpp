// netvmo detect DATASET --out DIR: runs the tag front end on every camera and frame of a dataset
// folder and writes DIR/detections.csv (one row per frame and camera, pixels).
//
// Unreadable frames (corrupt image, undecodable video frame, wrong image size): the camera is
// treated as blind for that frame (detected = 0) and the other cameras' results are kept;
// detections.csv is always complete. Without --keep-going the command then ends with one error
// line naming the first unreadable file and exit code 1; with --keep-going each is a warning and
// the exit code is 0. Dataset-level problems (network.yaml, a missing calibration, no frames for
// a camera, an unknown camera id) stop before anything is written.
#include <algorithm>
#include <cstdio>
#include <cstring>

#include "choices.hpp"
#include "commands.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/photo_recall.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/image_file.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "netvmo/pipeline/run/detect.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;
using namespace netvmo::io;
using namespace netvmo::sources;
using namespace netvmo::frontend;

namespace {

struct DetectOptions {
  std::string dataset, out;
  DetectorSettings det;
  TrackingSettings tracking;
  std::string refinement = to_string(DetectorSettings{}.refinement);
  bool no_border_check = false;
  bool no_edge_bias = false;
  bool no_shared_deviation = false;
  bool no_edge_bias_correction = false;
  bool keep_going = false;
  bool quiet = false;
  bool photos = false;  ///< DATASET is a folder of photos (run_detect_photos)
  PhotoRecallSettings recall;
};

int column_width(TargetStatus s) {
  return std::max(6, static_cast<int>(std::strlen(to_string(s))));
}

void print_truth_tally(const run::TruthTally& t) {
  std::printf("against truth.csv: fully visible tags detected, by narrowest side [px]:");
  for (size_t b = 0; b < t.visible.size(); ++b)
    std::printf(" %s %d/%d", run::TruthTally::bin_label(b).c_str(), t.detected[b], t.visible[b]);
  std::printf("; accepted %d, with a corner > 1 px off %d (max %.2f px)\n", t.accepted, t.off_1px,
              t.max_error);
}

/// The settings of both jobs from the options.
run::DetectSettings detect_settings(const DetectOptions& o) {
  run::DetectSettings s;
  s.detector = o.det;
  s.tracking = o.tracking;
  s.keep_going = o.keep_going;
  s.progress = !o.quiet;
  return s;
}

void warn(const std::string& line) {
  std::fprintf(stderr, "netvmo detect: warning: %s\n", line.c_str());
}

/// The detector settings the command line's flags and names stand for.
void apply_detector_flags(DetectOptions& o) {
  o.det.refinement = parse_refinement(o.refinement);
  o.det.border_check = !o.no_border_check;
  o.det.border_edge_bias = !o.no_edge_bias;
  o.det.border_shared_deviation = !o.no_shared_deviation;
  o.det.correct_edge_bias = !o.no_edge_bias_correction;
}

int run_detect(DetectOptions o) {
  apply_detector_flags(o);
  io::check_output_apart(o.out, o.dataset);
  io::OutputDir out(o.out, "detect");
  Dataset ds = open_dataset(o.dataset, {}, o.keep_going);
  for (const auto& w : ds.warnings) warn(w);
  const fs::path out_dir(o.out);
  io::AtomicFile csv(out.path() / "detections.csv");
  csv << kDetectionsHeader << "\n";
  const run::DatasetDetections r = run::detect_dataset(ds, detect_settings(o), csv.stream(), warn);
  csv.commit();
  out.commit();  // complete, even when frames were unreadable (reported below)
  for (const auto& w : r.warnings) warn(w);

  std::printf(
      "netvmo detect: %s -> %s (%d frames, target %s id %d%s)\n", o.dataset.c_str(),
      (out_dir / "detections.csv").string().c_str(), ds.frame_count,
      ds.network.target().family.c_str(), ds.network.target().id,
      ds.network.targets.size() > 1
          ? (", the first of " + std::to_string(ds.network.targets.size()) + " targets").c_str()
          : "");
  // Per camera: detections, then one column per reason the target was not used in a frame
  // (the `status` tokens of detections.csv), then other ids and unreadable frames.
  std::printf("%-8s %-28s %7s %7s %9s %6s %11s", "camera", "source", "frames", "images", "detected",
              "rate", "mean_margin");
  for (TargetStatus s : kAllTargetStatuses)
    if (s != TargetStatus::detected) std::printf(" %*s", column_width(s), to_string(s));
  std::printf(" %10s %10s\n", "other_ids", "unreadable");
  for (size_t c = 0; c < ds.cameras.size(); ++c) {
    const run::CameraDetections& st = r.cameras[c];
    const std::string src = ds.cameras[c].source->label();
    const double rate = st.frames ? 100.0 * st.detected / st.frames : 0.0;
    const double mm = st.detected ? st.margin_sum / st.detected : 0.0;
    std::printf("%-8d %-28s %7d %7d %9d %5.1f%% %11.1f", ds.cameras[c].id, src.c_str(), st.frames,
                st.images, st.detected, rate, mm);
    for (TargetStatus s : kAllTargetStatuses)
      if (s != TargetStatus::detected) {
        const auto it = st.by_status.find(s);
        std::printf(" %*d", column_width(s), it == st.by_status.end() ? 0 : it->second);
      }
    std::printf(" %10zu %10d\n", st.other_ids.size(), st.unreadable);
  }
  int images = 0;
  for (const auto& st : r.cameras) images += st.images;
  std::printf("front end: %.2f ms per image (mean over %d images)\n",
              images ? 1e3 * r.front_end_seconds / images : 0.0, images);
  if (r.has_truth) print_truth_tally(r.truth);
  if (!r.unreadable.empty() && !o.keep_going)
    throw InputError(r.unreadable.front() + " (" + std::to_string(r.unreadable.size()) +
                     " unreadable frame(s) in total, treated as blind in detections.csv; "
                     "fix the files or pass --keep-going)");
  return 0;
}

/// netvmo detect --photos DIR: every image below DIR (sorted; a folder's calib.yaml, an OpenCV
/// calibration, is its photos' camera) against libapriltag's own detections (photo_recall.hpp):
/// OUT/photos.csv, a line per folder and the totals with every loss by reason.
int run_detect_photos(DetectOptions o) {
  apply_detector_flags(o);
  const fs::path root(o.dataset);
  const std::vector<fs::path> files = list_images(root);
  if (files.empty()) throw InputError(o.dataset + ": no images (" + kImageExtensions + ")");
  io::check_output_apart(o.out, o.dataset);
  io::OutputDir out(o.out, "detect");
  io::AtomicFile csv(out.path() / "photos.csv");
  csv << kPhotosHeader << "\n";
  const run::PhotoDetections r =
      run::detect_photos(root, files, detect_settings(o), o.recall, csv.stream(), warn);
  csv.commit();
  out.commit();
  const auto print = [](const std::string& name, const PhotoRecall& r) {
    std::vector<double> d = r.corner_differences;
    std::sort(d.begin(), d.end());
    std::printf("%-32s %6d %9d %6d %8d %6d", name.c_str(), r.photos, r.resampled, r.references,
                r.eligible, r.kept);
    if (r.eligible > 0)  // no recall of no tags
      std::printf(" %7.1f%%", 100.0 * r.recall());
    else
      std::printf(" %8s", "-");
    if (d.empty())
      std::printf(" %8s %8s", "-", "-");
    else
      std::printf(" %8.2f %8.2f", d[d.size() / 2], d.back());
    std::string lost;
    for (const auto& [st, n] : r.lost)
      lost += (lost.empty() ? " " : ", ") + std::string(to_string(st)) + " " + std::to_string(n);
    std::printf("%s\n", lost.empty() ? " -" : lost.c_str());
  };
  std::printf("netvmo detect --photos: %s -> %s (%zu images, family %s)\n", o.dataset.c_str(),
              (fs::path(o.out) / "photos.csv").string().c_str(), files.size(),
              o.det.family.c_str());
  std::printf("eligible: libapriltag hamming 0, fully visible, narrowest side >= %g px, id once\n",
              o.recall.min_side_px);
  std::printf("%-32s %6s %9s %6s %8s %6s %8s %8s %8s %s\n", "folder", "photos", "resampled", "tags",
              "eligible", "kept", "recall", "med_px", "max_px", "lost (by reason)");
  for (const auto& [folder, f] : r.by_folder) {
    const std::string rel = fs::relative(folder, root).string();
    print(rel.empty() || rel == "." ? "." : rel, f);
  }
  print("all", r.total);
  if (r.total.resampled > 0) {
    std::string where;
    for (const auto& [folder, f] : r.by_folder)
      if (f.resampled > 0) {
        const std::string rel = fs::relative(folder, root).string();
        where += (where.empty() ? "" : ", ") + (rel.empty() ? std::string(".") : rel) + " " +
                 std::to_string(f.resampled) + " of " + std::to_string(f.photos);
      }
    std::fprintf(stderr,
                 "warning: %d of %d photos look resampled by nearest neighbour (%s; photos.csv "
                 "repeated_pairs): %s\n",
                 r.total.resampled, r.total.photos, where.c_str(), kResamplingConsequence);
  }
  if (!r.unreadable.empty() && !o.keep_going)
    throw InputError(r.unreadable.front() + " (" + std::to_string(r.unreadable.size()) +
                     " unreadable image(s) in total, left out of photos.csv; fix the files or "
                     "pass --keep-going)");
  return 0;
}

}  // namespace

void add_detect(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<DetectOptions>();
  CLI::App* cmd = add_command(
      app, "detect", "Run the AprilTag front end on a dataset folder",
      "Writes OUT/detections.csv: frame,camera,tag_id,detected,status,margin,u0,v0,...,u3,v3,\n"
      "reason (OpenCV pixels, corners in libapriltag order; empty when not detected; status is\n"
      "detected or the reason the target was not used: not_found, duplicate_id, low_margin,\n"
      "high_hamming, border_mismatch, no_image; reason says it in words) and prints a\n"
      "per-camera summary with the count of each reason. Each camera's frames are searched as\n"
      "in `netvmo run` (tracking window, acquisition pass; --no-track: every frame whole). The\n"
      "tag family and target id come from network.yaml; a target with a tag bundle has one\n"
      "row per frame, camera and tag of the body, each with that tag's own decision.");
  cmd->add_option("dataset", o->dataset,
                  "Dataset folder (network.yaml, calib/, cam_<id>/ or cam_<id>.<ext>), or with "
                  "--photos a folder of photos")
      ->required();
  cmd->add_flag("--photos", o->photos,
                "DATASET is a folder of photos (searched recursively; a folder's calib.yaml is "
                "its camera): every tag libapriltag decodes in a photo is a reference, and the "
                "front end's recall of the fully visible ones is printed with every loss by "
                "reason; OUT/photos.csv has a row per reference tag");
  cmd->add_option("--family", o->det.family, "With --photos: the tag family")
      ->capture_default_str();
  cmd->add_option("--min-side", o->recall.min_side_px,
                  "With --photos: reference tags narrower than this are not counted [px]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  cmd->add_option("--out,-o", o->out, "Output folder (created)")->required();
  cmd->add_option("--decimate", o->det.quad_decimate, "libapriltag quad_decimate (1 to 8)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 8.0));
  cmd->add_option("--sigma", o->det.quad_sigma, "libapriltag quad_sigma (Gaussian blur, 0 to 10)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option(
         "--threads", o->det.nthreads,
         "libapriltag nthreads (1 to 64; > 1 uses libapriltag 3.3's worker pool, which has "
         "a known race: DetectorSettings::nthreads)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->add_option("--refine-edges", o->det.refine_edges, "libapriltag refine_edges (true/false)")
      ->capture_default_str();
  cmd->add_option("--sharpening", o->det.decode_sharpening,
                  "libapriltag decode_sharpening (0 to 10)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--min-contrast", o->det.min_white_black_diff,
                  "libapriltag qtp.min_white_black_diff (gray levels 0 to 255; libapriltag's own "
                  "default is 5)")
      ->capture_default_str()
      ->check(CLI::Range(0, 255));
  cmd->add_option("--min-margin", o->det.min_decision_margin,
                  "Minimum decision margin to accept the target (0 to 255)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 255.0));
  cmd->add_option("--max-hamming", o->det.max_hamming,
                  "Maximum corrected bits to accept the target (0 to 3)")
      ->capture_default_str()
      ->check(CLI::Range(0, 3));
  cmd->add_flag("--no-border-check", o->no_border_check,
                "Accept the target without checking that its corners frame a black border inside "
                "a white quiet zone (the check rejects quads on an occluder's outline)");
  cmd->add_option("--border-min-contrast", o->det.border_min_contrast,
                  "Border check: a sample passes when quiet zone - border >= this x (local white "
                  "- border), 0 to 1")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--border-max-failed", o->det.border_max_failed_fraction,
                  "Border check: a side fails when more than this fraction of its samples fail (0 "
                  "to 1)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--border-max-thickness", o->det.border_max_thickness_error,
                  "Border check: a side fails when the inner edge of the border is further than "
                  "this from one cell inside it [px], 0 to 10")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--border-blur-allowance", o->det.border_blur_allowance,
                  "Border check, where the print's edge bias cannot be measured: the thinning "
                  "every side shares is discounted up to this x the measured edge blur (a "
                  "camera's tone curve thins a blurred border; 0: the fixed limit alone), 0 to "
                  "10")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_flag("--no-edge-bias", o->no_edge_bias,
                "Border check: do not measure the print's edge bias on the tag's cells (ink "
                "spread, the tone curve under blur, motion blur); hold each side's thickness "
                "error around 0 (with the shared-thinning discount) instead");
  cmd->add_option("--border-scatter-allowance", o->det.border_scatter_allowance,
                  "Border check with the print's model: a side's limit is at least this x the "
                  "scatter of the print's edges measured on its cells (0: the fixed limit), 0 to "
                  "20")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 20.0));
  cmd->add_flag("--no-shared-deviation", o->no_shared_deviation,
                "Border check: do not take the deviation every side shares (a print's border "
                "thinner or thicker than its cells) off each side");
  cmd->add_flag("--no-edge-bias-correction", o->no_edge_bias_correction,
                "Report the corners fitted to the black border's outer edges (the inked "
                "outline), not those of the print's cell grid (the measured edge bias taken off "
                "each side)");
  cmd->add_option("--border-significance", o->det.border_significance,
                  "Border check: a side fails only where its thickness error also exceeds this "
                  "many of its own standard errors (0: off), 0 to 20")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 20.0));
  cmd->add_option("--border-max-bow", o->det.border_max_bow,
                  "Border check: a quad fails where its sides bow so that a corner lies more than "
                  "this many px from where their straight lines meet (a bent print, lens "
                  "distortion not calibrated; 0: off), 0 to 100")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--border-realign-max", o->det.border_realign_max,
                  "Border check: a quad whose sides fail on their thickness alone is kept with "
                  "those sides halfway to their border's inner edge where the check passes there "
                  "and no corner moves by more than this many px (0: off), 0 to 100")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--border-bow-correction", o->det.border_bow_correction,
                  "Corners: where the sides bow so that a corner lies more than this many px "
                  "from where their straight lines meet (on cells of at least "
                  "--border-bow-min-cell), every corner is moved to where the bowed sides end "
                  "(0: off), 0 to 100")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--border-bow-min-cell", o->det.border_bow_min_cell,
                  "Corners: the bow is taken off only where the quad's narrowest cell is at "
                  "least this many px (on smaller cells flat tags look bowed), 0 to 1000")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--border-max-bent", o->det.border_max_bent,
                  "Border check: a quad that fails with sides bowed as a flat tag's are not is "
                  "checked again with its border sampled along the bowed sides, and kept with the "
                  "bow taken off where that passes and no corner moves by more than this many px "
                  "(a bent print; 0: off), 0 to 100")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--refine", o->refinement,
                  "Corner refinement of the target: none, subpix (cv::cornerSubPix) or edges "
                  "(lines fitted to the border edges)")
      ->check(CLI::IsMember({"none", "subpix", "edges"}))
      ->capture_default_str();
  add_search_options(*cmd, o->tracking);
  cmd->add_flag("--keep-going", o->keep_going,
                "Unreadable frames are warnings (camera blind there) instead of an error exit");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress line");
  cmd->callback([o, &exit_code] {
    exit_code =
        guarded("detect", [o] { return o->photos ? run_detect_photos(*o) : run_detect(*o); });
  });
}

}  // namespace netvmo::tools
