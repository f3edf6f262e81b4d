#include "netvmo/render/geometry.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace netvmo::render {

Pose look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 z = target - eye;
  if (z.norm() < 1e-9) throw std::invalid_argument("look_at: eye and target coincide");
  const Vec3 zc = z.normalized();
  Vec3 x = (-up).cross(zc);  // x right = y (down) x z (forward)
  if (x.norm() < 1e-9) throw std::invalid_argument("look_at: viewing direction parallel to up");
  x.normalize();
  const Vec3 y = zc.cross(x);
  Pose g = Pose::Identity();
  g.linear().col(0) = x;
  g.linear().col(1) = y;
  g.linear().col(2) = zc;
  g.translation() = eye;
  return g;
}

Mesh make_box(const Vec3& s) {
  Mesh m;
  const float hx = float(s.x() / 2), hy = float(s.y() / 2), hz = float(s.z() / 2);
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1) ? hx : -hx, (i & 2) ? hy : -hy, (i & 4) ? hz : -hz);
  // Quads (outward, counter-clockwise seen from outside), split into two triangles each.
  const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                       {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({std::uint32_t(f[0]), std::uint32_t(f[1]), std::uint32_t(f[2])});
    m.triangles.push_back({std::uint32_t(f[0]), std::uint32_t(f[2]), std::uint32_t(f[3])});
  }
  return m;
}

Mesh make_plane(double sx, double sy) {
  Mesh m;
  const float hx = float(sx / 2), hy = float(sy / 2);
  m.vertices = {{-hx, -hy, 0}, {hx, -hy, 0}, {hx, hy, 0}, {-hx, hy, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

Mesh make_cylinder(double radius, double height, int segments) {
  if (segments < 3) segments = 3;
  Mesh m;
  const float h = float(height / 2);
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * M_PI * i / segments;
    const float x = float(radius * std::cos(a)), y = float(radius * std::sin(a));
    m.vertices.emplace_back(x, y, -h);
    m.vertices.emplace_back(x, y, h);
  }
  const auto bot = std::uint32_t(m.vertices.size());
  m.vertices.emplace_back(0, 0, -h);
  m.vertices.emplace_back(0, 0, h);
  const auto top = bot + 1;
  for (int i = 0; i < segments; ++i) {
    const auto a0 = std::uint32_t(2 * i), a1 = a0 + 1;
    const auto b0 = std::uint32_t(2 * ((i + 1) % segments)), b1 = b0 + 1;
    m.triangles.push_back({a0, b0, b1});
    m.triangles.push_back({a0, b1, a1});
    m.triangles.push_back({bot, b0, a0});
    m.triangles.push_back({top, a1, b1});
  }
  return m;
}

Mesh parse_obj(const std::string& text, const std::string& name) {
  Mesh m;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(name + ":" + std::to_string(lineno) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      double x, y, z;
      if (!(ls >> x >> y >> z)) fail("vertex needs 3 numbers");
      m.vertices.emplace_back(float(x), float(y), float(z));
    } else if (tag == "f") {
      std::vector<std::uint32_t> idx;
      std::string tok;
      while (ls >> tok) {
        long i = 0;
        try {
          i = std::stol(tok.substr(0, tok.find('/')));
        } catch (const std::exception&) {
          fail("bad face index '" + tok + "'");
        }
        const long n = static_cast<long>(m.vertices.size());
        if (i < 0) i = n + i + 1;
        if (i < 1 || i > n)
          fail("face index " + tok + " out of range (1.." + std::to_string(n) + ")");
        idx.push_back(std::uint32_t(i - 1));
      }
      if (idx.size() < 3) fail("face needs at least 3 vertices");
      for (size_t k = 1; k + 1 < idx.size(); ++k)
        m.triangles.push_back({idx[0], idx[k], idx[k + 1]});
    }
  }
  if (m.triangles.empty()) throw std::invalid_argument(name + ": no faces in OBJ file");
  return m;
}

Mesh transformed(const Mesh& mesh, const Pose& g) {
  Mesh out = mesh;
  const Eigen::Isometry3f gf = g.cast<float>();
  for (auto& v : out.vertices) v = gf * v;
  return out;
}

}  // namespace netvmo::render
