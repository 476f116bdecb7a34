include(CMakePackageConfigHelpers)
# The OpenCV adapter is an optional component with its own targets file, so
# that a consumer of the rest needs neither OpenCV nor Eigen.
if(TARGET keepless::opencv)
  set(KEEPLESS_PACKAGE_HAS_OPENCV TRUE)
  install(EXPORT keeplessOpencvTargets NAMESPACE keepless:: FILE keeplessOpencvTargets.cmake
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
else()
  set(KEEPLESS_PACKAGE_HAS_OPENCV FALSE)
endif()
# Likewise the LCM messages and the node's library: their own targets file,
# loaded only where the consumer's machine has LCM.
if(TARGET keepless::lcm_types)
  set(KEEPLESS_PACKAGE_HAS_LCM TRUE)
  install(EXPORT keeplessLcmTargets NAMESPACE keepless:: FILE keeplessLcmTargets.cmake
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
else()
  set(KEEPLESS_PACKAGE_HAS_LCM FALSE)
endif()
install(EXPORT keeplessTargets NAMESPACE keepless:: FILE keeplessTargets.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/keeplessConfig.cmake.in
  ${PROJECT_BINARY_DIR}/keeplessConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/keeplessConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/keeplessConfig.cmake ${PROJECT_BINARY_DIR}/keeplessConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
