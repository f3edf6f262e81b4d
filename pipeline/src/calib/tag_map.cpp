// MAP.yaml: the static tags of a calibration (calibrate.hpp).
#include <cmath>
#include <set>

#include "netvmo/pipeline/calib/calibrate.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"

namespace netvmo::calib {

TagMap load_tag_map(const std::filesystem::path& file) {
  auto root = io::MapReader::from_file(file);
  TagMap map;
  map.source = file.string();
  const auto list = root.get("tags");
  std::set<int> ids;
  for (const auto& tv : list.sequence()) {
    auto t = tv.map();
    MapTag tag;
    const auto fam = t.get("family");
    tag.family = io::read_tag_family(fam);
    if (!map.tags.empty() && tag.family != map.tags[0].family)
      fam.fail("family " + tag.family + ": every map tag must use the first tag's family (" +
               map.tags[0].family + ")");
    const auto id = t.get("id");
    tag.id = io::read_tag_id(id);
    if (!ids.insert(tag.id).second)
      id.fail("duplicate tag id " + std::to_string(tag.id) + " (each map tag once)");
    const auto size = t.get("size");
    tag.size = size.number();
    if (!(tag.size > 0) || !std::isfinite(tag.size)) size.fail("must be positive (metres)");
    const obs::Vec3 p = t.get("p").vec<3>();
    if (!p.allFinite()) t.get("p").fail("must be finite");
    obs::Mat3 R;
    if (t.has("R")) {
      if (t.has("r")) t.get("r").fail("give either r (rotation vector) or R (matrix), not both");
      const auto Rv = t.get("R");
      const auto rows = Rv.sequence();
      if (rows.size() != 3) Rv.fail("expected 3 rows of 3 numbers");
      for (int i = 0; i < 3; ++i) R.row(i) = rows[static_cast<size_t>(i)].vec<3>().transpose();
      const double orth = (R.transpose() * R - obs::Mat3::Identity()).norm();
      if (!R.allFinite() || !(orth < 1e-6) || !(R.determinant() > 0))
        Rv.fail("not a rotation: |R^T R - I| = " + io::format_number(orth) +
                ", det = " + io::format_number(R.determinant()) +
                " (need an orthonormal matrix with det +1, within 1e-6)");
    } else {
      const auto rv = t.get("r");
      const obs::Vec3 r = rv.vec<3>();
      if (!r.allFinite()) rv.fail("must be finite");
      R = obs::exp_so3(r);
    }
    t.finish();
    tag.g_wt.linear() = R;
    tag.g_wt.translation() = p;
    map.tags.push_back(tag);
  }
  if (map.tags.empty()) list.fail("at least one tag is required");
  root.finish();
  return map;
}

}  // namespace netvmo::calib
