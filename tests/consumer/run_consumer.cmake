# cmake -P script behind the consumer_installed_package test (see CMakeLists.txt).
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${cmd}")
  endif()
endfunction()

# A fresh prefix each run, so a missing install rule cannot hide behind an
# earlier run's files.
file(REMOVE_RECURSE ${PREFIX} ${CONSUMER_BUILD})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${KEEPLESS_BUILD_DIR} --prefix ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install ${KEEPLESS_BUILD_DIR} failed: the package needs the whole tree built")
endif()

# The installed tool starts from the prefix (shared libraries: found through its RPATH).
if(NOT TOOLCHAIN)
  run(${PREFIX}/bin/keepless_sparsify --version)
endif()

set(args -S ${CONSUMER_SOURCE} -B ${CONSUMER_BUILD} -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_PREFIX_PATH=${PREFIX})
if(TOOLCHAIN)
  # Cross: the toolchain confines find_package to the sysroot; the prefix is
  # one more root to search.
  list(APPEND args -DCMAKE_TOOLCHAIN_FILE=${TOOLCHAIN} -DKEEPLESS_SYSROOT=${SYSROOT}
       -DCMAKE_FIND_ROOT_PATH=${PREFIX})
else()
  list(APPEND args -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
endif()
run(${CMAKE_COMMAND} ${args})
run(${CMAKE_COMMAND} --build ${CONSUMER_BUILD})

string(REPLACE "|" ";" emulator "${EMULATOR}")
execute_process(COMMAND ${emulator} ${CONSUMER_BUILD}/onboard_module
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "onboard_module exited with ${rc}")
endif()
if(NOT out MATCHES "onboard_module: [0-9]+ keyframes, [0-9]+ points: kept [1-9][0-9]*, culled [1-9][0-9]*")
  message(FATAL_ERROR "onboard_module printed no decision summary")
endif()
# A package with LCM must have exercised it (this machine has LCM).
if(EXISTS ${PREFIX}/include/keepless/decision_t.hpp AND NOT out MATCHES "decision_t: [0-9]+ bytes")
  message(FATAL_ERROR "onboard_module did not use keepless::lcm_types although the package has it")
endif()
# A package with the OpenCV adapter must have exercised it.
if(EXISTS ${PREFIX}/include/keepless/opencv/keyframe_adapter.hpp AND
   NOT out MATCHES "keepless::opencv: [1-9][0-9]* culled ids, the same decisions")
  message(FATAL_ERROR "onboard_module did not use keepless::opencv although the package has it")
endif()

# keepless::core needs neither OpenCV nor Eigen: with both hidden from
# find_package the package still loads (without keepless::opencv) and the
# module builds and runs on the rest.
if(NOT TOOLCHAIN)
  set(bare ${CONSUMER_BUILD}-without-opencv)
  file(REMOVE_RECURSE ${bare})
  run(${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${bare} -G ${GENERATOR} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
      -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
      -DCMAKE_DISABLE_FIND_PACKAGE_OpenCV=ON -DCMAKE_DISABLE_FIND_PACKAGE_Eigen3=ON)
  run(${CMAKE_COMMAND} --build ${bare})
  execute_process(COMMAND ${bare}/onboard_module RESULT_VARIABLE rc OUTPUT_VARIABLE out)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "kept [1-9][0-9]*, culled [1-9][0-9]*" OR out MATCHES "keepless::opencv")
    message(FATAL_ERROR "without OpenCV and Eigen the consumer did not run on keepless::core alone:\n${out}")
  endif()
endif()

# LCM in a prefix of its own: a copy of this build's LCM headers and library
# under a scratch prefix, searched first; the package must use that copy.
if(NOT TOOLCHAIN AND EXISTS ${PREFIX}/include/keepless/decision_t.hpp)
  set(lcm_prefix ${CONSUMER_BUILD}-lcm-prefix)
  set(probe ${CONSUMER_BUILD}-lcm-probe)
  file(REMOVE_RECURSE ${lcm_prefix} ${probe})
  file(COPY ${LCM_INCLUDE_DIR}/lcm DESTINATION ${lcm_prefix}/include)
  file(GLOB lcm_libs ${LCM_LIBRARY}*)
  file(COPY ${lcm_libs} DESTINATION ${lcm_prefix}/lib)
  file(GLOB_RECURSE keepless_config ${PREFIX}/keeplessConfig.cmake)
  get_filename_component(keepless_dir "${keepless_config}" DIRECTORY)
  run(${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/lcm_probe -B ${probe} -G ${GENERATOR}
      -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_PREFIX_PATH=${lcm_prefix} -Dkeepless_DIR=${keepless_dir} -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
  run(${CMAKE_COMMAND} --build ${probe})
  run(${probe}/lcm_probe)
endif()
