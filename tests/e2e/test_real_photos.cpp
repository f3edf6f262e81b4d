// The front end on real photos (docs/frontend.md, "Real photos"): every fully visible tag that
// libapriltag itself decodes with hamming 0 is a reference, and the front end should keep it.
//  - RealPhotos.DeskPhoto...: a real photo every CI machine has: Debian's visp-images-data
//    (installed by tools/install_deps.sh; read where the package puts it, not copied into the
//    project), ViSP's AprilTag.pgm, a 640x480 photo of a printed sheet of twelve 53 mm
//    tag36h11 tags (ids 8-19) on a desk, seen about 55 degrees off the sheet's normal, with
//    ViSP's own pose estimates of each tag beside it (ground_truth_pose.txt; the camera
//    parameters and tag size are those of ViSP's regression test of that file).
//  - RealPhotos.PhotosInTheRepository: the 29 photos of datasets/real_photos/photos (part of the
//    corpus below, with their licences), in every CI run.
//  - RealPhotos.Corpus: the corpus of datasets/real_photos/MANIFEST.md, assembled by
//    tools/real_photos.sh, where it is: $NETVMO_REAL_PHOTOS, else real_photos/ in the shared
//    folder beside the checkout. Skipped, with that reason, where it is not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/border_check.hpp"
#include "netvmo/pipeline/frontend/photo_recall.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/io/image_file.hpp"
#include "netvmo/pipeline/run/detect.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;
using namespace frontend;

const fs::path kVispPhotoDir = "/usr/share/visp-images-data/ViSP-images/AprilTag";

/// ViSP's pose estimates of the desk photo's tags: id -> (t, theta u) of cMo.
std::map<int, std::pair<obs::Vec3, obs::Vec3>> read_visp_poses(const fs::path& file) {
  std::map<int, std::pair<obs::Vec3, obs::Vec3>> out;
  std::ifstream in(file);
  std::string label;
  while (in >> label) {
    const auto at = label.rfind('_');
    if (at == std::string::npos) break;
    const int id = std::stoi(label.substr(at + 1));
    obs::Vec3 t, r;
    in >> t.x() >> t.y() >> t.z() >> r.x() >> r.y() >> r.z();
    out[id] = {t, r};
  }
  return out;
}

TEST(RealPhotos, DeskPhotoEveryTagKeptAndPosesAgreeWithVisp) {
  const fs::path photo = kVispPhotoDir / "AprilTag.pgm";
  if (!fs::exists(photo))
    GTEST_SKIP() << photo << " missing: Debian's visp-images-data is not installed "
                 << "(tools/install_deps.sh installs it)";
  const cv::Mat gray = cv::imread(photo.string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(gray.empty());
  // The camera of ViSP's regression test of this photo (no distortion); tags of 53 mm.
  io::Calibration calib = nominal_calibration(gray.cols, gray.rows);
  calib.K = cv::Matx33d(615.1674805, 0, 312.1889954, 0, 615.1675415, 243.4373779, 0, 0, 1);
  constexpr double kTagSize = 0.053;
  const auto results = evaluate_photo(gray, calib, DetectorSettings{}, TrackingSettings{});
  const auto visp = read_visp_poses(kVispPhotoDir / "ground_truth_pose.txt");
  ASSERT_EQ(results.size(), 12u) << "libapriltag's own detections";
  int eligible = 0, compared = 0;
  double worst_dp = 0.0, worst_normal = 0.0;
  for (const PhotoTagResult& t : results) {
    const std::string what = "id " + std::to_string(t.ref.id);
    ASSERT_TRUE(t.eligible) << what << ": hamming " << t.ref.hamming << ", narrowest "
                            << t.ref.narrowest << " px";
    ++eligible;
    EXPECT_EQ(t.status, TargetStatus::detected) << what << ": " << t.reason;
    if (t.status != TargetStatus::detected) continue;
    EXPECT_LT(t.corner_difference, 1.0) << what << ": corners far from libapriltag's";
    const auto pose =
        pnp_pose(normalized_features(t.corners_px, calib), obs::FeatureModel::square(kTagSize));
    ASSERT_TRUE(pose) << what;
    const auto it = visp.find(t.ref.id);
    ASSERT_NE(it, visp.end()) << what;
    // The tag's centre in the camera, and its normal (the frames' axes may be named
    // differently: the normal is compared up to its sign).
    const obs::Vec3 dp = pose->g_io.translation() - it->second.first;
    const obs::Vec3 n_ours = pose->g_io.linear().col(2);
    const obs::Vec3 n_visp = obs::exp_so3(it->second.second).col(2);
    const double normal_deg = std::acos(std::min(1.0, std::abs(n_ours.dot(n_visp)))) * 180 / M_PI;
    std::printf(
        "%s: corners %.2f px from libapriltag's; position %.1f mm, normal %.2f deg from "
        "ViSP's estimate\n",
        what.c_str(), t.corner_difference, 1e3 * dp.norm(), normal_deg);
    EXPECT_LT(dp.norm(), 0.01) << what;
    EXPECT_LT(normal_deg, 3.0) << what;
    worst_dp = std::max(worst_dp, dp.norm());
    worst_normal = std::max(worst_normal, normal_deg);
    ++compared;
  }
  EXPECT_EQ(eligible, 12);
  EXPECT_EQ(compared, 12);
  std::printf("%d of 12 kept; largest difference to ViSP's poses %.1f mm, %.2f deg\n", compared,
              1e3 * worst_dp, worst_normal);
}

/// A CSV line's fields (no quoting; a trailing empty field kept).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> out(1);
  for (const char ch : line)
    if (ch == ',')
      out.emplace_back();
    else
      out.back() += ch;
  return out;
}

// netvmo detect --photos on a folder with the desk photo: its report and photos.csv, whose rows
// carry the corners evaluate_photo gives (libapriltag's; the front end's where it kept the tag)
// and corner_difference_px their largest distance; then a JPEG that cannot be decoded beside it:
// one line naming the file, exit 1, and the previous results untouched; with --keep-going a
// warning and the report.
TEST(RealPhotos, DetectPhotosReportAndBadJpeg) {
  const fs::path photo = kVispPhotoDir / "AprilTag.pgm";
  if (!fs::exists(photo)) GTEST_SKIP() << photo << " missing (visp-images-data)";
  const fs::path dir = test::scratch_dir("photos");
  fs::create_directories(dir / "photos");
  fs::copy_file(photo, dir / "photos" / "desk.pgm");
  const std::string out = (dir / "out").string();
  const auto ok =
      test::run_netvmo("detect --photos " + (dir / "photos").string() + " --out " + out, dir, 300);
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.out.find("all"), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("100.0%"), std::string::npos) << ok.out;
  const std::string csv = test::slurp(dir / "out" / "photos.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 13) << "a header and 12 tags";
  {
    const cv::Mat gray = cv::imread(photo.string(), cv::IMREAD_GRAYSCALE);
    const auto results = evaluate_photo(gray, nominal_calibration(gray.cols, gray.rows),
                                        DetectorSettings{}, TrackingSettings{});
    std::istringstream lines(csv);
    std::string line;
    std::getline(lines, line);
    const std::vector<std::string> header = csv_fields(line);
    const auto field = [&header](const std::vector<std::string>& row, const std::string& name) {
      const auto at = std::find(header.begin(), header.end(), name);
      EXPECT_NE(at, header.end()) << "no column " << name;
      return at == header.end() ? std::string() : row[static_cast<size_t>(at - header.begin())];
    };
    size_t n = 0;
    int kept = 0;
    while (std::getline(lines, line)) {
      const std::vector<std::string> row = csv_fields(line);
      ASSERT_EQ(row.size(), header.size()) << line;
      ASSERT_LT(n, results.size());
      const PhotoTagResult& t = results[n++];
      EXPECT_EQ(field(row, "id"), std::to_string(t.ref.id));
      const bool detected = t.status == TargetStatus::detected;
      kept += detected;
      double worst = 0.0;
      for (size_t k = 0; k < 4; ++k) {
        const std::string c = std::to_string(k);
        const cv::Point2d ref(std::stod(field(row, "apriltag_x" + c)),
                              std::stod(field(row, "apriltag_y" + c)));
        EXPECT_LT(cv::norm(ref - t.ref.corners[k]), 1e-3) << line;
        if (!detected) {
          EXPECT_EQ(field(row, "x" + c) + field(row, "y" + c), "") << line;
          continue;
        }
        const cv::Point2d ours(std::stod(field(row, "x" + c)), std::stod(field(row, "y" + c)));
        EXPECT_LT(cv::norm(ours - t.corners_px[k]), 1e-3) << line;
        worst = std::max(worst, cv::norm(ours - ref));
      }
      if (detected) {
        EXPECT_NEAR(std::stod(field(row, "corner_difference_px")), worst, 2e-3) << line;
      }
    }
    EXPECT_EQ(n, results.size());
    EXPECT_EQ(kept, 12);
  }
  test::write_text(dir / "photos" / "broken.jpg", "\xff\xd8 not a JPEG");
  const auto bad =
      test::run_netvmo("detect --photos " + (dir / "photos").string() + " --out " + out, dir, 300);
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("broken.jpg: JPEG cut short: the data ends at byte 13 before any scan"),
            std::string::npos)
      << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_EQ(test::slurp(dir / "out" / "photos.csv"), csv) << "results already written changed";
  const auto kept = test::run_netvmo(
      "detect --photos " + (dir / "photos").string() + " --out " + out + " --keep-going", dir, 300);
  EXPECT_EQ(kept.code, 0) << kept.err;
  EXPECT_NE(kept.err.find("warning"), std::string::npos) << kept.err;
  // A folder without tags: no recall to print (not 100 % of none).
  fs::create_directories(dir / "blank");
  cv::imwrite((dir / "blank" / "white.png").string(), cv::Mat(120, 160, CV_8UC1, cv::Scalar(255)));
  const auto blank = test::run_netvmo(
      "detect --photos " + (dir / "blank").string() + " --out " + (dir / "out_blank").string(), dir,
      300);
  EXPECT_EQ(blank.code, 0) << blank.err;
  EXPECT_EQ(blank.out.find('%'), std::string::npos) << blank.out;
  EXPECT_NE(
      blank.out.find(
          "all                                   1         0      0        0      0        -"),
      std::string::npos)
      << blank.out;
  fs::remove_all(dir);
}

fs::path corpus_dir() {
  if (const char* env = std::getenv("NETVMO_REAL_PHOTOS")) return env;
  return fs::path(NETVMO_SOURCE_DIR).parent_path() / "shared" / "real_photos";
}

/// Recall against libapriltag over every photo below `dir` (a folder's calib.yaml is its photos'
/// camera), every eligible loss printed with its reason; with `losses`, each as "<folder>/<file>
/// id <id>: <reason>". Every kept tag's corners must lie within 1.65 px of libapriltag's (the
/// front end reports the print's cell grid, libapriltag the inked outline), or, where the frame
/// check keeps libapriltag's own quad as a bent print (BorderCheck::bent), of libapriltag's
/// corners moved by the bow (take_off_bow()): straight sides miss a bent print's corners by the
/// bow. Those tags are listed in `bent`.
PhotoRecall recall_over(const fs::path& dir, std::vector<std::string>* losses = nullptr,
                        std::vector<std::string>* bent = nullptr,
                        std::ostringstream* csv_rows = nullptr) {
  // The loop of netvmo detect --photos, with its one libapriltag decoding table for every photo.
  std::ostringstream own_rows;
  std::ostringstream& rows = csv_rows ? *csv_rows : own_rows;
  const auto found = run::detect_photos(
      dir, io::list_images(dir), run::DetectSettings{}, {}, rows,
      [](const std::string& line) { ADD_FAILURE() << line; },
      [&](const fs::path& photo, const std::vector<PhotoTagResult>& results) {
        for (const auto& t : results) {
          const std::string name = photo.parent_path().filename().string() + "/" +
                                   photo.filename().string() + " id " + std::to_string(t.ref.id);
          if (t.eligible && t.status != TargetStatus::detected) {
            std::printf("lost: %s (%.0f px): %s\n", name.c_str(), t.ref.narrowest,
                        t.reason.c_str());
            if (losses) losses->push_back(name + ": " + t.reason);
          }
          if (t.status != TargetStatus::detected) continue;
          if (!t.check.bent) {
            EXPECT_LT(t.corner_difference, 1.65) << name;
            continue;
          }
          const auto moved = take_off_bow(t.ref.corners, t.check.bow);
          double d = 0.0;
          for (size_t c = 0; c < 4; ++c) d = std::max(d, cv::norm(t.corners_px[c] - moved[c]));
          std::printf(
              "kept as a bent print: %s, corners %.2f px from libapriltag's, %.2f px "
              "from libapriltag's moved by the bow\n",
              name.c_str(), t.corner_difference, d);
          EXPECT_LT(d, 1.65) << name;
          if (bent) bent->push_back(name);
        }
      });
  for (const auto& line : found.unreadable) ADD_FAILURE() << line;
  const PhotoRecall& total = found.total;
  std::printf("%d photos, %d eligible tags, %d kept (%.1f %%)\n", total.photos, total.eligible,
              total.kept, 100.0 * total.recall());
  return total;
}

// Recall against libapriltag on every eligible tag of the corpus, with every loss listed.
// The figure the front end reaches (docs/frontend.md) is asserted not to fall: 98.5 % of the
// 395 eligible tags (389) measured when a bent print was first checked along its bowed sides
// (98.2 % before, 97.0 % before a side off its inner edge alone was kept halfway, 92.4 % before
// the shared border deviation and the significance test; the goal, 99 %, is not reached: the
// losses are listed); every kept tag's corners within 1.65 px of libapriltag's (recall_over()).
TEST(RealPhotos, Corpus) {
  const fs::path dir = corpus_dir();
  if (!fs::is_directory(dir))
    GTEST_SKIP() << dir << " missing: assemble the corpus with tools/real_photos.sh "
                 << "(datasets/real_photos/MANIFEST.md) and point NETVMO_REAL_PHOTOS at it";
  const PhotoRecall total = recall_over(dir);
  ASSERT_GT(total.eligible, 0);
  EXPECT_GE(total.kept, 389);
}

// The part of the corpus this repository holds (datasets/real_photos/photos: 29 photos of 8 sets
// from 5 repositories, chosen by set and file name, not by result; MANIFEST.md, "In this
// repository"), so every CI run judges the front end on real photos. libapriltag finds 206
// eligible tags there; the front end keeps 204 (99.0 %; 203 before a bent print was checked along
// its bowed sides, 201 before a side off its inner edge alone was kept halfway, 192 before the
// shared border deviation and the significance test) and may not keep fewer (every loss is
// printed with its reason). One tag is kept as a bent print, and only that one: id 3 of
// swatbotics_hallway/IMG_0613.jpg, a curled sheet whose bowed sides put a corner 2.3 px from
// where its straight sides meet (rejected as bowed before): no flat tag there takes that path.
TEST(RealPhotos, PhotosInTheRepository) {
  const fs::path dir = fs::path(NETVMO_SOURCE_DIR) / "datasets" / "real_photos" / "photos";
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  std::vector<std::string> losses, bent;
  std::ostringstream rows;
  const PhotoRecall total = recall_over(dir, &losses, &bent, &rows);
  EXPECT_EQ(total.photos, 29);
  EXPECT_EQ(total.eligible, 206) << "libapriltag's own eligible tags";
  EXPECT_GE(total.kept, 204);
  EXPECT_EQ(losses.size(), static_cast<size_t>(total.eligible - total.kept));
  ASSERT_EQ(bent.size(), 1u);
  EXPECT_EQ(bent[0], "swatbotics_hallway/IMG_0613.jpg id 3");
  // photos.csv says so: `bent` 1 on that tag's row alone, its inner edge's bow beside it.
  const std::vector<std::string> header = csv_fields(kPhotosHeader);
  const auto column = [&](const std::string& name) {
    return static_cast<size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const size_t bent_col = column("bent"), inner_col = column("inner_bow");
  ASSERT_LT(inner_col, header.size());
  std::istringstream in(rows.str());
  int bent_rows = 0;
  for (std::string line; std::getline(in, line);) {
    const std::vector<std::string> f = csv_fields(line);
    ASSERT_GT(f.size(), inner_col) << line;
    if (f[bent_col] != "1") continue;
    ++bent_rows;
    EXPECT_EQ(f[0] + " id " + f[1], "swatbotics_hallway/IMG_0613.jpg id 3") << line;
    EXPECT_GT(std::stod(f[inner_col]), 0.5) << line;
  }
  EXPECT_EQ(bent_rows, 1);
}

}  // namespace
}  // namespace netvmo
