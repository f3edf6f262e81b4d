// A node's journal (net/node_journal.hpp): what `netvmo node` writes is what the merge reads
// back, bit for bit, and a journal damaged in any field (a file gathered from another machine)
// is one line naming the file, the line and the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/net/node.hpp"
#include "netvmo/pipeline/net/node_journal.hpp"
#include "test_util.hpp"

namespace netvmo::net {
namespace {
namespace fs = std::filesystem;
using obs::SE3;

// Two rows of every kind of field: a detection with a PnP pose, and a frame without one.
std::vector<NodeRow> two_rows() {
  NodeRow a;
  a.frame = 0;
  a.t = 1.0 / 3.0;
  a.cam.delta = true;
  a.cam.status = frontend::TargetStatus::detected;
  a.cam.tag_id = 7;
  a.cam.hamming = 1;
  a.cam.margin = 61.25;
  for (int k = 0; k < 4; ++k) a.cam.corners_px[static_cast<size_t>(k)] = {100.1 + k, 200.7 - k};
  for (int k = 0; k < 8; ++k) a.cam.f_normalized(k) = 0.1 * k - 0.35;
  a.cam.g_io_pnp = obs::make_pose(obs::Vec3(0.1, -0.2, 2.0), obs::Vec3(0.3, -0.2, 0.1));
  a.initialized = true;
  a.est_w = obs::make_pose(obs::Vec3(1.0, 2.0, 0.5), obs::Vec3(-0.7, 0.4, 2.9));
  NodeRow b;
  b.frame = 2;
  b.t = 0.4;
  b.cam.status = frontend::TargetStatus::border_mismatch;
  b.cam.tag_id = -1;
  b.cam.read_failed = true;
  b.initialized = true;
  b.est_w = a.est_w;
  b.indep = true;
  b.indep_w = obs::make_pose(obs::Vec3(-1.0, 0.0, 3.0), obs::Vec3(0.0, 1.5, 0.0));
  return {a, b};
}

std::string journal_text(const std::vector<NodeRow>& rows) {
  std::string s = std::string(kNodeJournalHeader) + "\n";
  for (const auto& r : rows) s += node_journal_row(r);
  return s;
}

void expect_same(const NodeRow& x, const NodeRow& y) {
  EXPECT_EQ(x.frame, y.frame);
  EXPECT_EQ(x.t, y.t);
  EXPECT_EQ(x.cam.delta, y.cam.delta);
  EXPECT_EQ(x.cam.read_failed, y.cam.read_failed);
  EXPECT_EQ(x.cam.status, y.cam.status);
  EXPECT_EQ(x.cam.tag_id, y.cam.tag_id);
  EXPECT_EQ(x.cam.hamming, y.cam.hamming);
  EXPECT_EQ(x.cam.margin, y.cam.margin);
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(x.cam.corners_px[k].x, y.cam.corners_px[k].x);
    EXPECT_EQ(x.cam.corners_px[k].y, y.cam.corners_px[k].y);
  }
  EXPECT_EQ(x.cam.f_normalized, y.cam.f_normalized);
  ASSERT_EQ(x.cam.g_io_pnp.has_value(), y.cam.g_io_pnp.has_value());
  if (x.cam.g_io_pnp) {
    EXPECT_EQ(x.cam.g_io_pnp->matrix(), y.cam.g_io_pnp->matrix());
  }
  EXPECT_EQ(x.initialized, y.initialized);
  EXPECT_EQ(x.est_w.matrix(), y.est_w.matrix());
  EXPECT_EQ(x.indep, y.indep);
  EXPECT_EQ(x.indep_w.matrix(), y.indep_w.matrix());
}

TEST(NodeJournal, ReadsBackWhatTheNodeWroteBitForBit) {
  const fs::path dir = test::scratch_dir("node_journal_round_trip");
  const auto rows = two_rows();
  const fs::path file = test::write_text(dir / "node_1.csv", journal_text(rows));
  const auto back = read_node_journal(file, false);
  ASSERT_EQ(back.size(), rows.size());
  for (size_t k = 0; k < rows.size(); ++k) expect_same(back[k], rows[k]);
  // Written again, the same text.
  EXPECT_EQ(journal_text(back), test::slurp(file));

  // A node killed for good: no journal, its .partial read instead without its last line (cut
  // off by the kill, no newline); without allow_missing the journal must be there.
  fs::remove(file);
  std::string partial = journal_text(rows);
  partial += partial.substr(partial.rfind('\n', partial.size() - 2) + 1, 40);  // a cut line
  test::write_text(partial_path(file), partial);
  EXPECT_EQ(read_node_journal(file, true).size(), 2u);
  test::expect_input_error([&] { read_node_journal(file, false); }, {file.string(), "not found"});
  EXPECT_TRUE(read_node_journal(dir / "node_9.csv", true).empty());
}

// Every field damaged in turn, in the second row (line 3): one line naming the file, the line
// and the column, and what was found.
TEST(NodeJournal, ADamagedFieldIsOneLineNamingFileLineAndColumn) {
  const fs::path dir = test::scratch_dir("node_journal_damaged");
  const auto rows = two_rows();
  const std::string good = node_journal_row(rows[0]);
  const std::string second = node_journal_row(rows[1]);
  // The second row with field `index` (from 0) replaced by `value`.
  const auto with = [&](size_t index, const std::string& value) {
    std::vector<std::string> f;
    std::string cell;
    for (const char c : second.substr(0, second.size() - 1)) {
      if (c == ',') {
        f.push_back(cell);
        cell.clear();
      } else {
        cell += c;
      }
    }
    f.push_back(cell);
    f.at(index) = value;
    std::string line;
    for (size_t k = 0; k < f.size(); ++k) line += (k ? "," : "") + f[k];
    return line + "\n";
  };
  const fs::path file = dir / "node_2.csv";
  const auto expect = [&](const std::string& row, std::initializer_list<std::string> needles) {
    test::write_text(file, std::string(kNodeJournalHeader) + "\n" + good + row);
    test::expect_input_error([&] { read_node_journal(file, false); }, needles);
    test::expect_input_error([&] { read_node_journal(file, false); }, {file.string() + ":3: "});
  };
  // The undamaged second row reads.
  test::write_text(file, std::string(kNodeJournalHeader) + "\n" + good + with(1, "0.4"));
  EXPECT_EQ(read_node_journal(file, false).size(), 2u);

  expect(with(0, "1.5"), {"frame: expected an integer, got '1.5'"});
  expect(with(0, "0"), {"frame: 0 is not after the previous row's"});
  expect(with(0, "-3"), {"frame: expected a frame index >= 0, got -3"});
  expect(with(0, "99999999999"), {"frame: expected an integer"});
  expect(with(1, "x"), {"t: expected a finite number, got 'x'"});
  expect(with(1, "nan"), {"t: expected a finite number, got 'nan'"});
  expect(with(1, "0.3"), {"t: 0.29999999999999999 is before the previous row's"});
  expect(with(2, "2"), {"delta: expected 0 or 1, got '2'"});
  expect(with(4, "7"), {"status: expected a status 0..6, got '7'"});
  expect(with(4, "-1"), {"status: expected a status 0..6, got '-1'"});
  expect(with(7, "inf"), {"margin: expected a finite number, got 'inf'"});
  expect(with(8, ""), {"c0x: expected a finite number, got ''"});
  expect(with(23, "1e999"), {"f7: expected a finite number, got '1e999'"});
  expect(with(24, "yes"), {"pnp: expected 0 or 1, got 'yes'"});
  // est_w's rotation (fields 41..49, after its translation 38..40): a scaled entry, a
  // reflection (its first row negated).
  expect(with(41, "1.5"), {"est_w[3]..est_w[11]: not a rotation matrix"});
  {
    NodeRow mirrored = rows[1];
    mirrored.est_w.linear().row(0) = -rows[1].est_w.linear().row(0);
    expect(node_journal_row(mirrored), {"est_w[3]..est_w[11]: not a rotation matrix"});
  }
  expect(with(62, "0.5x"), {"indep_w[11]: expected a finite number, got '0.5x'"});
  // Fields missing or extra.
  expect(second.substr(0, second.rfind(',')) + "\n", {"62 fields, expected 63"});
  expect(second.substr(0, second.size() - 1) + ",0\n", {"64 fields, expected 63"});
  expect(second.substr(0, second.size() - 1) + ",\n", {"64 fields, expected 63"});

  // Another file under the journal's name: its first line named.
  test::write_text(file, "frame,t,camera,delta,px,py,pz,rx,ry,rz\n0,0,1,1,0,0,0,0,0,0\n");
  test::expect_input_error([&] { read_node_journal(file, false); },
                           {file.string() + ":1: not a node journal"});
}

}  // namespace
}  // namespace netvmo::net
