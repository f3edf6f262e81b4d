#include "netvmo/pipeline/sources/network_source.hpp"

#include <map>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace netvmo::sources {
namespace fs = std::filesystem;

namespace {

class DatasetProvider final : public NetworkSource {
 public:
  DatasetProvider(const fs::path& dir, std::optional<int> only_camera, bool keep_going)
      : ds_(open_dataset(dir, only_camera, keep_going)) {
    const fs::path target = dir / "target.csv", cams = dir / "truth_cameras.csv";
    if (fs::exists(target) && fs::exists(cams)) {
      for (const auto& r : io::read_target_csv(target)) target_[r.frame] = r.g_wo;
      std::map<int, obs::SE3> by_id;
      for (const auto& r : io::read_truth_cameras_csv(cams)) by_id[r.camera] = r.g_wi;
      for (const auto& c : ds_.network.cameras) {
        const auto it = by_id.find(c.id);
        if (it == by_id.end())
          throw InputError(cams.string() + ": no row for camera " + std::to_string(c.id) +
                           " of network.yaml");
        camera_truth_.push_back(it->second);
      }
    }
  }
  const io::NetworkConfig& network() const override { return ds_.network; }
  const io::Calibration& calibration(size_t i) const override { return ds_.cameras.at(i).calib; }
  int frame_count() const override { return ds_.frame_count; }
  cv::Mat read(size_t i, int frame) override { return ds_.read(i, frame); }
  std::optional<obs::SE3> target_truth(int frame) const override {
    const auto it = target_.find(frame);
    if (it == target_.end()) return std::nullopt;
    return it->second;
  }
  std::optional<obs::SE3> camera_truth(size_t i) const override {
    if (i >= camera_truth_.size()) return std::nullopt;
    return camera_truth_[i];
  }
  std::vector<std::string> warnings() const override { return ds_.warnings; }
  std::string name() const override { return ds_.dir.string(); }

 private:
  Dataset ds_;
  std::map<int, obs::SE3> target_;
  std::vector<obs::SE3> camera_truth_;
};

}  // namespace

std::unique_ptr<NetworkSource> open_dataset_source(const fs::path& dir,
                                                   std::optional<int> only_camera,
                                                   bool keep_going) {
  return std::make_unique<DatasetProvider>(dir, only_camera, keep_going);
}

}  // namespace netvmo::sources
