#pragma once
// Everything keepless_eval writes, generated from the contract (run_record.hpp):
// Markdown tables (accuracy at equal kept fraction with mean ± sd over seeds,
// the equal-count baselines, the per-group comparison shaped like the paper's
// Table V, the cost ablation, and which claims held), a CSV of every run,
// SVG plots, and the JSON line. README's Evidence section is tables.md;
// `keepless_eval --report DIR` regenerates it from DIR's runs.csv.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "run_record.hpp"
#include "slam_sim.hpp"

namespace keepless::eval {

// One keyframe's keypoints, ours vs ANMS (the SVG).
struct Snapshot {
  std::string input, kind;
  int width = 0, height = 0;
  std::int64_t M = 0;
  std::vector<SnapshotPoint> ours, anms;
};

struct EvalSummary {
  std::string mode;  // quick | full
  std::vector<std::uint64_t> seeds;
  std::map<std::string, double> error_floor;  // per group, metres
  std::string command, settings;
  std::vector<std::string> settings_inputs;
  std::vector<Comparison> comparisons;  // every record
  std::vector<ContractRun> runs;        // summarize(comparisons[i])
  std::vector<Snapshot> snapshots;
  double elapsed_s = 0;
  // keepless's core::Params policy (the JSON's "policy"); empty scope when
  // the summary was read back with --report (the command line then says it).
  std::string scope, cost_model;
  std::uint32_t coverage_floor = 0;
};

std::string markdown_tables(const EvalSummary& s);
bool write_outputs(const EvalSummary& s, const std::string& out_dir, std::string* error);
// The comparisons, command and settings back from write_outputs' runs.csv
// and meta.txt, appended to `s`, so the tables can be regenerated (from one
// run or several) without re-running.
bool read_outputs(const std::string& out_dir, EvalSummary* s, std::string* error);
std::string json_summary(const EvalSummary& s);

}  // namespace keepless::eval
