#include "netvmo/pipeline/sources/render_source.hpp"

#include "netvmo/render/renderer.hpp"

namespace netvmo::sources {

namespace {

class RenderProvider final : public NetworkSource {
 public:
  RenderProvider(render::SceneDescription scene, int frames)
      : renderer_(std::move(scene)),
        frames_(frames > 0 ? frames : renderer_.frame_count()) {
    const auto& s = renderer_.scene();
    net_.fps = s.fps;
    net_.frames = frames_;
    net_.target.family = s.target.tag.family;
    net_.target.id = s.target.tag.id;
    net_.target.size = s.target.tag.size;
    net_.edges = s.edges;
    net_.source = "live rendering";
    for (const auto& c : s.cameras) {
      net_.cameras.push_back({c.id, c.g_wi_believed});
      io::Calibration k;
      k.width = c.intrinsics.width;
      k.height = c.intrinsics.height;
      k.K = cv::Matx33d(c.intrinsics.fx, 0, c.intrinsics.cx, 0, c.intrinsics.fy, c.intrinsics.cy, 0, 0, 1);
      for (int j = 0; j < 5; ++j) k.dist[j] = c.intrinsics.dist[static_cast<size_t>(j)];
      k.source = "camera " + std::to_string(c.id) + " of the scene";
      calib_.push_back(k);
    }
  }
  const io::NetworkConfig& network() const override { return net_; }
  const io::Calibration& calibration(size_t i) const override { return calib_.at(i); }
  int frame_count() const override { return frames_; }
  cv::Mat read(size_t i, int frame) override { return renderer_.render(static_cast<int>(i), frame); }
  std::optional<obs::SE3> target_truth(int frame) const override {
    return renderer_.target_pose(frame);
  }
  std::optional<obs::SE3> camera_truth(size_t i) const override {
    return renderer_.scene().cameras.at(i).g_wi_true;
  }
  std::string name() const override { return "live rendering"; }

 private:
  render::Renderer renderer_;
  int frames_;
  io::NetworkConfig net_;
  std::vector<io::Calibration> calib_;
};

}  // namespace

std::unique_ptr<NetworkSource> make_render_source(render::SceneDescription scene, int frames) {
  return std::make_unique<RenderProvider>(std::move(scene), frames);
}

}  // namespace netvmo::sources
