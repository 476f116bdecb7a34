# The .lcm files also generate Java (for LCM's Java tools, lcm-spy), and the
# Java must compile against lcm.jar (javac: default-jdk-headless; lcm.jar:
# liblcm-java; a missing one fails the check).
#   cmake -DLCM_GEN=... -DJAVAC=... -DLCM_JAR=... -DOUT=... -DSOURCES="a.lcm;b.lcm" -P lcm_java_check.cmake
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${LCM_GEN} --java --jpath ${OUT} ${SOURCES} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "lcm-gen --java failed (${rc}): ${err}")
endif()
file(GLOB_RECURSE java_files ${OUT}/*.java)
list(LENGTH java_files n)
list(LENGTH SOURCES expected)
if(NOT n EQUAL expected)
  message(FATAL_ERROR "lcm-gen --java wrote ${n} files for ${expected} types")
endif()
if(JAVAC AND EXISTS "${LCM_JAR}")
  execute_process(COMMAND ${JAVAC} -nowarn -cp ${LCM_JAR} -d ${OUT}/classes ${java_files}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "javac failed (${rc}):\n${out}${err}")
  endif()
  message(STATUS "compiled ${n} Java message classes against ${LCM_JAR}")
else()
  message(FATAL_ERROR "generated ${n} Java files but cannot compile them: javac '${JAVAC}' (default-jdk-headless) "
                      "or lcm.jar '${LCM_JAR}' (liblcm-java) is missing")
endif()
