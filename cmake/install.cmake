include(CMakePackageConfigHelpers)
# The package config looks for OpenCV only when the adapter is in it.
if(TARGET keepless::opencv)
  set(KEEPLESS_PACKAGE_HAS_OPENCV TRUE)
else()
  set(KEEPLESS_PACKAGE_HAS_OPENCV FALSE)
endif()
install(EXPORT keeplessTargets NAMESPACE keepless:: FILE keeplessTargets.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/keeplessConfig.cmake.in
  ${PROJECT_BINARY_DIR}/keeplessConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/keeplessConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/keeplessConfig.cmake ${PROJECT_BINARY_DIR}/keeplessConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/keepless)
