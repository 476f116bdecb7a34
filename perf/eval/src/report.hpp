#pragma once
// Everything keepless_eval writes: Markdown tables shaped like the paper's
// (I: MP/KF ratio per M, II: multi-M relative ATE, III: KITTI-style absolute,
// IV: comparison with ANMS, V: cost ablation), the BAL table, a CSV of every
// run, SVG plots, and the JSON summary line.

#include <cstdint>
#include <string>
#include <vector>

#include "bal_eval.hpp"
#include "slam_sim.hpp"

namespace keepless::eval {

struct InputReport {
  std::string input, name, group, kind;
  std::uint32_t keyframes = 0;
  std::uint64_t landmarks = 0;
  std::uint32_t width = 0, height = 0;
  RunResult original;
  std::vector<RunResult> ours;  // per M, in --M order
  bool has_baselines = false;
  RunResult anms, random;       // at the operating M
  std::vector<RunResult> ablation;  // c_c, c_c+c_s, c_c+c_b (all = ours at the operating M)
  std::int64_t op_M = 100;
  std::size_t op_index = 0;     // index of op_M in ours
};

struct EvalSummary {
  std::string mode;  // quick | full
  std::uint64_t seed = 1;
  std::vector<std::int64_t> Ms;
  std::vector<InputReport> inputs;
  std::vector<BalResult> bal;
  double elapsed_s = 0;
  std::string command;
};

std::string markdown_tables(const EvalSummary& s);
bool write_outputs(const EvalSummary& s, const std::string& out_dir, std::string* error);
std::string json_summary(const EvalSummary& s);

}  // namespace keepless::eval
