#include "netvmo/pipeline/sources/render_source.hpp"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"

namespace netvmo::sources {

namespace {

class RenderSource final : public NetworkSource {
 public:
  RenderSource(render::SceneDescription scene, int frames)
      : renderer_(std::move(scene)), frames_(frames > 0 ? frames : renderer_.frame_count()) {
    net_ = io::scene_network_config(renderer_.scene(), frames_);
    net_.source = "live rendering";
    for (const auto& c : renderer_.scene().cameras) calib_.push_back(io::scene_calibration(c));
  }
  const io::NetworkConfig& network() const override { return net_; }
  const io::Calibration& calibration(size_t i) const override { return calib_.at(i); }
  int frame_count() const override { return frames_; }
  bool one_frame_at_a_time() const override { return true; }  // Renderer::set_frame
  cv::Mat read(size_t i, int frame) override {
    cv::Mat img = renderer_.render(static_cast<int>(i), frame);
    // sensor.jpeg_quality: the image a recorded dataset would hold (io::write_dataset's JPEG).
    const int quality = renderer_.scene().cameras.at(i).sensor.jpeg_quality;
    if (quality > 0) {
      std::vector<uchar> jpg;
      cv::imencode(".jpg", img, jpg, {cv::IMWRITE_JPEG_QUALITY, quality});
      img = cv::imdecode(jpg, cv::IMREAD_GRAYSCALE);
    }
    return img;
  }
  std::optional<obs::SE3> target_truth(int frame, size_t target) const override {
    return renderer_.target_pose(frame, target);
  }
  std::optional<obs::SE3> camera_truth(size_t i, int frame) const override {
    return renderer_.camera_pose(static_cast<int>(i), frame);
  }
  obs::SE3 camera_believed(size_t i, int frame) const override {
    return renderer_.believed_camera_pose(static_cast<int>(i), frame);
  }
  bool cameras_move() const override {
    const auto& cams = renderer_.scene().cameras;
    return std::any_of(cams.begin(), cams.end(), [](const auto& c) { return c.moving(); });
  }
  std::string name() const override { return "live rendering"; }
  std::optional<obs::SE3> target_truth_at(double t, size_t target) const override {
    return renderer_.scene().targets.at(target).motion.at(t);
  }
  std::optional<obs::SE3> camera_truth_at(size_t i, double t) const override {
    return renderer_.scene().cameras.at(i).true_pose(t);
  }
  obs::SE3 camera_believed_at(size_t i, double t) const override {
    return renderer_.scene().cameras.at(i).believed_pose(t);
  }

 private:
  render::Renderer renderer_;
  int frames_;
  io::NetworkConfig net_;
  std::vector<io::Calibration> calib_;
};

}  // namespace

std::unique_ptr<NetworkSource> make_render_source(render::SceneDescription scene, int frames) {
  for (const auto& c : scene.cameras)
    if ((c.fps && *c.fps != scene.fps) || c.start != 0.0)
      throw InputError("live rendering: camera " + std::to_string(c.id) +
                       " has its own fps or start, but live frames are on the scene's clock "
                       "(render a dataset with `netvmo render` and run that)");
  return std::make_unique<RenderSource>(std::move(scene), frames);
}

}  // namespace netvmo::sources
