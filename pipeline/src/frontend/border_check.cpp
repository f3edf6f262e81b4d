#include "netvmo/pipeline/frontend/border_check.hpp"

#include <apriltag/apriltag.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/render/tag_family.hpp"
#include "sampling.hpp"
#include "tag_square.hpp"

namespace netvmo::frontend {

namespace {

// What a point-sampled (aliased) image adds to the thickness and bow limits [px]: its edges are
// quantised to the pixel grid.
constexpr double kAliasedAllowance = 0.5;

using detail::edge_offset;
using detail::edge_spread;
using detail::inside;
using detail::intersect_lines;
using detail::median;
using detail::sample_bilinear;
using detail::SquareToImage;

/// Where the inner edge is located along a white data cell next to the border [cells].
constexpr double kThicknessT[] = {0.2, 0.35, 0.5, 0.65, 0.8};

/// Pairs of adjacent runs needed on each axis to believe its measured edge bias.
constexpr int kMinEdgeBiasPairs = 4;

/// Offsets r_i of the inner border edge measured at positions t_i along a side (cells): the
/// line r(t) = a + b t fitted to them (least squares, then again without the points further
/// than max(0.3 px, 3 robust sigmas) from it), evaluated at the first and the last measured
/// position; returns the one of larger magnitude. A side that is shifted or tilted against the
/// true border edge makes r constant or growing towards the wrong corner. Not extrapolated to
/// the corners: with 2x2 supersampled or aliased images a short stretch of edge carries up to
/// ~0.25 px of quantisation error, which extrapolation would amplify. With the points spanning
/// less than 2 cells, their median. NaN for fewer than 4 points.
double end_offset(const std::vector<double>& t, const std::vector<double>& r,
                  double* standard_error = nullptr) {
  const size_t k = r.size();
  if (standard_error) *standard_error = std::numeric_limits<double>::quiet_NaN();
  if (k < 4) return std::numeric_limits<double>::quiet_NaN();
  const auto [tmin, tmax] = std::minmax_element(t.begin(), t.end());
  // The points of one data cell share that cell's print: one independent measurement a cell.
  const double per_cell = static_cast<double>(std::size(kThicknessT));
  if (*tmax - *tmin < 2.0) {
    const double m = median(r);
    if (standard_error) {
      double ss = 0.0;
      for (double x : r) ss += (x - m) * (x - m);
      // The median's standard error: sqrt(pi / 2) = 1.2533 times the mean's.
      *standard_error = std::sqrt(ss / static_cast<double>(k - 1)) *
                        std::sqrt(per_cell / static_cast<double>(k)) * 1.2533;
    }
    return m;
  }
  std::vector<char> use(k, 1);
  double a = 0.0, b = 0.0, se = std::numeric_limits<double>::quiet_NaN();
  for (int pass = 0; pass < 2; ++pass) {
    double s0 = 0, st = 0, stt = 0, sr = 0, str = 0;
    for (size_t i = 0; i < k; ++i)
      if (use[i]) {
        s0 += 1, st += t[i], stt += t[i] * t[i], sr += r[i], str += t[i] * r[i];
      }
    const double det = s0 * stt - st * st;
    if (s0 < 3 || !(det > 1e-9)) break;
    b = (s0 * str - st * sr) / det;
    a = (sr - b * st) / s0;
    std::vector<double> res(k);
    double ss = 0.0;
    for (size_t i = 0; i < k; ++i) {
      res[i] = std::abs(r[i] - a - b * t[i]);
      if (use[i]) ss += res[i] * res[i];
    }
    {  // The line's standard error at the end further from the points' centre, the larger of
       // the two ends'.
      const double sigma = std::sqrt(ss / std::max(1.0, s0 - 2.0));
      const double tbar = st / s0, sxx = stt - s0 * tbar * tbar;
      const double tend = std::abs(*tmin - tbar) > std::abs(*tmax - tbar) ? *tmin : *tmax;
      se = sigma * std::sqrt(per_cell) * std::sqrt(1.0 / s0 + (tend - tbar) * (tend - tbar) / sxx);
    }
    const double cut = std::max(0.3, 3.0 * 1.4826 * median(res));
    for (size_t i = 0; i < k; ++i) use[i] = res[i] <= cut;
  }
  if (standard_error) *standard_error = se;
  const double r0 = a + b * *tmin, r1 = a + b * *tmax;
  return std::abs(r0) >= std::abs(r1) ? r0 : r1;
}

/// The pair estimates of the print's edge bias, per axis, and its local value.
struct EdgeBias {
  struct Estimate {
    cv::Point2d at;  // object cell coordinates of the transition the two runs share
    double b;        // [px]
    // b is linear in the offsets of the three transitions it is made of: db / d(offset).
    std::array<int, 3> edge{};
    std::array<double, 3> coef{};
  };
  std::array<std::vector<Estimate>, 2> estimates;
  /// The bias across `axis` at object point p: the mean of the axis's estimates weighted by a
  /// Gaussian of 1.5 cells in their distance to p (perspective grows the cells, and an ink
  /// spread in pixels with them, toward the near side of an oblique tag), or `fallback` where
  /// their weights add up to less than one estimate's at 2 cells.
  double at(size_t axis, cv::Point2d p, double fallback) const {
    double sw = 0.0, swb = 0.0;
    for (const auto& e : estimates[axis]) {
      const cv::Point2d d = e.at - p;
      const double w = std::exp(-d.dot(d) / (2.0 * 1.5 * 1.5));
      sw += w;
      swb += w * e.b;
    }
    return sw >= std::exp(-4.0 / (2.0 * 1.5 * 1.5)) ? swb / sw : fallback;
  }
  /// The derivative of at(axis, p) with respect to the transitions' offsets, as (transition,
  /// coefficient) pairs (a transition in several estimates appears once per estimate).
  std::vector<std::pair<int, double>> sensitivity(size_t axis, cv::Point2d p) const {
    const std::vector<double> w = weights(axis, p);
    std::vector<std::pair<int, double>> out;
    for (size_t i = 0; i < w.size(); ++i)
      for (size_t t = 0; t < 3; ++t)
        out.emplace_back(estimates[axis][i].edge[t], w[i] * estimates[axis][i].coef[t]);
    return out;
  }
  /// The weights of the axis's estimates in at(axis, p) (summing to 1), uniform where at() falls
  /// back (the median, taken as the mean: its standard error is 1.25x smaller than the median's).
  std::vector<double> weights(size_t axis, cv::Point2d p) const {
    std::vector<double> w;
    double sw = 0.0;
    for (const auto& e : estimates[axis]) {
      const cv::Point2d d = e.at - p;
      w.push_back(std::exp(-d.dot(d) / (2.0 * 1.5 * 1.5)));
      sw += w.back();
    }
    if (!(sw >= std::exp(-4.0 / (2.0 * 1.5 * 1.5)))) {
      w.assign(w.size(), 1.0);
      sw = static_cast<double>(w.size());
    }
    for (auto& x : w) x /= sw;
    return w;
  }
};

/// The print's edge bias along each tag axis (X, then Y), measured on the tag's own cells: see
/// BorderCheck::edge_bias. `white(X, Y)` is the bitmap's colour at object cell coordinates.
/// Axis a's lines are the data rows (a = 0: runs along X) or columns (a = 1: along Y).
template <typename White>
void measure_edge_bias(const cv::Mat& gray, int n, White white, const SquareToImage& map,
                       int min_pairs, EdgeBias& bias, BorderCheck& out) {
  // Object point of axis coordinate u on line j (the line's cell centre across it).
  const auto object = [](int axis, double u, int j) {
    return axis == 0 ? cv::Point2d(u, j + 0.5) : cv::Point2d(j + 0.5, u);
  };
  const auto colour = [&](int axis, int i, int j) {
    return axis == 0 ? white(i + 0.5, j + 0.5) : white(j + 0.5, i + 0.5);
  };
  // The interior transitions of every data line (u = i between cell i - 1 and cell i), each
  // with its point and the points half a cell either side, mapped in one batch.
  struct Edge {
    int axis, j, u;
    double off = 0.0;  // measured position minus mapped position, along +u [px]
    bool ok = false;
  };
  std::vector<Edge> edges;
  std::vector<cv::Point2d> obj;
  for (int axis = 0; axis < 2; ++axis) {
    if (axis == 1) out.first_y_transition = static_cast<int>(edges.size());
    for (int j = 1; j < n - 1; ++j)  // lines 0 and n - 1 are all border
      for (int i = 1; i < n; ++i) {
        if (colour(axis, i - 1, j) == colour(axis, i, j)) continue;
        edges.push_back({axis, j, i});
        obj.push_back(object(axis, i, j));
        obj.push_back(object(axis, i - 0.5, j));
        obj.push_back(object(axis, i + 0.5, j));
      }
  }
  const std::vector<cv::Point2d> img = map.map(obj);
  for (size_t q = 0; q < edges.size(); ++q) {
    Edge& edge = edges[q];
    const cv::Point2d e = img[3 * q], a = img[3 * q + 1], b = img[3 * q + 2];
    const double cell = cv::norm(b - a);
    if (!(cell > 0.0) || !inside(gray, a) || !inside(gray, b)) continue;
    const cv::Point2d u = (b - a) / cell;
    const bool rising = colour(edge.axis, edge.u, edge.j);  // dark to bright along +u
    const double w = std::clamp(std::min(0.45 * cell, cell - 1.2), 1.0, 4.0);
    double sv = 0.0;
    if (!edge_offset(gray, e, rising ? u : -u, w, sv) || !(std::abs(sv) < 0.5 * cell)) continue;
    edge.off = rising ? sv : -sv;
    edge.ok = true;
  }
  // Runs between consecutive transitions of a line, and each pair of adjacent runs (one white,
  // one black): d = off_end - off_start = 2 b p + k eps (p = +1 black, -1 white; k cells long;
  // eps a local scale error per cell, from the homography), so d1/k1 - d2/k2 = 2 b p1 (1/k1 +
  // 1/k2): b without eps, which a side moved off the border makes large.
  for (size_t q = 0; q + 2 < edges.size(); ++q) {
    const Edge &e0 = edges[q], &e1 = edges[q + 1], &e2 = edges[q + 2];
    if (e0.axis != e2.axis || e0.j != e2.j || !e0.ok || !e1.ok || !e2.ok) continue;
    const double k1 = e1.u - e0.u, k2 = e2.u - e1.u;
    const double d1 = e1.off - e0.off, d2 = e2.off - e1.off;
    const double p1 = colour(e0.axis, e0.u, e0.j) ? -1.0 : 1.0;  // the first run's colour
    const double D = 2.0 * p1 * (1.0 / k1 + 1.0 / k2);
    const int i0 = static_cast<int>(q);
    bias.estimates[static_cast<size_t>(e0.axis)].push_back(
        {object(e0.axis, e1.u, e1.j),
         (d1 / k1 - d2 / k2) / D,
         {i0, i0 + 1, i0 + 2},
         {-1.0 / (k1 * D), (1.0 / k1 + 1.0 / k2) / D, -1.0 / (k2 * D)}});
  }
  // Per axis: the median, and the estimates further than 3 robust sigmas (at least 0.15 px)
  // from it left out of the local values.
  for (size_t axis = 0; axis < 2; ++axis) {
    auto& e = bias.estimates[axis];
    out.edge_bias_pairs[axis] = static_cast<int>(e.size());
    if (out.edge_bias_pairs[axis] < min_pairs) continue;
    std::vector<double> b, dev;
    for (const auto& x : e) b.push_back(x.b);
    const double m = median(b);
    for (double x : b) dev.push_back(std::abs(x - m));
    out.edge_bias_scatter[axis] = 1.4826 * median(dev);
    const double cut = std::max(0.15, 3.0 * out.edge_bias_scatter[axis]);
    e.erase(std::remove_if(e.begin(), e.end(),
                           [&](const EdgeBias::Estimate& x) { return std::abs(x.b - m) > cut; }),
            e.end());
    out.edge_bias[axis] = m;
    // The transitions' offset noise sigma: with b = C o (C: estimates x transitions, o
    // independent of variance sigma^2), E[sum_i (b_i - mean b)^2] = sigma^2 (tr(C C^T) -
    // |C^T 1|^2 / N), neighbouring estimates sharing transitions.
    if (e.size() >= 2) {
      const auto N = static_cast<double>(e.size());
      double mean = 0.0, ss = 0.0, trace = 0.0;
      std::map<int, double> column;
      for (const auto& x : e) mean += x.b / N;
      for (const auto& x : e) {
        ss += (x.b - mean) * (x.b - mean);
        for (size_t t = 0; t < 3; ++t) {
          trace += x.coef[t] * x.coef[t];
          column[x.edge[t]] += x.coef[t];
        }
      }
      double ones = 0.0;
      for (const auto& [t, c] : column) ones += c * c;
      const double dof = trace - ones / N;
      if (dof > 0.0) out.edge_offset_sd[axis] = std::sqrt(ss / dof);
    }
  }
}

}  // namespace

cv::Mat tag_pattern(const std::string& family, int id) {
  const render::TagFamily* f = render::find_tag_family(family);
  if (!f) throw InputError("unsupported tag family '" + family + "'");
  apriltag_family_t* fam = f->create();
  cv::Mat out;
  if (id >= 0 && static_cast<uint32_t>(id) < fam->ncodes) {
    image_u8_t* im = apriltag_to_image(fam, id);
    out = cv::Mat(im->height, im->width, CV_8UC1);
    for (int r = 0; r < im->height; ++r)
      for (int c = 0; c < im->width; ++c) out.at<uchar>(r, c) = im->buf[r * im->stride + c];
    // libapriltag 3.3 does not export image_u8_destroy; it is free(buf) + free(im).
    std::free(im->buf);
    std::free(im);
  }
  f->destroy(fam);
  return out;
}

namespace {

// The tag's bitmap at object cell coordinates (X right, Y down, the black square [0, n]^2):
// whether (X, Y) is white.
struct Bitmap {
  const cv::Mat& pattern;
  int off;  ///< bitmap index of the black square's first cell
  bool operator()(double X, double Y) const {
    const int c = static_cast<int>(std::floor(X)) + off, r = static_cast<int>(std::floor(Y)) + off;
    return pattern.at<uchar>(r, c) > 127;
  }
};

// A bent print's sides (check_border()'s stage 6): the quad is the one whose corners are where
// the bowed outer edges end (bowed_ends_ideal(): `ends`, in ideal pixels), and each side's outer
// edge lies off that quad's side by the quadratic (side_bow_at()) less its chord between the ends.
struct BentSides {
  BentSides(const QuadBow& bow, const std::array<cv::Point2d, 4>& ends) : bow(bow), ends(ends) {
    for (size_t k = 0; k < 4; ++k)
      at_ends[k] = {side_bow_at(bow.sides[k], ends[k]),
                    side_bow_at(bow.sides[k], ends[(k + 1) % 4])};
  }
  const QuadBow& bow;
  std::array<cv::Point2d, 4> ends;
  std::array<std::array<cv::Point2d, 2>, 4> at_ends;  ///< side k's bow at its two ends (the chord)
  cv::Point2d off_side(size_t k, const cv::Point2d& p) const {
    const cv::Point2d a = ends[k], ab = ends[(k + 1) % 4] - a;
    const double f = (p - a).dot(ab) / ab.dot(ab);  // where along the side, 0 at a, 1 at b
    return side_bow_at(bow.sides[k], p) - (1.0 - f) * at_ends[k][0] - f * at_ends[k][1];
  }
};

// What the border's samples show, per side (side k runs from corner k to corner k + 1).
struct SideSamples {
  std::array<size_t, 4> planned{};  ///< inner-edge points the bitmap places along the side
  /// The measured inner-edge offsets [px], where along the side (cells) and where on the tag
  /// (object cell coordinates) each was measured, and one cell across the edge there [px].
  std::array<std::vector<double>, 4> offsets, ts, cells;
  std::array<std::vector<cv::Point2d>, 4> where;
  /// Where each was expected, in ideal pixels, and the inward unit normal across the edge there.
  std::array<std::vector<cv::Point2d>, 4> ideal_at, inward;
  std::vector<double> spreads;  ///< the inner edge's spread at the measured points [px]
  /// Pixels whose centre lies within 0.5 px of a side, and how many of them are intermediate.
  int near_side = 0, intermediate = 0;
};

// Stage 1: the border sampled along each side: its contrast against the quiet zone (samples,
// failed, outside) and the inner edge's offset next to each white data cell, fitted along the
// side (thickness_error, thickness_se). False when the bitmap has no white data cell.
bool sample_border(const cv::Mat& gray, int n, const Bitmap& white_at, const SquareToImage& map,
                   const BentSides* follow, const DetectorSettings& s, SideSamples& smp,
                   BorderCheck& out) {
  // Side k runs from corner k to corner k+1: start S, direction D, outward normal O (cells).
  const detail::SquareSides sides(n);
  const cv::Point2d* S = sides.start;
  const cv::Point2d* D = sides.along;
  const cv::Point2d* O = sides.outward;
  constexpr int kPerCell = 4;  // contrast samples per cell along a side
  const int m = kPerCell * n;  // contrast samples per side

  // Every object point, mapped in one batch: white data cell centres, then per side its
  // contrast pairs (quiet zone, border) and its inner-edge triples (edge, outer, inner).
  std::vector<cv::Point2d> obj;
  std::vector<cv::Point2d> white_cells;
  for (int r = 1; r < n - 1; ++r)
    for (int c = 1; c < n - 1; ++c)
      if (white_at(c + 0.5, r + 0.5)) white_cells.emplace_back(c + 0.5, r + 0.5);
  if (white_cells.empty()) return false;
  obj.insert(obj.end(), white_cells.begin(), white_cells.end());
  std::array<std::vector<double>, 4> edge_t;  // positions along side k of inner-edge points
  std::array<size_t, 5> side_from{};          // side k's points: [side_from[k], side_from[k+1])
  for (int k = 0; k < 4; ++k) {
    side_from[static_cast<size_t>(k)] = obj.size();
    for (int j = 0; j < m; ++j) {
      const cv::Point2d p = S[k] + ((j + 0.5) / kPerCell) * D[k];
      obj.push_back(p + 0.5 * O[k]);
      obj.push_back(p - 0.5 * O[k]);
    }
    for (int i = 1; i < n - 1; ++i) {
      const cv::Point2d centre = S[k] + (i + 0.5) * D[k] - 1.5 * O[k];
      if (!white_at(centre.x, centre.y)) continue;
      for (double t : kThicknessT) {
        const cv::Point2d e = S[k] + (i + t) * D[k] - 1.0 * O[k];
        edge_t[static_cast<size_t>(k)].push_back(i + t);
        obj.push_back(e);
        obj.push_back(e + 0.5 * O[k]);
        obj.push_back(e - 0.5 * O[k]);
      }
    }
  }
  side_from[4] = obj.size();
  std::vector<cv::Point2d> ideal = map.map_ideal(obj);
  // A bent print's border follows its bowed sides: every point of side k moved as the side's
  // outer edge is, at the same place along it (a flat print's two border edges are parallel
  // lines; a bent print's or an uncalibrated lens's, parallel curves).
  if (follow)
    for (size_t k = 0; k < 4; ++k)
      for (size_t i = side_from[k]; i < side_from[k + 1]; ++i)
        ideal[i] += follow->off_side(k, ideal[i]);
  const std::vector<cv::Point2d> img = map.to_image(ideal);
  size_t at = 0;
  std::vector<double> white_level(white_cells.size());
  for (size_t i = 0; i < white_cells.size(); ++i) {
    const cv::Point2d p = img[at++];
    white_level[i] = inside(gray, p) ? sample_bilinear(gray, p.x, p.y)
                                     : std::numeric_limits<double>::quiet_NaN();
  }
  std::vector<double> all_white;
  for (double w : white_level)
    if (!std::isnan(w)) all_white.push_back(w);
  const double global_white = median(all_white);

  // Pixels whose centre lies within 0.5 px of a side: in an image integrated over the pixel
  // area (a camera, a supersampled rendering, any blur) those the edge crosses have
  // intermediate values (14-99 % of them on the rendered and synthesized tags); in a
  // point-sampled (aliased) image, such as a 1-sample-per-pixel rendering, none do (0-5 %), and
  // every edge position is quantised to the pixel grid by up to 0.5 px, so the border's two
  // edges may disagree by up to 1 px on a correct quad.
  int& near_side = smp.near_side;
  int& intermediate = smp.intermediate;
  std::vector<double> near;
  auto& spreads = smp.spreads;
  auto& offsets = smp.offsets;
  auto& ts = smp.ts;
  auto& cells = smp.cells;
  auto& where = smp.where;
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k);
    // Contrast samples.
    int failed = 0, outside = 0;
    for (int j = 0; j < m; ++j) {
      const cv::Point2d q = img[at++], b = img[at++];
      const cv::Point2d b_obj = S[k] + ((j + 0.5) / kPerCell) * D[k] - 0.5 * O[k];
      near.clear();
      for (size_t i = 0; i < white_cells.size(); ++i)
        if (!std::isnan(white_level[i]) && cv::norm(white_cells[i] - b_obj) <= 2.5)
          near.push_back(white_level[i]);
      const double white = near.empty() ? global_white : median(near);
      const bool in_image = inside(gray, q) && inside(gray, b);
      outside += !in_image;
      bool pass = in_image && !std::isnan(white);
      if (pass) {
        const double vq = sample_bilinear(gray, q.x, q.y), vb = sample_bilinear(gray, b.x, b.y);
        pass = white - vb > 0.0 && vq - vb >= s.border_min_contrast * (white - vb);
        const double len = cv::norm(q - b);
        if (pass && len > 0.0) {
          const cv::Point2d mid = 0.5 * (q + b), n = (q - b) / len;
          const int cx = cvRound(mid.x), cy = cvRound(mid.y);
          for (int y = cy - 1; y <= cy + 1; ++y)
            for (int x = cx - 1; x <= cx + 1; ++x) {
              if (x < 0 || y < 0 || x >= gray.cols || y >= gray.rows) continue;
              if (std::abs((cv::Point2d(x, y) - mid).dot(n)) > 0.5) continue;
              const double f = (gray.at<uchar>(y, x) - vb) / (vq - vb);
              ++near_side;
              intermediate += f >= 0.15 && f <= 0.85;
            }
        }
      }
      failed += !pass;
    }
    out.samples[ks] = m;
    out.failed[ks] = failed;
    out.outside[ks] = outside;
    // Inner edge of the border next to white data cells.
    for (size_t i = 0; i < edge_t[ks].size(); ++i) {
      const cv::Point2d e_ideal = ideal[at];
      const cv::Point2d e = img[at++], outer = img[at++], inner = img[at++];
      const double cell = cv::norm(inner - outer);  // one cell across the edge, in pixels
      if (!(cell > 0.0)) continue;
      const cv::Point2d nin = (inner - outer) / cell;  // inward: border (dark) -> data (bright)
      const double w = std::clamp(std::min(0.45 * cell, cell - 1.2), 1.0, 4.0);
      if (!inside(gray, e - 1.2 * cell * nin) || !inside(gray, e + 1.2 * cell * nin)) continue;
      // Sub-pixel step near the expected position, kept only where the centroid in half the
      // window agrees to 0.2 px: another edge in the window (a shadow boundary running along
      // the border) pulls the wide centroid more.
      auto clean_step = [&](double from, double win, double& s_out) {
        double sw = 0.0, sh = 0.0;
        if (!edge_offset(gray, e + from * nin, nin, win, sw)) return false;
        if (!edge_offset(gray, e + (from + sw) * nin, nin, std::max(1.0, 0.5 * win), sh))
          return false;
        // The windows of a blurred edge truncate its profile differently wherever it is not
        // symmetric (a lens, JPEG ringing, sharpening): the agreement asked for grows with the
        // edge's own spread (0.2 px up to a spread of 0.67 px, which covers every rendering).
        const double spread = edge_spread(gray, e + (from + sw) * nin, nin, win);
        if (std::abs(sh) > std::max(0.2, 0.3 * (std::isnan(spread) ? 0.0 : spread))) return false;
        s_out = from + sw;
        return true;
      };
      double sv = 0.0;
      if (!clean_step(0.0, w, sv)) {
        // A quad off by more than the window: the steepest dark-to-bright rise within 0.8
        // cell, measured with a window that stays clear of the fitted side (one cell out).
        const double reach = 0.8 * cell;
        double best = 0.0, start = 0.0;
        for (double x = -reach; x <= reach; x += 0.25) {
          const cv::Point2d a = e + (x - 0.5) * nin, b = e + (x + 0.5) * nin;
          const double rise = sample_bilinear(gray, b.x, b.y) - sample_bilinear(gray, a.x, a.y);
          if (rise > best) best = rise, start = x;
        }
        const double win = std::clamp(start + cell - 1.0, 1.0, w);
        if (!clean_step(start, win, sv)) continue;
      }
      offsets[ks].push_back(sv);
      smp.ideal_at[ks].push_back(e_ideal);
      smp.inward[ks].push_back(nin);
      cells[ks].push_back(cell);
      ts[ks].push_back(edge_t[ks][i]);
      where[ks].push_back(S[k] + edge_t[ks][i] * D[k] - 1.0 * O[k]);
      const double spread = edge_spread(gray, e + sv * nin, nin, 0.5 * cell);
      if (!std::isnan(spread)) spreads.push_back(spread);
    }
    out.thickness_error[ks] = end_offset(ts[ks], offsets[ks], &out.thickness_se[ks]);
    smp.planned[ks] = edge_t[ks].size();
  }
  return true;
}

// Stage 2: the edge blur, and the thinning every side shares
// (common_offset).
void shared_thinning(const SideSamples& smp, const DetectorSettings& s, BorderCheck& out) {
  // A camera's tone curve moves every edge of a blurred print alike: gamma encoding puts a
  // blurred edge a fraction of the blur toward the dark side (0.42 sigma per edge for sRGB and
  // black ink at 5 % of the white), so a correct border looks thinner on all four sides. The
  // thinning that every side shares (at least 3, and every side with a white data cell next to
  // it measured), that of the least thin side, is discounted up to border_blur_allowance x the
  // measured blur. A side on an occluder's outline
  // is thinner alone (or with its neighbour, towards one corner): the other sides do not share
  // its error, so it is judged as before. A border thicker on every side is not discounted.
  const double spread = median(smp.spreads);
  out.edge_blur = std::isnan(spread) ? 0.0 : std::sqrt(std::max(0.0, spread * spread - 0.25));
  {
    int planned = 0, measured = 0, thinner = 0;
    double least = -std::numeric_limits<double>::infinity();  // the least thin side
    for (size_t k = 0; k < 4; ++k) {
      const double t = out.thickness_error[k];
      planned += smp.planned[k] >= 4;
      if (std::isnan(t)) continue;
      ++measured;
      thinner += t < 0.0;
      least = std::max(least, t);
    }
    // Every side the bitmap lets us measure must have been measured: a side whose inner edge
    // is not found where one cell inside it should be (a side moved off the border) is no
    // evidence of a thinning shared by all sides.
    if (measured >= 3 && measured == planned && thinner == measured)
      out.common_offset = std::max(least, -s.border_blur_allowance * out.edge_blur);
  }
}

// Stage 3: each side's thickness error less what the print explains (the edge bias its cells
// show, what every side shares), with each side's limit (side_limit) and what was expected
// (expected_thickness_error).
std::array<double, 4> unexplained_thickness(const cv::Mat& gray,
                                            const std::array<cv::Point2d, 4>& corners, int n,
                                            const Bitmap& white_at, const SquareToImage& map,
                                            const DetectorSettings& s, const SideSamples& smp,
                                            BorderCheck& out) {
  const double N = n;
  const detail::SquareSides sides(n);
  const cv::Point2d* S = sides.start;
  const cv::Point2d* D = sides.along;
  // The print's edge bias, measured on the tag's own cells: every edge of the print imaged b
  // toward the white (ink spread; the tone curve under blur; one axis only under motion blur).
  // The sides are fitted to the outer edges, so the quad is dilated by b on each side and the
  // cell it predicts by 2 b / n, while the inner edge lies b further in: a correct side's
  // thickness error is 2 b (1 - 1/n), with b of the axis across it (sides 0 and 2 run along X,
  // their normal is along Y). A side moved off the border adds its own error, which b, from
  // runs of cells with the local scale eliminated, does not share.
  EdgeBias bias;
  if (s.border_edge_bias) measure_edge_bias(gray, n, white_at, map, kMinEdgeBiasPairs, bias, out);
  int planned = 0, measured = 0;
  for (size_t k = 0; k < 4; ++k) {
    planned += smp.planned[k] >= 4;
    measured += !std::isnan(out.thickness_error[k]);
  }
  const bool biased = !std::isnan(out.edge_bias[0]) && !std::isnan(out.edge_bias[1]);
  // With the print's model, each side's error less what the cells say sets it apart from the
  // others: at every inner-edge point 2 (b - b_mean) (1 - 1/n), b the local bias across the
  // side (clamped to border_max_edge_bias of the side's cell) and b_mean the tag's, is taken
  // off before the line fit along the side.
  std::array<double, 4> shared = out.thickness_error;
  out.side_limit.fill(out.thickness_limit);
  const double b_mean = biased ? 0.5 * (out.edge_bias[0] + out.edge_bias[1]) : 0.0;
  if (biased)
    for (size_t k = 0; k < 4; ++k) {
      const size_t axis = k % 2 == 0 ? 1 : 0;  // sides 0 and 2 run along X: their normal is Y
      const double cell = cv::norm(corners[(k + 1) % 4] - corners[k]) / n;
      const double limit = s.border_max_edge_bias * cell;
      std::vector<double> r = smp.offsets[k];
      for (size_t i = 0; i < r.size(); ++i) {
        const double b =
            std::clamp(bias.at(axis, smp.where[k][i], out.edge_bias[axis]), -limit, limit);
        r[i] -= 2.0 * (b - b_mean) * (1.0 - 1.0 / n);
      }
      shared[k] = end_offset(smp.ts[k], r, &out.thickness_se[k]);
      // The bias across the side itself, a quarter and three quarters along it (perspective
      // grows an ink spread in pixels toward the near side); 0 where the axis's bias is within
      // what the estimator itself shows on clean renderings (edge_bias_deadband).
      // Nor in a point-sampled image, whose edges are quantised to the pixel grid (`aliased`).
      for (size_t e = 0; e < 2; ++e) {
        const bool off = out.aliased || std::abs(out.edge_bias[axis]) <= s.edge_bias_deadband;
        const cv::Point2d at = S[k] + (0.25 + 0.5 * static_cast<double>(e)) * N * D[k];
        const double b = bias.at(axis, at, out.edge_bias[axis]);
        out.side_edge_bias[k][e] = off ? 0.0 : std::clamp(b, -limit, limit);
        if (!off && std::abs(b) < limit)
          out.side_edge_bias_sensitivity[k][e] = bias.sensitivity(axis, at);
      }
      // A print whose edges are irregular (a real printer, JPEG) scatters the border's edges
      // as much as its cells': the limit is at least border_scatter_allowance x that scatter.
      out.side_limit[k] =
          std::max(out.thickness_limit, s.border_scatter_allowance * out.edge_bias_scatter[axis]);
    }
  // What all sides share, c. With the model: what the cells say they share, 2 b_mean (1 -
  // 1/n), so that each side's error is the part of it the print's edges do not explain;
  // where a side the bitmap lets us measure was not measured, a side whose inner edge is not
  // found where one cell inside it should be, c is instead as close to 0 as a side's limit
  // from that allows (such a side is no evidence of where the border is, and the others are
  // then held nearer to the fixed limit). Without it, the shared-thinning discount.
  double c = 0.0;
  if (biased) {
    const double centre = 2.0 * b_mean * (1.0 - 1.0 / n);
    c = measured >= 3 && measured == planned
            ? centre
            : std::clamp(0.0, centre - s.border_max_thickness_error,
                         centre + s.border_max_thickness_error);
  } else {
    c = out.common_offset;
  }
  std::array<double, 4> residual{};
  for (size_t k = 0; k < 4; ++k) residual[k] = shared[k] - c;
  // What the print's border does on every side alike. A real print's border is not exactly one
  // of its cells thick (the printer's rounding of the bitmap, toner, a relief print's walls, the
  // camera's resampling), but it is the same print on all four sides; a side on an occluder's
  // outline or moved off the border deviates alone. Where at least three sides are measured
  // and all deviate the same way, the least deviating one (at most border_max_edge_bias of a
  // cell) is the print's and is taken off every side.
  // The deviation is a fraction of a cell: under perspective each side's share of it, in
  // pixels, is that fraction of the cell across the side.
  if (s.border_shared_deviation) {
    int measured_sides = 0, above = 0, below = 0;
    double least = std::numeric_limits<double>::infinity();  // [cells]
    std::array<double, 4> cell{};
    for (size_t k = 0; k < 4; ++k) {
      if (std::isnan(residual[k]) || smp.cells[k].empty()) continue;
      cell[k] = median(smp.cells[k]);
      ++measured_sides;
      above += residual[k] > 0.0;
      below += residual[k] < 0.0;
      if (std::abs(residual[k] / cell[k]) < std::abs(least)) least = residual[k] / cell[k];
    }
    if (measured_sides >= 3 && (above == measured_sides || below == measured_sides)) {
      out.shared_deviation = std::clamp(least, -s.border_max_edge_bias, s.border_max_edge_bias);
      for (size_t k = 0; k < 4; ++k)
        if (!std::isnan(residual[k])) residual[k] -= out.shared_deviation * cell[k];
    }
  }
  for (size_t k = 0; k < 4; ++k) {
    out.expected_thickness_error[k] = out.thickness_error[k] - residual[k];
    // A deviation is only evidence where it stands out of the side's own measurement noise.
    if (s.border_significance > 0.0 && !std::isnan(out.thickness_se[k]))
      out.side_limit[k] = std::max(out.side_limit[k], s.border_significance * out.thickness_se[k]);
  }
  return residual;
}

// Stage 4: a side fails on its contrast or on its unexplained thickness (`residual`); ok and
// the reason.
void judge_sides(const std::array<double, 4>& residual, const DetectorSettings& s,
                 BorderCheck& out) {
  const bool biased = !std::isnan(out.edge_bias[0]) && !std::isnan(out.edge_bias[1]);
  // A side fails on either test; the reason names the side that fails worst (relative to its
  // threshold), which is the one on the occluder's outline when the others only inherit part
  // of its error through the homography.
  char buf[200];
  double worst = 0.0;  // how far the worst failing side exceeds its threshold (ratio)
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k);
    const int m = out.samples[ks];
    const int failed = out.failed[ks];
    const double contrast_excess =
        std::max(failed / std::max(1.0, s.border_max_failed_fraction * m),
                 out.outside[ks] > 0 ? 1.0 + static_cast<double>(out.outside[ks]) / m : 0.0);
    const double thickness_excess =
        std::isnan(residual[ks]) ? 0.0 : std::abs(residual[ks]) / out.side_limit[ks];
    // A quiet zone cut by the image border cannot be verified: a tag is only accepted with its
    // quiet zone in the image (else a partly visible neighbour, e.g. on another face of a cube,
    // could pass and hide the target as a duplicate).
    const bool contrast_fails = failed > s.border_max_failed_fraction * m || out.outside[ks] > 0;
    const bool thickness_fails = thickness_excess > 1.0;
    if (!contrast_fails && !thickness_fails) continue;
    out.ok = false;
    const double excess =
        std::max(contrast_fails ? contrast_excess : 0.0, thickness_fails ? thickness_excess : 0.0);
    if (excess <= worst) continue;
    worst = excess;
    if (out.outside[ks] > 0 && (!thickness_fails || contrast_excess >= thickness_excess))
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): quiet zone outside the image at %d of %d samples", k,
                    k, (k + 1) % 4, out.outside[ks], m);
    else if (contrast_fails && (!thickness_fails || contrast_excess >= thickness_excess))
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): quiet zone not brighter than the border at %d of "
                    "%d samples",
                    k, k, (k + 1) % 4, failed, m);
    else if (biased)
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): black border %.2f px %s than one cell, %.2f px "
                    "expected from the print's edge bias",
                    k, k, (k + 1) % 4, std::abs(out.thickness_error[ks]),
                    out.thickness_error[ks] < 0 ? "thinner" : "thicker",
                    out.expected_thickness_error[ks]);
    else if (out.common_offset == 0.0)
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): black border %.2f px %s than one cell", k, k,
                    (k + 1) % 4, std::abs(out.thickness_error[ks]),
                    out.thickness_error[ks] < 0 ? "thinner" : "thicker");
    else
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): black border %.2f px %s than one cell (%.2f px "
                    "of it on every side discounted for blur)",
                    k, k, (k + 1) % 4, std::abs(out.thickness_error[ks]),
                    out.thickness_error[ks] < 0 ? "thinner" : "thicker",
                    std::abs(out.common_offset));
    out.reason = buf;
  }
}

// A bow that a flat tag would not show (taken off, take_off_bow()): measured, not in a
// point-sampled image (its staircase bends the sides), some corner's shift above
// border_bow_correction and border_significance of its standard error, on cells of at least
// border_bow_min_cell (on smaller ones a flat tag's data cells can fake it).
bool bow_to_take_off(const QuadBow& bow, bool aliased, const std::array<cv::Point2d, 4>& corners,
                     int n, const DetectorSettings& s) {
  if (!bow.measured || aliased || !(s.border_bow_correction > 0.0)) return false;
  bool bowed = false;
  for (size_t k = 0; k < 4; ++k) {
    const double shift = cv::norm(bow.corner_shift[k]);
    bowed = bowed ||
            (shift > s.border_bow_correction && shift > s.border_significance * bow.corner_se[k]);
  }
  return bowed && narrowest_side(corners) / n >= s.border_bow_min_cell;
}

// Stage 5: the sides' bow (quad_bow): a corner further from where the straight sides meet than
// border_max_bow fails; a smaller bow that a flat tag would not show is marked to be taken off.
void judge_bow(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int n,
               const io::Calibration* calib, const EdgeSamples* edges, const DetectorSettings& s,
               BorderCheck& out) {
  if (out.ok && s.border_max_bow > 0.0) {
    out.bow = quad_bow(gray, corners, n, calib, edges);
    // A point-sampled image's edge samples are quantised to the pixel grid, and its staircase
    // bends a quadratic's ends (flat tags of moving_cameras.yaml rendered at 1 sample per pixel:
    // up to 1.04 px): as much more as for the thickness.
    const double limit = s.border_max_bow + (out.aliased ? kAliasedAllowance : 0.0);
    double worst_bow = 0.0;
    for (int k = 0; k < 4 && out.bow.measured; ++k) {
      const size_t ks = static_cast<size_t>(k);
      const double shift = cv::norm(out.bow.corner_shift[ks]);
      if (!(shift > limit && shift > s.border_significance * out.bow.corner_se[ks]) ||
          shift <= worst_bow)
        continue;
      worst_bow = shift;
      out.ok = false;
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "sides %d and %d bowed: corner %d lies %.2f px (se %.2f) from where their "
                    "straight lines meet (a bent print or lens distortion not calibrated)",
                    (k + 3) % 4, k, k, shift, out.bow.corner_se[ks]);
      out.reason = buf;
    }
  }
  // A bow that a flat tag would not show is taken off (take_off_bow()).
  if (out.ok) out.bow_taken_off = bow_to_take_off(out.bow, out.aliased, corners, n, s);
}

// How far the border's inner edge bows with its outer edge (BorderCheck::inner_bow): per side k
// with 8 inner-edge points or more, the offsets measured against the straight sides,
// r_i = a + b t_i + gamma_k p_i (least squares; p_i the offset the outer edge's bow predicts
// there, side_bow_at() across the edge), gamma_k 1 where the inner edge bows as the outer one does
// (a bent print) and 0 where it is straight (the outer edge's bow is something else: a side
// partly on an occluder's outline); its standard error with one independent measurement per
// data cell, as thickness_se. The sides' estimates combined, weighted by their precision (a side
// whose bow predicts little at its inner-edge points has little weight). NaN where none.
void inner_bow(const SideSamples& smp, const QuadBow& bow, double& gamma, double& se) {
  double weight = 0.0, sum = 0.0;
  for (size_t k = 0; k < 4; ++k) {
    const auto& r = smp.offsets[k];
    const size_t m = r.size();
    if (m < 8) continue;
    Eigen::Matrix3d XtX = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Xty = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> X(m);
    for (size_t i = 0; i < m; ++i) {
      const double p = side_bow_at(bow.sides[k], smp.ideal_at[k][i]).dot(smp.inward[k][i]);
      X[i] = Eigen::Vector3d(1.0, smp.ts[k][i], p);
      XtX += X[i] * X[i].transpose();
      Xty += r[i] * X[i];
    }
    if (!(std::abs(XtX.determinant()) > 1e-12)) continue;
    const Eigen::Vector3d beta = XtX.ldlt().solve(Xty);
    double rss = 0.0;
    for (size_t i = 0; i < m; ++i) rss += std::pow(r[i] - X[i].dot(beta), 2);
    const double per_cell = static_cast<double>(std::size(kThicknessT));
    const double var = rss / static_cast<double>(m - 3) * per_cell * XtX.inverse()(2, 2);
    if (!(var > 0.0) || !std::isfinite(var)) continue;
    weight += 1.0 / var;
    sum += beta(2) / var;
  }
  gamma = weight > 0.0 ? sum / weight : std::numeric_limits<double>::quiet_NaN();
  se = weight > 0.0 ? 1.0 / std::sqrt(weight) : std::numeric_limits<double>::quiet_NaN();
}

// Where the bowed sides end (QuadBow::corner_shift), in undistorted (ideal) pixels.
std::array<cv::Point2d, 4> bowed_ends_ideal(const std::array<cv::Point2d, 4>& corners,
                                            const QuadBow& bow, const io::Calibration* calib) {
  std::array<cv::Point2d, 4> c = SquareToImage::ideal_corners(corners, calib);
  for (size_t k = 0; k < 4; ++k) c[k] += bow.corner_shift[k];
  return c;
}

// Whether a quad the check failed is worth checking again as a bent print: a bow that a flat
// tag would not show (bow_to_take_off()), and no corner's shift beyond border_max_bent, up to
// which the shift puts the corners where the bowed sides end.
bool bent_print(const QuadBow& bow, const BorderCheck& failed,
                const std::array<cv::Point2d, 4>& corners, int n, const DetectorSettings& s) {
  if (!(s.border_max_bent > 0.0) || !bow_to_take_off(bow, failed.aliased, corners, n, s))
    return false;
  for (size_t k = 0; k < 4; ++k)
    if (!(cv::norm(bow.corner_shift[k]) <= s.border_max_bent)) return false;
  return true;
}

}  // namespace

BorderCheck check_border(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners,
                         const cv::Mat& pattern, int border_cells, const DetectorSettings& s,
                         const io::Calibration* calib, const EdgeSamples* edges) {
  CV_Assert(gray.type() == CV_8UC1);
  BorderCheck out;
  const int n = border_cells;
  if (pattern.empty() || n < 3 || pattern.rows != pattern.cols || pattern.rows < n + 2) return out;
  const Bitmap white_at{pattern, (pattern.rows - n) / 2};
  // Only for a black border ring inside a white ring (not the reversed-border families).
  for (int i = 0; i < n; ++i)
    if (white_at(i + 0.5, 0.5) || white_at(0.5, i + 0.5) || white_at(i + 0.5, n - 0.5) ||
        white_at(n - 0.5, i + 0.5) || !white_at(i + 0.5, -0.5) || !white_at(-0.5, i + 0.5) ||
        !white_at(i + 0.5, n + 0.5) || !white_at(n + 0.5, i + 0.5))
      return out;
  const SquareToImage map(corners, n, calib);
  if (!map.ok()) return out;
  out.checked = true;

  // Stages 1-5 on the quad's straight sides, or on a bent print's (`follow`); `samples` keeps
  // what stage 1 sampled.
  const auto run = [&](const std::array<cv::Point2d, 4>& quad, const SquareToImage& to_image,
                       const BentSides* follow, SideSamples& samples) {
    BorderCheck r = out;
    if (!sample_border(gray, n, white_at, to_image, follow, s, samples, r)) {
      r.checked = false;
      return r;
    }
    r.aliased = samples.near_side >= 16 && samples.intermediate < 0.1 * samples.near_side;
    r.thickness_limit = s.border_max_thickness_error + (r.aliased ? kAliasedAllowance : 0.0);
    shared_thinning(samples, s, r);
    const std::array<double, 4> residual =
        unexplained_thickness(gray, quad, n, white_at, to_image, s, samples, r);
    judge_sides(residual, s, r);
    if (!follow) judge_bow(gray, quad, n, calib, edges, s, r);
    return r;
  };
  SideSamples straight_samples;
  BorderCheck straight = run(corners, map, nullptr, straight_samples);
  if (straight.ok || !straight.checked) return straight;
  // Stage 6: a bent print (DetectorSettings::border_max_bent), checked again on the quad whose
  // corners are where its bowed sides end, every border sample moved off that quad's sides as
  // the bowed outer edge is there.
  const QuadBow bow =
      straight.bow.measured ? straight.bow : quad_bow(gray, corners, n, calib, edges);
  if (!bent_print(bow, straight, corners, n, s)) return straight;
  // The inner edge must bow with the outer one: nearer gamma 1 than 0, measured well enough to
  // tell the two apart (2 standard errors between them).
  inner_bow(straight_samples, bow, straight.inner_bow, straight.inner_bow_se);
  if (!(straight.inner_bow > 0.5 && straight.inner_bow_se <= 0.5)) return straight;
  const std::array<cv::Point2d, 4> ideal_ends = bowed_ends_ideal(corners, bow, calib);
  const SquareToImage bent_map(ideal_ends, n, calib, SquareToImage::Ideal{});
  if (!bent_map.ok()) return straight;
  const std::vector<cv::Point2d> ends = bent_map.to_image({ideal_ends.begin(), ideal_ends.end()});
  const BentSides follow{bow, ideal_ends};
  SideSamples bent_samples;
  BorderCheck bent = run({ends[0], ends[1], ends[2], ends[3]}, bent_map, &follow, bent_samples);
  if (!bent.ok) return straight;
  bent.bow = bow;
  bent.inner_bow = straight.inner_bow;
  bent.inner_bow_se = straight.inner_bow_se;
  bent.bent = true;
  bent.bow_taken_off = true;
  return bent;
}

std::array<cv::Point2d, 4> take_off_bow(const std::array<cv::Point2d, 4>& corners,
                                        const QuadBow& bow, const io::Calibration* calib) {
  if (!bow.measured) return corners;
  const std::array<cv::Point2d, 4> ideal = bowed_ends_ideal(corners, bow, calib);
  if (!calib || !calib->has_distortion()) return ideal;
  const auto c = io::distorted_pixels({ideal.begin(), ideal.end()}, *calib);
  return {c[0], c[1], c[2], c[3]};
}

CornerCovariance bow_covariance(const QuadBow& bow) {
  CornerCovariance cov = CornerCovariance::Zero();
  if (!bow.measured) return cov;
  for (size_t k = 0; k < 4; ++k) {
    const Eigen::Vector2d v(bow.corner_shift[k].x, bow.corner_shift[k].y);
    const double len = v.norm();
    const Eigen::Index i = static_cast<Eigen::Index>(2 * k);
    const double var = bow.corner_se[k] * bow.corner_se[k];
    // Along the shift where it has a direction, else the same in every direction.
    cov.block<2, 2>(i, i) = len > 0.0 ? Eigen::Matrix2d(var * (v / len) * (v / len).transpose())
                                      : Eigen::Matrix2d(var * Eigen::Matrix2d::Identity());
  }
  return cov;
}

std::array<cv::Point2d, 4> remove_edge_bias(const std::array<cv::Point2d, 4>& corners,
                                            const BorderCheck& check,
                                            const io::Calibration* calib) {
  for (const auto& side : check.side_edge_bias)
    if (std::isnan(side[0]) || std::isnan(side[1])) return corners;
  const io::Calibration* dist = calib && calib->has_distortion() ? calib : nullptr;
  std::vector<cv::Point2d> ideal(corners.begin(), corners.end());
  if (dist) ideal = io::ideal_pixels(ideal, *dist);
  const cv::Point2d centre = 0.25 * (ideal[0] + ideal[1] + ideal[2] + ideal[3]);
  // Side k moved inward by its bias: the points a quarter and three quarters along it, each
  // moved by the bias there along the side's inward normal.
  std::array<cv::Point2d, 4> a, d;
  for (size_t k = 0; k < 4; ++k) {
    const cv::Point2d p = ideal[k], q = ideal[(k + 1) % 4], u = q - p;
    cv::Point2d normal(-u.y, u.x);
    normal /= cv::norm(normal);
    if ((centre - p).dot(normal) < 0.0) normal = -normal;
    const cv::Point2d p1 = p + 0.25 * u + check.side_edge_bias[k][0] * normal;
    const cv::Point2d p3 = p + 0.75 * u + check.side_edge_bias[k][1] * normal;
    a[k] = p1;
    d[k] = p3 - p1;
  }
  std::vector<cv::Point2d> out(4);
  for (size_t k = 0; k < 4; ++k) {
    // Corner k: sides k - 1 and k.
    const size_t j = (k + 3) % 4;
    const auto corner = intersect_lines(a[j], d[j], a[k], d[k]);
    if (!corner) return corners;
    out[k] = *corner;
  }
  if (dist) out = io::distorted_pixels(out, *dist);
  return {out[0], out[1], out[2], out[3]};
}

std::optional<std::array<cv::Point2d, 4>> realign_sides(const std::array<cv::Point2d, 4>& corners,
                                                        const BorderCheck& check, int border_cells,
                                                        const DetectorSettings& s, double fraction,
                                                        const io::Calibration* calib) {
  if (!check.checked || check.ok || border_cells < 2) return std::nullopt;
  // Each side's error after the print's model; the one side that fails on it.
  std::array<double, 4> residual{};
  int failing = -1;
  for (size_t k = 0; k < 4; ++k) {
    if (check.outside[k] > 0 || check.failed[k] > s.border_max_failed_fraction * check.samples[k])
      return std::nullopt;
    residual[k] = std::abs(check.thickness_error[k] - check.expected_thickness_error[k]);
    if (!(residual[k] > check.side_limit[k])) continue;  // passes, or not measured (NaN)
    if (failing >= 0) return std::nullopt;
    failing = static_cast<int>(k);
  }
  if (failing < 0) return std::nullopt;
  // One side off alone, every other measured side within half its error. Where several sides
  // fail or deviate alike (a print's border thinner than its cells on every side, and one side
  // moved out), which of them is off is not determined by the check, and a quad realigned on
  // the wrong one can pass as well.
  const size_t f = static_cast<size_t>(failing);
  for (size_t k = 0; k < 4; ++k)
    if (k != f && residual[k] > 0.5 * residual[f]) return std::nullopt;
  const double n = border_cells;
  const double cell = cv::norm(corners[(f + 1) % 4] - corners[f]) / n;
  if (residual[f] > s.border_max_edge_bias * cell) return std::nullopt;
  // remove_edge_bias() moves each side inward by its side_edge_bias: the same operation. A
  // thinner border (signed residual < 0) puts the inner edge closer to the side than one cell:
  // the side belongs further out, which is inward by a negative amount. Moving it out by x
  // grows the cell across it by x / n, so the inner edge one cell inside moves by x (1 - 1/n).
  BorderCheck moved;
  for (auto& side : moved.side_edge_bias) side = {0.0, 0.0};
  const double shift =
      fraction * (check.thickness_error[f] - check.expected_thickness_error[f]) * n / (n - 1.0);
  moved.side_edge_bias[f] = {shift, shift};
  const auto out = remove_edge_bias(corners, moved, calib);
  if (out == corners) return std::nullopt;  // the sides did not intersect
  return out;
}

CornerCovariance undecided_covariance(const std::array<cv::Point2d, 4>& a,
                                      const std::array<cv::Point2d, 4>& b) {
  Eigen::Matrix<double, 8, 1> v;
  for (size_t c = 0; c < 4; ++c) {
    v(static_cast<Eigen::Index>(2 * c)) = 0.5 * (b[c].x - a[c].x);
    v(static_cast<Eigen::Index>(2 * c + 1)) = 0.5 * (b[c].y - a[c].y);
  }
  return v * v.transpose();
}

std::optional<Realigned> realign_and_check(const cv::Mat& gray,
                                           const std::array<cv::Point2d, 4>& corners,
                                           const BorderCheck& check, const cv::Mat& pattern,
                                           int border_cells, const DetectorSettings& s,
                                           const io::Calibration* calib) {
  if (!(s.border_realign_max > 0.0)) return std::nullopt;
  const auto inner = realign_sides(corners, check, border_cells, s, 1.0, calib);
  if (!inner) return std::nullopt;
  for (size_t k = 0; k < 4; ++k)
    if (cv::norm((*inner)[k] - corners[k]) > s.border_realign_max) return std::nullopt;
  // Checked again without a shared deviation: it could take the moved side's error off the
  // others.
  DetectorSettings strict = s;
  strict.border_shared_deviation = false;
  BorderCheck again = check_border(gray, *inner, pattern, border_cells, strict, calib);
  if (!again.ok) return std::nullopt;
  const auto half = realign_sides(corners, check, border_cells, s, 0.5, calib);
  if (!half) return std::nullopt;
  return Realigned{*half, *inner, std::move(again), undecided_covariance(corners, *inner)};
}

CornerCovariance edge_bias_covariance(const std::array<cv::Point2d, 4>& corners,
                                      const BorderCheck& check, const io::Calibration* calib) {
  CornerCovariance cov = CornerCovariance::Zero();
  const io::Calibration* dist = calib && calib->has_distortion() ? calib : nullptr;
  const auto ideal = [&](const std::array<cv::Point2d, 4>& c) {
    std::vector<cv::Point2d> v(c.begin(), c.end());
    return dist ? io::ideal_pixels(v, *dist) : v;
  };
  const auto base = ideal(remove_edge_bias(corners, check, calib));
  constexpr double h = 1e-3;  // px
  // The corners' derivative with respect to each side end's value.
  std::array<std::array<Eigen::Matrix<double, 8, 1>, 2>, 4> J;
  for (size_t k = 0; k < 4; ++k)
    for (size_t e = 0; e < 2; ++e) {
      BorderCheck moved = check;
      moved.side_edge_bias[k][e] += h;
      const auto shifted = ideal(remove_edge_bias(corners, moved, calib));
      for (size_t c = 0; c < 4; ++c) {
        J[k][e](static_cast<Eigen::Index>(2 * c)) = (shifted[c].x - base[c].x) / h;
        J[k][e](static_cast<Eigen::Index>(2 * c + 1)) = (shifted[c].y - base[c].y) / h;
      }
    }
  // Each transition's offset moves every side end that depends on it (its sensitivity there).
  std::map<int, Eigen::Matrix<double, 8, 1>> g;
  for (size_t k = 0; k < 4; ++k)
    for (size_t e = 0; e < 2; ++e)
      for (const auto& [t, c] : check.side_edge_bias_sensitivity[k][e]) {
        auto it = g.try_emplace(t, Eigen::Matrix<double, 8, 1>::Zero()).first;
        it->second += c * J[k][e];
      }
  for (const auto& [t, gt] : g) {
    // Transitions are numbered over both axes; a transition's axis is that of its side ends.
    const double sd = check.edge_offset_sd[t < check.first_y_transition ? 0 : 1];
    cov += sd * sd * gt * gt.transpose();
  }
  return cov;
}

}  // namespace netvmo::frontend
