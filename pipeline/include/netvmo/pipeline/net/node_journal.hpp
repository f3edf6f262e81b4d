// A node's journal, node_<id>.csv: one row per frame the node finished, written as it goes by
// `netvmo node` (into node_<id>.csv.partial, renamed when it ends) and read back by the merge
// (`netvmo launch`, `netvmo merge`, of files gathered from several machines). The format is
// written and read here only:
//
//   frame,t,delta,read_failed,status,tag_id,hamming,margin,c0x..c3y,f0..f7,
//   pnp,pnp_pose[12],initialized,est_w[12],indep,indep_w[12]
//
// numbers as io::exact_text writes them (%.17g, so a row read back is the row written), a pose
// as its translation then its rotation matrix row by row, flags 0 or 1, status the
// TargetStatus's value.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"

namespace netvmo::net {

/// The journal's first line.
inline constexpr const char* kNodeJournalHeader =
    "frame,t,delta,read_failed,status,tag_id,hamming,margin,c0x,c0y,c1x,c1y,c2x,c2y,c3x,c3y,"
    "f0,f1,f2,f3,f4,f5,f6,f7,pnp,pnp_pose[12],initialized,est_w[12],indep,indep_w[12]";

/// One frame of a node: its front end's result (corners, f, the PnP pose; not the per-tag
/// details), its networked estimate and its independent baseline's, in the world.
struct NodeRow {
  int frame = 0;
  double t = 0.0;  ///< the frame's time [s] on the node's clock
  frontend::Observation cam;
  bool initialized = false, indep = false;
  obs::SE3 est_w = obs::SE3::Identity(), indep_w = obs::SE3::Identity();
};

/// The row's line, with its newline.
std::string node_journal_row(const NodeRow& row);

/// The rows of a journal in the order written. Each row must have every field (frames
/// increasing, times not decreasing, flags 0 or 1, a status of TargetStatus, finite numbers,
/// rotations orthonormal); InputError naming the file, line and field otherwise, or when the
/// first line is not kNodeJournalHeader. With `allow_missing`, a journal that is not there is
/// read from its .partial (a node killed for good), whose last line, cut off by the kill, is
/// left out; no .partial either: no rows.
std::vector<NodeRow> read_node_journal(std::filesystem::path file, bool allow_missing);

}  // namespace netvmo::net
