// netvmo bag DATASET --out BAG [--encoding mono8|rgb8|png|jpeg] [--no-camera-info]
// Writes a dataset folder as a rosbag2 bag (sqlite3 storage), the form ROS 2 recordings take;
// every command that takes a dataset folder takes the bag too.
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "netvmo/pipeline/io/output_dir.hpp"
#include "netvmo/pipeline/sources/bag_export.hpp"

namespace netvmo::tools {

void add_bag(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, out;
    sources::BagExportSettings bag;
    bool no_camera_info = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = add_command(
      app, "bag", "Write a dataset folder as a rosbag2 bag (sqlite3 storage)",
      "Writes BAG/metadata.yaml and BAG/bag_0.db3 (rosbag2's sqlite3 storage, ROS 2 Humble's\n"
      "layout): every camera's images on /cam_<id>/image_raw (sensor_msgs/msg/Image) or\n"
      "/cam_<id>/image_raw/compressed (CompressedImage), its calibration on /cam_<id>/camera_info\n"
      "(CameraInfo), header.stamp = 1.7e9 s + the image's time; beside them network.yaml naming\n"
      "each camera's topics, and truth.csv, target.csv and cameras.csv when the dataset has them.\n"
      "BAG is itself a dataset for detect, run, sweep, node, launch and calibrate\n"
      "(docs/datasets.md, \"rosbag2 bags\"). Written in BAG.partial-<pid> and swapped into place.");
  cmd->add_option("DATASET", o->dataset, "dataset folder")->required();
  cmd->add_option("--out", o->out, "bag folder to write")->required();
  cmd->add_option("--encoding", o->bag.encoding,
                  "mono8 or rgb8 (sensor_msgs Image), png or jpeg (CompressedImage)")
      ->capture_default_str()
      ->check(CLI::IsMember({"mono8", "rgb8", "png", "jpeg"}));
  cmd->add_flag("--no-camera-info", o->no_camera_info,
                "copy calib/ instead of writing CameraInfo topics");
  cmd->callback([o, &exit_code]() {
    exit_code = guarded("bag", [&]() {
      sources::Dataset ds = sources::open_dataset(o->dataset);
      for (const auto& w : ds.warnings)
        std::fprintf(stderr, "netvmo bag: warning: %s\n", w.c_str());
      o->bag.camera_info = !o->no_camera_info;
      io::check_output_apart(o->out, o->dataset);
      io::OutputDir out(o->out, "bag");
      const int n = sources::write_bag(ds, out.path(), o->bag);
      out.commit();
      std::printf("wrote %s: %d images of %zu cameras (%s)\n", o->out.c_str(), n, ds.cameras.size(),
                  o->bag.encoding.c_str());
      return 0;
    });
  });
}

}  // namespace netvmo::tools
