# Runs keepless_latency on the small workload and checks its last stdout line
# (a JSON object): every documented key is present, identical_decisions is
# true and allocations_after_warmup is 0. Timings are not asserted.
execute_process(
  COMMAND ${BIN} --workload small --keyframes 40 --compare 3 --reps 1 --budget-ms 0
  OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "keepless_latency exited with ${rc}\n${out}\n${err}")
endif()
string(STRIP "${out}" out)
string(REGEX REPLACE ".*\n" "" last "${out}")
foreach(key workload decisions e2e_p50_ms e2e_p99_ms e2e_max_ms budget_exhausted
            allocations_after_warmup footprint_bytes ours_scratch_median_ms incremental_median_ms
            lemon_ns_median_ms lemon_cs_median_ms closed_form_median_ms ours_zero_flow_median_ms
            slide_zero_flow_median_ms identical_decisions)
  string(JSON value ERROR_VARIABLE missing GET "${last}" ${key})
  if(missing)
    message(FATAL_ERROR "key ${key} missing from: ${last}")
  endif()
endforeach()
string(JSON identical GET "${last}" identical_decisions)
string(JSON allocations GET "${last}" allocations_after_warmup)
string(JSON decisions GET "${last}" decisions)
string(JSON workload GET "${last}" workload)
if(NOT identical STREQUAL "ON" AND NOT identical STREQUAL "true")
  message(FATAL_ERROR "identical_decisions is ${identical}: ${last}")
endif()
if(NOT allocations EQUAL 0)
  message(FATAL_ERROR "allocations_after_warmup is ${allocations}: ${last}")
endif()
if(NOT decisions EQUAL 40 OR NOT workload STREQUAL "small")
  message(FATAL_ERROR "unexpected run: ${last}")
endif()
