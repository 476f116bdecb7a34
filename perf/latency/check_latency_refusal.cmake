# A policy keepless_node refuses (a track share without a count: --use
# offline's, or one given with --track-share) is refused at once with exit 2
# and a reason naming the flag, not replayed with every decision failing.
foreach(case "--use;offline;--use offline" "--track-share;0.5;--track-share")
  list(GET case 0 flag)
  list(GET case 1 value)
  list(GET case 2 named)
  execute_process(COMMAND ${BIN} ${flag} ${value} --keyframes 5 RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err TIMEOUT 120)
  if(NOT rc EQUAL 2)
    message(FATAL_ERROR "${flag} ${value} without a count: exit ${rc}, expected 2\n${err}")
  endif()
  if(NOT err MATCHES "${named} takes a share of a count: give --keep-points or --keep-fraction")
    message(FATAL_ERROR "${flag} ${value} without a count: no reason naming ${named} on stderr\n${err}")
  endif()
  if(err MATCHES "keyframe 0")
    message(FATAL_ERROR "${flag} ${value} without a count: the replay ran\n${err}")
  endif()
endforeach()
