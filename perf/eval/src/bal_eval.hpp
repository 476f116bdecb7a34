#pragma once
// A real BA problem (BAL format): solve the full problem, sparsify it with
// the cameras as keyframes, re-solve on the kept points (and on a random set
// of equal size), and compare the cameras with the full solution after a
// similarity alignment (BAL has no metric scale and no ground truth).

#include <cstdint>
#include <string>
#include <vector>

namespace keepless::eval {

struct BalOptions {
  std::vector<std::int64_t> Ms{100};
  int max_iterations = 50;
  std::uint64_t seed = 1;
};

struct BalRun {
  std::string variant;  // full, ours, random
  std::int64_t M = 0;
  std::uint32_t points = 0;
  std::uint32_t observations = 0;
  double solve_s = 0;
  int iterations = 0;
  double final_cost = 0;
  double pos_rms = 0;      // camera centres vs the full solution, BAL units, after Sim(3)
  double rot_rms_deg = 0;  // camera orientations, same alignment
};

struct BalResult {
  std::string input;
  std::uint32_t cameras = 0, points = 0, observations = 0;
  double extent = 0;  // RMS distance of the full solution's centres from their mean (scale)
  double sparsify_s = 0;
  BalRun full;
  std::vector<BalRun> ours, random;  // per M
};

bool run_bal(const std::string& path, const BalOptions& options, BalResult* out, std::string* error);

}  // namespace keepless::eval
