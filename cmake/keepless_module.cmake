# keepless_module(<name> SOURCES ... [DEPS ...]): library keepless_<name>,
# alias keepless::<name>, headers under <name>/include/keepless/<name>/.
function(keepless_module name)
  cmake_parse_arguments(M "" "" "SOURCES;DEPS" ${ARGN})
  add_library(keepless_${name} ${M_SOURCES})
  add_library(keepless::${name} ALIAS keepless_${name})
  set_target_properties(keepless_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME keepless_${name})
  target_include_directories(keepless_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(keepless_${name} PUBLIC ${M_DEPS} PRIVATE keepless_options)
  install(TARGETS keepless_${name} EXPORT keeplessTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
