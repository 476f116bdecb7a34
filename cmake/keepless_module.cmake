# keepless_module(<name> SOURCES ... [DEPS ...] [HEADERS ...] [EXPORT set]):
# library keepless_<name>, alias keepless::<name>, headers under
# <name>/include/keepless/<name>/. It installs its include/ folder, or only
# HEADERS (paths under include/) where a header needs what the package may
# lack, and exports into keeplessTargets unless EXPORT names another set (an
# optional component's, loaded on its own by keeplessConfig.cmake).
function(keepless_module name)
  cmake_parse_arguments(M "" "EXPORT" "SOURCES;DEPS;HEADERS" ${ARGN})
  if(NOT M_EXPORT)
    set(M_EXPORT keeplessTargets)
  endif()
  add_library(keepless_${name} ${M_SOURCES})
  add_library(keepless::${name} ALIAS keepless_${name})
  set_target_properties(keepless_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME keepless_${name})
  target_include_directories(keepless_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # Consumers compile our headers as C++17; our warning flags stay ours.
  target_compile_features(keepless_${name} PUBLIC cxx_std_17)
  target_link_libraries(keepless_${name} PUBLIC ${M_DEPS} PRIVATE $<BUILD_INTERFACE:keepless_options>)
  install(TARGETS keepless_${name} EXPORT ${M_EXPORT}
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  if(M_HEADERS)
    foreach(header ${M_HEADERS})
      get_filename_component(dir ${header} DIRECTORY)
      install(FILES include/${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/${dir})
    endforeach()
  else()
    install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endfunction()
