// `netvmo detect` end to end on synthesized dataset folders (binary run via std::system).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "netvmo/pipeline/frontend/resampling.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"
#include "synth.hpp"
#include "test_util.hpp"

namespace netvmo {
namespace {
using namespace io;
using frontend::kAllTargetStatuses;
using frontend::TargetStatus;
namespace fs = std::filesystem;

using test::slurp;

test::CliResult run_detect(const fs::path& dataset, const fs::path& out,
                           const std::string& extra = "") {
  return test::run_netvmo(
      "detect " + dataset.string() + " --out " + out.string() + " --quiet " + extra,
      out.parent_path());
}

int count_lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

TEST(Cli, DetectWritesCsvAndSummary) {
  const auto dir = testing::fresh_dir("cli_ok");
  const auto truth = testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 3));
  const auto r = run_detect(dir / "ds", dir / "out");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("camera"), std::string::npos);
  EXPECT_NE(r.out.find("mean_margin"), std::string::npos);
  const auto rows = read_detections_csv(dir / "out" / "detections.csv");
  ASSERT_EQ(rows.size(), 6u);  // frames x cameras
  for (const auto& row : rows) {
    ASSERT_TRUE(row.detected);
    EXPECT_EQ(row.tag_id, 0);
    EXPECT_GT(row.margin, 20.0);
    const size_t ci = static_cast<size_t>(row.camera - 1), f = static_cast<size_t>(row.frame);
    EXPECT_LT(testing::corner_rms(*row.corners, truth[ci][f]), 0.1);
  }
  const std::string header =
      "frame,camera,tag_id,detected,status,margin,u0,v0,u1,v1,u2,v2,u3,v3,reason\n";
  EXPECT_EQ(slurp(dir / "out" / "detections.csv").substr(0, header.size()), header);
  // the summary has a column per reason for not using the target
  for (TargetStatus st : kAllTargetStatuses)
    EXPECT_NE(r.out.find(to_string(st)), std::string::npos) << to_string(st);
}

// Both cameras' frames blurred as by a lens (sigma 1 px, so that their edges have the ramps the
// measurement counts: camera 1 is then not flagged by the fraction of repeated pairs, not for
// want of pairs); camera 2's frames then enlarged by copying pixels (each halved, then doubled
// by nearest neighbour: the size of its calibration). Camera 2 is named in one warning by
// `netvmo detect` (stderr) and `netvmo run` (stderr and summary.json's warnings); camera 1 is
// not.
TEST(Cli, ACameraOfResampledFramesIsWarnedAboutOnce) {
  const auto dir = testing::fresh_dir("cli_resampled");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 3));
  int resampled = 0;
  for (const int camera : {1, 2})
    for (const auto& e : fs::directory_iterator(dir / "ds" / ("cam_" + std::to_string(camera)))) {
      cv::Mat img = cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(img.empty()) << e.path();
      cv::GaussianBlur(img, img, cv::Size(0, 0), 1.0);
      if (camera == 1) {
        const auto r = frontend::measure_resampling(img);
        EXPECT_GE(r.pairs, frontend::ResamplingSettings().min_pairs) << e.path();
        EXPECT_FALSE(r.nearest_neighbour) << e.path() << ": " << r.repeated;
      } else {
        cv::Mat half;
        cv::resize(img, half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
        cv::resize(half, img, img.size(), 0.0, 0.0, cv::INTER_NEAREST);
        ++resampled;
      }
      ASSERT_TRUE(cv::imwrite(e.path().string(), img));
    }
  ASSERT_EQ(resampled, 3);
  const std::string warning = "its images look resampled by nearest neighbour";
  const auto count = [&](const std::string& s) {
    int n = 0;
    for (size_t at = s.find(warning); at != std::string::npos; at = s.find(warning, at + 1)) ++n;
    return n;
  };
  const auto d = run_detect(dir / "ds", dir / "detect");
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_EQ(count(d.err), 1) << d.err;
  EXPECT_NE(d.err.find("camera 2: " + warning), std::string::npos) << d.err;
  const auto r = test::run_netvmo("run " + (dir / "ds").string() + " --out " +
                                      (dir / "run").string() + " --no-overlays --no-plots",
                                  dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(count(r.err), 1) << r.err;
  const std::string summary = slurp(dir / "run" / "summary.json");
  EXPECT_EQ(count(summary), 1) << summary;
  // One clock: the files' t is frame / fps (docs/images.md, summary.json's time_origin_s).
  EXPECT_NE(summary.find("\"time_origin_s\": null"), std::string::npos) << summary;
  EXPECT_NE(summary.find("camera 2: " + warning), std::string::npos);
  EXPECT_EQ(summary.find("camera 1: " + warning), std::string::npos);
}

// `netvmo detect --photos` on two folders of the same three frames, blurred as by a lens (sigma 1
// px): `raw` as they are, `nn` halved and doubled by nearest neighbour. photos.csv gives each
// photo's pairs on steep edges and the fraction repeated (those of measure_resampling), the
// report a count of resampled photos per folder, and stderr one warning naming `nn` alone.
TEST(Cli, DetectPhotosCountsThePhotosResampledByNearestNeighbour) {
  const auto dir = testing::fresh_dir("cli_photos_resampled");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(1, 3));
  std::map<std::string, frontend::Resampling> expected;  // by file, relative to photos/
  for (const std::string folder : {"raw", "nn"}) {
    fs::create_directories(dir / "photos" / folder);
    for (const auto& e : fs::directory_iterator(dir / "ds" / "cam_1")) {
      cv::Mat img = cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(img.empty()) << e.path();
      cv::GaussianBlur(img, img, cv::Size(0, 0), 1.0);
      if (folder == "nn") {
        cv::Mat half;
        cv::resize(img, half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
        cv::resize(half, img, img.size(), 0.0, 0.0, cv::INTER_NEAREST);
      }
      const std::string name = folder + "/" + e.path().filename().string();
      ASSERT_TRUE(cv::imwrite((dir / "photos" / name).string(), img));
      expected[name] = frontend::measure_resampling(img);
      EXPECT_GE(expected[name].pairs, frontend::ResamplingSettings().min_pairs) << name;
      EXPECT_EQ(expected[name].nearest_neighbour, folder == "nn") << name;
    }
  }
  ASSERT_EQ(expected.size(), 6u);
  const auto r = test::run_netvmo(
      "detect --photos " + (dir / "photos").string() + " --out " + (dir / "out").string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  // One warning: 3 of 6 photos, the folder nn alone.
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("warning: 3 of 6 photos look resampled by nearest neighbour (nn 3 of 3;"),
            std::string::npos)
      << r.err;
  // The report: photos, then resampled photos, per folder and in all.
  for (const auto& [folder, n] : {std::pair<std::string, int>{"nn", 3}, {"raw", 0}, {"all", 0}}) {
    std::istringstream lines(r.out);
    std::string line;
    bool found = false;
    while (std::getline(lines, line)) {
      std::istringstream row(line);
      std::string name;
      int photos = 0, resampled = -1;
      if (!(row >> name >> photos >> resampled) || name != folder) continue;
      found = true;
      EXPECT_EQ(photos, folder == "all" ? 6 : 3) << line;
      EXPECT_EQ(resampled, folder == "all" ? 3 : n) << line;
    }
    EXPECT_TRUE(found) << folder << " not in\n" << r.out;
  }
  // photos.csv: every row's photo with its pairs and fraction.
  std::istringstream csv(slurp(dir / "out" / "photos.csv"));
  std::string line;
  std::getline(csv, line);
  ASSERT_EQ(line.substr(line.size() - 26), ",edge_pairs,repeated_pairs") << line;
  std::set<std::string> seen;
  while (std::getline(csv, line)) {
    const std::string file = line.substr(0, line.find(','));
    ASSERT_TRUE(expected.count(file)) << line;
    seen.insert(file);
    const size_t last = line.rfind(','), before = line.rfind(',', last - 1);
    EXPECT_EQ(std::stol(line.substr(before + 1, last - before - 1)), expected[file].pairs) << line;
    EXPECT_NEAR(std::stod(line.substr(last + 1)), expected[file].repeated, 5e-5) << line;
  }
  EXPECT_EQ(seen.size(), 6u) << "a row for each photo's tag";
}

// A frame whose target quad fails the border check (frame 1: the tag's side on the image
// border, test BorderCheck.QuadOnTheImageBorderRejected) is a `border_mismatch` row, counted in
// the summary's border_mismatch column; --no-border-check accepts it.
TEST(Cli, DetectReportsBorderMismatch) {
  const auto dir = testing::fresh_dir("cli_border");
  auto spec = testing::simple_dataset_spec(1, 2);
  spec.g_wo = {testing::facing_pose(1.2, 0.0, 0.0, {0.0, 0.0, 0.05}),
               testing::facing_pose(1.2, 0.5175, 0.0, {0.0, 0.0, 0.05})};
  spec.options.noise_sigma = 2.0;
  testing::write_synth_dataset(dir / "ds", spec);
  const auto r = run_detect(dir / "ds", dir / "out");
  ASSERT_EQ(r.code, 0) << r.err;
  auto rows = read_detections_csv(dir / "out" / "detections.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].status, TargetStatus::detected);
  EXPECT_EQ(rows[1].status, TargetStatus::border_mismatch);
  EXPECT_FALSE(rows[1].detected);
  // summary: the header has the reasons in enum order, the camera's row a 1 under border_mismatch
  std::istringstream out(r.out);
  std::string line, header, row;
  while (std::getline(out, line)) {
    if (line.rfind("camera", 0) == 0) header = line;
    if (line.rfind("1 ", 0) == 0) row = line;
  }
  std::istringstream hs(header), rs(row);
  std::vector<std::string> names, values;
  for (std::string w; hs >> w;) names.push_back(w);
  for (std::string w; rs >> w;) values.push_back(w);
  ASSERT_EQ(names.size(), values.size()) << header << "\n" << row;
  std::map<std::string, std::string> column;
  for (size_t i = 0; i < names.size(); ++i) column[names[i]] = values[i];
  EXPECT_EQ(column["detected"], "1");
  EXPECT_EQ(column["border_mismatch"], "1");
  EXPECT_EQ(column["not_found"], "0");
  const auto r2 = run_detect(dir / "ds", dir / "out2", "--no-border-check");
  ASSERT_EQ(r2.code, 0) << r2.err;
  rows = read_detections_csv(dir / "out2" / "detections.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].status, TargetStatus::detected);
}

TEST(Cli, CorruptImageOneErrorLineOtherCamerasKept) {
  const auto dir = testing::fresh_dir("cli_corrupt");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 2));
  const fs::path bad = dir / "ds" / "cam_2" / "000001.png";
  { std::ofstream(bad, std::ios::binary) << "garbage, not a png"; }
  const auto r = run_detect(dir / "ds", dir / "out");
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
  const auto rows = read_detections_csv(dir / "out" / "detections.csv");
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& row : rows)
    EXPECT_EQ(row.detected, !(row.camera == 2 && row.frame == 1)) << row.camera << " " << row.frame;
  // --keep-going: same rows, a warning, exit 0
  const auto k = run_detect(dir / "ds", dir / "out2", "--keep-going");
  EXPECT_EQ(k.code, 0) << k.err;
  EXPECT_NE(k.err.find("warning"), std::string::npos);
  EXPECT_EQ(slurp(dir / "out" / "detections.csv"), slurp(dir / "out2" / "detections.csv"));
}

// A JPEG or PNG frame cut short (a recording or copy interrupted): libjpeg alone would decode it
// with the rest gray and print a warning without the file's name; libpng would fail with a line
// of its own. Here it is the frame's one error line, as a corrupt image is, and the only line
// (neither library says anything: the frame is not decoded).
TEST(Cli, CutShortImageOneErrorLineOtherCamerasKept) {
  for (const std::string ext : {".jpg", ".png"}) {
    const auto dir = testing::fresh_dir("cli_cut_" + ext.substr(1));
    testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 2));
    const fs::path png = dir / "ds" / "cam_2" / "000001.png";
    const fs::path cut = dir / "ds" / "cam_2" / ("000001" + ext);
    std::vector<uchar> bytes;
    ASSERT_TRUE(cv::imencode(ext, cv::imread(png.string()), bytes));
    fs::remove(png);
    std::ofstream(cut, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size() / 2));
    const auto r = run_detect(dir / "ds", dir / "out");
    EXPECT_NE(r.code, 0) << ext;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    const std::string format = ext == ".jpg" ? "JPEG" : "PNG";
    EXPECT_NE(r.err.find(cut.string() + ": " + format + " cut short"), std::string::npos) << r.err;
    const auto rows = read_detections_csv(dir / "out" / "detections.csv");
    ASSERT_EQ(rows.size(), 4u);
    for (const auto& row : rows)
      EXPECT_EQ(row.detected, !(row.camera == 2 && row.frame == 1))
          << ext << ": " << row.camera << " " << row.frame;
  }
}

TEST(Cli, DatasetErrorsOneLineNothingWritten) {
  const auto dir = testing::fresh_dir("cli_err");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 1));
  fs::remove(dir / "ds" / "calib" / "cam_2.yaml");
  auto r = run_detect(dir / "ds", dir / "out");
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("cam_2.yaml"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "detections.csv"));

  testing::write_synth_dataset(dir / "ds2", testing::simple_dataset_spec(2, 1));
  std::string net = slurp(dir / "ds2" / "network.yaml");
  net.replace(net.find("[[1, 2]]"), 8, "[[1, 5]]");
  std::ofstream(dir / "ds2" / "network.yaml") << net;
  r = run_detect(dir / "ds2", dir / "out2");
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("network.yaml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("unknown camera id 5"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out2" / "detections.csv"));
}

// timestamps.csv going backwards stops `netvmo run` with one line naming the file, line and
// field, --keep-going or not (it only blinds cameras whose image cannot be read), and writes
// nothing.
TEST(Cli, BackwardsTimestampsStopRunEvenWithKeepGoing) {
  const auto dir = testing::fresh_dir("cli_times");
  testing::write_synth_dataset(dir / "ds", testing::simple_dataset_spec(2, 3));
  std::ofstream(dir / "ds" / "timestamps.csv")
      << "camera,frame,t\n1,0,0\n1,1,0.1\n1,2,0.2\n2,0,0\n2,1,0.2\n2,2,0.1\n";
  const std::string file = (dir / "ds" / "timestamps.csv").string();
  for (const std::string extra : {"", " --keep-going"}) {
    const auto r =
        test::run_netvmo("run " + (dir / "ds").string() + " --out " + (dir / "out").string() +
                             " --no-overlays --no-plots" + extra,
                         dir);
    EXPECT_NE(r.code, 0) << extra;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(file + ":7: t: camera 2 frame 2 at t = 0.1 s is not after its frame 1"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "summary.json"));
  }
}

}  // namespace
}  // namespace netvmo
