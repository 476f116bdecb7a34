#pragma once
// A real BA problem (BAL format): solve the full problem, sparsify it with
// the cameras as keyframes, re-solve on the kept points (and on random and
// longest-track sets of equal size), and compare the cameras with the full
// solution after a similarity alignment (BAL has no metric scale and no
// ground truth, so the full solve is the reference: its "ATE" is 0).

#include <cstdint>
#include <string>
#include <vector>

#include "run_record.hpp"

namespace keepless::eval {

struct BalOptions {
  std::int64_t M = 100;            // used when target_fraction is NaN
  double target_fraction = NAN;    // else: the M whose kept share is closest
  int max_iterations = 50;
  std::vector<std::uint64_t> seeds{1};  // random's priorities; ours is deterministic
  bool baselines = true;
};

// Fills `out` (kind bal, one record per seed; ANMS is not defined without
// keypoint responses and stays empty).
bool run_bal(const std::string& path, const BalOptions& options, Comparison* out, std::string* error);

}  // namespace keepless::eval
