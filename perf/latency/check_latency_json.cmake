# Runs keepless_latency on the small workload and checks its last stdout line
# (a JSON object): every documented key is present, identical_decisions is
# true and allocations_after_warmup is 0 (the A/A replay's too, with the
# reference's decisions), the run was pinned to CPUs 0 and 1
# (the perf rule: two cores) and LEMON, the reference, was timed. Timings are
# not asserted.
#
# With -DKEEP=F it also runs --keep-fraction F, alone, with each --use and with
# --track-share (see below).
#
# With -DCOST=authors|information (optionally -DFLOOR=L) it also runs that
# cost model and checks the policy's keys: the stream carried what the model
# reads, the in-process paper reference decided exactly what the plain paper
# run decided (the extras change nothing for it), the model decided
# differently (it used them), and neither replay allocated.
#
# With -DLCM=ON it also runs --lcm with --cost authors: keepless_node (beside
# the tool) must answer every keyframe the stream publishes over loopback UDP,
# none lost: it is sized for the unmapped keypoints the keyframes carry.
cmake_minimum_required(VERSION 3.20)  # quoted if() arguments are strings (CMP0054)

function(run_latency last_var)
  execute_process(
    COMMAND ${BIN} --workload small --keyframes 40 --compare 3 --reps 1 --budget-ms 0 --cpus 0,1 ${ARGN}
    OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "keepless_latency ${ARGN} exited with ${rc}\n${out}\n${err}")
  endif()
  string(STRIP "${out}" out)
  string(REGEX REPLACE ".*\n" "" last "${out}")
  foreach(key workload decisions pinned mlock mlock_ok e2e_p50_ms e2e_p99_ms e2e_max_ms budget_exhausted
              allocations_after_warmup footprint_bytes ours_scratch_median_ms ours_scratch_solve_median_ms
              incremental_median_ms scratch_over_incremental
              lemon_ns_median_ms lemon_cs_median_ms closed_form_median_ms ours_zero_flow_median_ms
              slide_zero_flow_median_ms identical_decisions
              use scope maturity_keyframes defer_keyframes track_share track_share_from track_share_to coverage_floor cost_model intrinsics_and_depths unmapped_per_kf floor_bound_decisions
              floor_promoted out_of_scope_mean decisions_digest reference reference_e2e_p50_ms
              reference_e2e_p99_ms reference_allocations_after_warmup reference_decisions_digest
              p50_ratio_to_paper p99_ratio_to_paper profile profile_fits node_memory_predicted_bytes
              node_memory_bytes peak_rss_bytes aa_e2e_p50_ms aa_e2e_p99_ms aa_p50_ratio aa_p99_ratio
              aa_allocations_after_warmup aa_decisions_digest aa_cpu_p99_ratio e2e_cpu_p50_ms e2e_cpu_p99_ms
              reference_e2e_cpu_p50_ms reference_e2e_cpu_p99_ms cpu_p50_ratio_to_paper cpu_p99_ratio_to_paper
              keep_budget keep_budget_value keep_budget_share_p50 keep_budget_share_p99 node_rss_growth_bytes
              lcm_lost)
    string(JSON value ERROR_VARIABLE missing GET "${last}" ${key})
    if(missing)
      message(FATAL_ERROR "key ${key} missing from: ${last}")
    endif()
  endforeach()
  string(JSON identical GET "${last}" identical_decisions)
  string(JSON allocations GET "${last}" allocations_after_warmup)
  string(JSON ref_allocations GET "${last}" reference_allocations_after_warmup)
  string(JSON decisions GET "${last}" decisions)
  string(JSON workload GET "${last}" workload)
  string(JSON exhausted GET "${last}" budget_exhausted)
  if(NOT identical STREQUAL "ON" AND NOT identical STREQUAL "true")
    message(FATAL_ERROR "identical_decisions is ${identical}: ${last}")
  endif()
  if(NOT allocations EQUAL 0 OR NOT ref_allocations EQUAL 0)
    message(FATAL_ERROR "allocations after warm-up ${allocations} (reference ${ref_allocations}): ${last}")
  endif()
  # The A/A control replays the reference's policy again: the same decisions
  # (no budget runs out under --budget-ms 0), nothing allocated.
  string(JSON aa_digest GET "${last}" aa_decisions_digest)
  string(JSON aa_allocations GET "${last}" aa_allocations_after_warmup)
  string(JSON ref_digest GET "${last}" reference_decisions_digest)
  if(NOT aa_digest STREQUAL ref_digest OR NOT aa_allocations EQUAL 0)
    message(FATAL_ERROR "A/A replay: digest ${aa_digest} against the reference's ${ref_digest}, allocations ${aa_allocations}: ${last}")
  endif()
  if(NOT decisions EQUAL 40 OR NOT workload STREQUAL "small" OR NOT exhausted EQUAL 0)
    message(FATAL_ERROR "unexpected run: ${last}")
  endif()
  string(JSON cpus GET "${last}" cpus)
  string(JSON pinned GET "${last}" pinned)
  string(JSON lemon GET "${last}" lemon_ns_median_ms)
  if(NOT cpus STREQUAL "0,1" OR NOT pinned OR NOT lemon GREATER 0)
    message(FATAL_ERROR "expected a run pinned to CPUs 0,1 with LEMON timed: ${last}")
  endif()
  set(${last_var} "${last}" PARENT_SCOPE)
endfunction()

run_latency(paper_json)
# A count beyond the tool's range is refused (usage error), not replaced by another.
if(NOT DEFINED KEEP AND NOT DEFINED COST AND NOT LCM)
  execute_process(COMMAND ${BIN} --workload small --keyframes 4294967296 --compare 0
                  OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
  if(NOT rc EQUAL 2)
    message(FATAL_ERROR "--keyframes 4294967296 exited with ${rc} (expected 2, a usage error)\n${err}")
  endif()
endif()
string(JSON reference GET "${paper_json}" reference)
string(JSON paper_digest GET "${paper_json}" decisions_digest)
string(JSON paper_model GET "${paper_json}" cost_model)
if(NOT reference STREQUAL "self" OR NOT paper_model STREQUAL "paper")
  message(FATAL_ERROR "the default run is its own paper reference: ${paper_json}")
endif()
# -DKEEP=F: a kept fraction (its memory of earlier decisions must be the
# checks' too), against the in-process paper reference.
if(DEFINED KEEP)
  run_latency(keep_json --keep-fraction ${KEEP})
  string(JSON budget GET "${keep_json}" keep_budget)
  string(JSON reference GET "${keep_json}" reference)
  string(JSON digest GET "${keep_json}" decisions_digest)
  string(JSON reference_digest GET "${keep_json}" reference_decisions_digest)
  if(NOT budget STREQUAL "fraction" OR NOT reference STREQUAL "paper")
    message(FATAL_ERROR "expected a fraction budget against the paper reference: ${keep_json}")
  endif()
  if(NOT reference_digest STREQUAL paper_digest OR digest STREQUAL paper_digest)
    message(FATAL_ERROR "the reference must decide as the paper run, the budget otherwise: ${keep_json}")
  endif()
  # The uses (keepless_node's --use) with that fraction: the fields each sets,
  # checked like the rest; monocular and offline decide otherwise than the
  # plain fraction, monocular-deferred as the fraction with --scope auto (its
  # deferral is the node's; its track share stops at 0.15, below KEEP = 0.3).
  run_latency(auto_json --scope auto --keep-fraction ${KEEP})
  string(JSON auto_digest GET "${auto_json}" decisions_digest)
  foreach(use_expect "monocular;newest;2;0;0.5;0.3;1" "offline;window;0;0;1;0;1" "monocular-deferred;auto;0;2;0.5;0;0.15")
    list(GET use_expect 0 use)
    run_latency(use_json --use ${use} --keep-fraction ${KEEP})
    set(i 0)
    foreach(key use scope maturity_keyframes defer_keyframes track_share track_share_from track_share_to)
      string(JSON value GET "${use_json}" ${key})
      list(GET use_expect ${i} expected)
      math(EXPR i "${i} + 1")
      if(NOT value STREQUAL expected AND NOT value EQUAL expected)  # EQUAL: numbers, as doubles
        message(FATAL_ERROR "--use ${use}: ${key} is ${value}, expected ${expected}: ${use_json}")
      endif()
    endforeach()
    string(JSON use_digest GET "${use_json}" decisions_digest)
    string(JSON reference_digest GET "${use_json}" reference_decisions_digest)
    if(NOT reference_digest STREQUAL paper_digest)
      message(FATAL_ERROR "--use ${use}: the reference decided otherwise than the paper run: ${use_json}")
    endif()
    if(use STREQUAL "monocular-deferred")
      if(NOT use_digest STREQUAL auto_digest)
        message(FATAL_ERROR "--use ${use} decided ${use_digest}, the fraction with --scope auto ${auto_digest}: ${use_json}")
      endif()
    elseif(use_digest STREQUAL digest)
      message(FATAL_ERROR "--use ${use} decided as the plain fraction (${digest}): ${use_json}")
    endif()
  endforeach()
  # A given --track-share applies at every budget (the use's bound reset), so
  # at KEEP it changes what monocular-deferred decides.
  run_latency(share_json --use monocular-deferred --keep-fraction ${KEEP} --track-share 0.5)
  foreach(key_expect "track_share;0.5" "track_share_from;0" "track_share_to;1")
    list(GET key_expect 0 key)
    list(GET key_expect 1 expected)
    string(JSON value GET "${share_json}" ${key})
    if(NOT value EQUAL expected)
      message(FATAL_ERROR "--track-share 0.5: ${key} is ${value}, expected ${expected}: ${share_json}")
    endif()
  endforeach()
  string(JSON share_digest GET "${share_json}" decisions_digest)
  if(share_digest STREQUAL auto_digest)
    message(FATAL_ERROR "--track-share 0.5 decided as the use without it (${auto_digest}): ${share_json}")
  endif()
endif()
if(LCM)
  run_latency(lcm_json --lcm --cost authors)
  string(JSON lcm_decisions GET "${lcm_json}" lcm_decisions)
  string(JSON lcm_lost GET "${lcm_json}" lcm_lost)
  string(JSON unmapped GET "${lcm_json}" unmapped_per_kf)
  if(NOT lcm_decisions EQUAL 40 OR NOT lcm_lost EQUAL 0 OR NOT unmapped EQUAL 300)
    message(FATAL_ERROR "--lcm: expected 40 decisions from keepless_node, none lost, with 300 unmapped "
                        "keypoints a keyframe: ${lcm_json}")
  endif()

endif()
if(NOT DEFINED COST)
  return()
endif()

set(args --cost ${COST})
if(DEFINED FLOOR)
  list(APPEND args --floor ${FLOOR})
endif()
run_latency(policy_json ${args})
string(JSON model GET "${policy_json}" cost_model)
string(JSON reference GET "${policy_json}" reference)
string(JSON floor GET "${policy_json}" coverage_floor)
string(JSON camera GET "${policy_json}" intrinsics_and_depths)
string(JSON unmapped GET "${policy_json}" unmapped_per_kf)
string(JSON digest GET "${policy_json}" decisions_digest)
string(JSON reference_digest GET "${policy_json}" reference_decisions_digest)
if(NOT model STREQUAL COST OR NOT reference STREQUAL "paper")
  message(FATAL_ERROR "expected cost_model ${COST} against the paper reference: ${policy_json}")
endif()
if(DEFINED FLOOR AND NOT floor EQUAL FLOOR)
  message(FATAL_ERROR "coverage_floor is ${floor}, not ${FLOOR}: ${policy_json}")
endif()
# What each model reads: information the intrinsics and depths, authors the
# unmapped keypoints (half the small workload's 600 observations a keyframe).
if(COST STREQUAL "information" AND NOT (camera STREQUAL "ON" OR camera STREQUAL "true"))
  message(FATAL_ERROR "--cost information ran without intrinsics and depths: ${policy_json}")
endif()
if(COST STREQUAL "authors" AND NOT unmapped EQUAL 300)
  message(FATAL_ERROR "--cost authors ran with ${unmapped} unmapped keypoints a keyframe: ${policy_json}")
endif()
if(NOT reference_digest STREQUAL paper_digest)
  message(FATAL_ERROR "the paper's decisions changed with the ${COST} extras in the stream: "
                      "${reference_digest} vs ${paper_digest}")
endif()
if(digest STREQUAL paper_digest)
  message(FATAL_ERROR "--cost ${COST} decided exactly as the paper model on every window: ${policy_json}")
endif()
