# A policy keepless_node refuses (--use offline's track share without a
# count) is refused at once with exit 2 and a reason, not replayed with every
# decision failing.
execute_process(COMMAND ${BIN} --use offline --keyframes 5 RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err TIMEOUT 120)
if(NOT rc EQUAL 2)
  message(FATAL_ERROR "--use offline without a count: exit ${rc}, expected 2\n${err}")
endif()
if(NOT err MATCHES "--keep-points or --keep-fraction")
  message(FATAL_ERROR "--use offline without a count: no reason on stderr\n${err}")
endif()
if(err MATCHES "keyframe 0")
  message(FATAL_ERROR "--use offline without a count: the replay ran\n${err}")
endif()
