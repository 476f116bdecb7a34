#include "vo_eval.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "real_vo.hpp"
#include "vo_report.hpp"

namespace keepless::eval::vo {
namespace {

RunRecord record_of(const RealRunResult& r, const char* variant, std::uint64_t seed, std::int64_t M) {
  RunRecord x;
  x.variant = variant;
  x.seed = seed;
  x.M = M;
  x.mps = static_cast<std::uint64_t>(r.map_points);
  x.kfs = static_cast<std::uint64_t>(r.keyframes);
  x.observations = static_cast<std::uint64_t>(r.local_ba_observations);
  x.ba_s = r.local_ba_seconds;
  x.ba_cpu_s = r.local_ba_cpu_seconds;
  x.refine_cpu_s = r.refine_cpu_seconds;
  x.total_s = r.total_seconds;
  x.ate_m = r.ate_m;
  x.ate_r_deg = r.ate_r_deg;
  x.frames = r.frames;
  x.frames_tracked = r.frames_tracked;
  x.selector = r.selector;
  return x;
}

void log_run(const RealSequence& s, const RunRecord& r, const RealRunResult& x) {
  std::fprintf(stderr,
               "  %s seed %llu %s M=%lld: tracked %d/%d (losses %d) mps %d kfs %d (made %d) culled %lld deleted %lld "
               "excluded matched %lld rule violations %lld culled outside the keyframe %lld (windows %llu, refused %d) "
               "kept %.1f%% (of evaluated, map %.1f%%) floor kfs %llu promoted %llu "
               "short %llu, auto scope newest %llu (switches %llu), ate %.4f m, "
               "local BA %.2f s (%d, cpu %.2f s, %lld obs), refine cpu %.2f s, total %.1f s, "
               "BA points %lld (mean track %.2f, angle %.2f deg)\n",
               s.name.c_str(), static_cast<unsigned long long>(r.seed), r.variant.c_str(),
               static_cast<long long>(r.M), x.frames_tracked, x.frames, x.tracking_losses, x.map_points, x.keyframes,
               x.keyframes_created, static_cast<long long>(x.points_culled_by_selector),
               static_cast<long long>(x.points_deleted_deferred), static_cast<long long>(x.excluded_matches),
               static_cast<long long>(x.defer_rule_violations), static_cast<long long>(x.points_culled_elsewhere),
               static_cast<unsigned long long>(x.selector.windows), x.window_rejections, 100.0 * x.mean_kept_fraction,
               x.points_evaluated > 0
                   ? 100.0 * (1.0 - static_cast<double>(x.points_culled_by_selector) / static_cast<double>(x.points_evaluated))
                   : 100.0,
               static_cast<unsigned long long>(x.selector.floor_keyframes),
               static_cast<unsigned long long>(x.selector.floor_promoted),
               static_cast<unsigned long long>(x.selector.floor_short),
               static_cast<unsigned long long>(x.selector.decided_newest),
               static_cast<unsigned long long>(x.selector.scope_switches), x.ate_m,
               x.local_ba_seconds, x.local_bas, x.local_ba_cpu_seconds,
               static_cast<long long>(x.local_ba_observations), x.refine_cpu_seconds, x.total_seconds,
               static_cast<long long>(x.ba_points), x.ba_points > 0 ? x.ba_point_track_sum / double(x.ba_points) : 0.0,
               x.ba_points > 0 ? x.ba_point_angle_sum / double(x.ba_points) : 0.0);
}

bool load_sequence(const VoInput& in, const FrameSelection& frames, RealSequence* seq, std::string* error) {
  if (in.layout == VoLayout::kKittiImages) return load_kitti_sequence(in.dir, in.calib, in.poses, frames, seq, error);
  if (!load_rgbd_sequence(in.dir, frames, seq, error)) return false;
  if (in.layout == VoLayout::kColourOnly) drop_depth(seq);
  return true;
}

}  // namespace

bool evaluate_real_vo(const VoInput& in, const VoEvalOptions& o, std::vector<Comparison>* out, std::string* error) {
  RealSequence seq;
  if (!load_sequence(in, o.frames, &seq, error)) return false;
  std::fprintf(stderr, "keepless_eval: %s %s: %zu frames, path %.2f m, %dx%d, fx %.1f\n", seq.rgbd ? "rgbd" : "images",
               seq.name.c_str(), seq.image_files.size(), seq.path_length(), seq.camera.width, seq.camera.height,
               seq.camera.fx);
  const std::size_t first = out->size();
  for (const auto& [fraction, M] : o.ops) {
    Comparison c;
    c.info.input = in.dir;
    c.info.name = seq.name;
    c.info.kind = seq.rgbd ? "rgbd" : "images";
    c.info.group = "vo_" + c.info.kind;
    c.info.sim3 = !seq.rgbd;  // monocular: scale is not observable
    c.target_fraction = fraction;
    c.M = M;
    out->push_back(c);
  }
  RealRunResult first_original, first_ours;  // the first seed at the first operating point, for the SVGs
  for (std::size_t si = 0; si < o.seeds.size(); ++si) {
    RealVoOptions vo;
    vo.params.scope = o.policy.scope;
    vo.params.coverage_floor = o.policy.coverage_floor;
    vo.params.cost_model = o.policy.cost_model;
    vo.params.track_terms = o.policy.track_terms;
    vo.params.cost_terms = o.policy.cost_terms;
    vo.params.spatial_weight = o.policy.spatial_weight;
    vo.params.maturity_keyframes = o.policy.maturity_keyframes;
    vo.params.tracked_first = o.policy.tracked_first;
    vo.params.defer_keyframes = o.policy.defer_keyframes;
    vo.tracked_flags = o.tracked_flags;
    vo.weak_keyframe = o.weak_keyframe;
    vo.keyframe_ratio = o.keyframe_ratio;
    vo.anms_variant = o.anms_variant;
    vo.defer_fixed = o.defer_fixed;
    vo.defer_refine = o.defer_refine;
    vo.defer_alternate = o.defer_alternate;
    vo.decide_window = o.decide_window;
    vo.hashed_ids = o.hashed_ids;
    vo.keyframe_culling = o.keyframe_culling;
    vo.seed = o.seeds[si];
    vo.selector = Selector::kOriginal;
    const RealRunResult original = run_real_vo(seq, vo);
    if (!original.error.empty()) {
      *error = original.error;
      return false;
    }
    for (std::size_t p = 0; p < o.ops.size(); ++p) {
      Comparison& c = (*out)[first + p];
      c.original.push_back(record_of(original, "original", vo.seed, 0));
      if (p == 0) log_run(seq, c.original.back(), original);
      // A kept fraction is a keep budget on the points the VO decides (the
      // new keyframe's, or with decide_window the window's): exact per
      // window, no M. Deciding the window is keepless's scope window, or
      // auto's choice between the window and the new keyframe.
      const core::Scope window_scope = o.policy.scope == core::Scope::kAuto ? core::Scope::kAuto : core::Scope::kWindow;
      if (std::isfinite(c.target_fraction)) {
        vo.params.budget = o.policy.budget;  // its track share
        vo.params.budget.kind = core::BudgetKind::kFraction;
        vo.params.budget.fraction = c.target_fraction;
        vo.params.scope = o.decide_window ? window_scope : core::Scope::kNewest;
      } else {
        vo.params.budget = core::KeepBudget{};
        vo.params.scope = o.decide_window ? window_scope : o.policy.scope;
        vo.params.pair_capacity = c.M;
      }
      const std::pair<Selector, std::vector<RunRecord>*> runs[] = {
          {Selector::kKeepless, &c.ours}, {Selector::kRandom, &c.random},
          {Selector::kLongestTrack, &c.longest_track}, {Selector::kAnms, &c.anms}};
      for (const auto& [selector, into] : runs) {
        if (selector != Selector::kKeepless &&
            std::find(o.baselines.begin(), o.baselines.end(), selector) == o.baselines.end()) {
          continue;
        }
        vo.selector = selector;
        const RealRunResult r = run_real_vo(seq, vo);
        into->push_back(record_of(r, selector == Selector::kKeepless ? "ours" : to_string(selector), vo.seed, c.M));
        log_run(seq, into->back(), r);
        if (si == 0 && p == 0 && selector == Selector::kKeepless) first_ours = r;
      }
    }
    if (si == 0) first_original = original;
  }
  if (!o.out.empty() && !o.ops.empty() && !o.seeds.empty()) {
    std::filesystem::create_directories(o.out);
    const std::string base = o.out + "/" + seq.name;
    const Comparison& c0 = (*out)[first];
    const std::string M = std::isfinite(c0.target_fraction) ? "F " + std::to_string(c0.target_fraction).substr(0, 4)
                                                            : "M " + std::to_string(c0.M);
    if (!write_trajectory_svg(base + "_trajectory.svg", seq.name + ", seed " + std::to_string(o.seeds[0]) + ", " + M,
                              first_original, first_ours) ||
        !write_keypoints_svg(base + "_keypoints.svg", seq.name + " keepless " + M, first_ours, seq.camera.width,
                             seq.camera.height)) {
      *error = "cannot write " + base + "_*.svg";
      return false;
    }
  }
  return true;
}

bool measure_real_windows(const VoInput& in, const FrameSelection& frames, std::uint64_t seed,
                          const core::Capacities& replay, std::string* name, WindowSizes* sizes, std::string* error) {
  RealSequence seq;
  if (!load_sequence(in, frames, &seq, error)) return false;
  RealVoOptions vo;
  vo.seed = seed;
  vo.selector = Selector::kOriginal;
  vo.measure_windows = true;
  vo.replay_capacities = replay;
  const RealRunResult r = run_real_vo(seq, vo);
  if (!r.error.empty()) {
    *error = r.error;
    return false;
  }
  std::fprintf(stderr, "  %s seed %llu original: %zu frames, tracked %d, kfs made %d, local-mapping steps %llu, %.1f s\n",
               seq.name.c_str(), static_cast<unsigned long long>(seed), seq.image_files.size(), r.frames_tracked,
               r.keyframes_created, static_cast<unsigned long long>(r.window_sizes.steps), r.total_seconds);
  *name = seq.name;
  *sizes = r.window_sizes;
  return true;
}

}  // namespace keepless::eval::vo
