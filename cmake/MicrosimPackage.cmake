# cmake --install BUILD [--prefix DIR]: headers, the static library microsim::microsim (with
# microsimConfig.cmake and its version file for find_package), the program and its image reader
# module (looked up next to the program).
include(CMakePackageConfigHelpers)
set(MICROSIM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/microsim)
install(TARGETS microsim_lib EXPORT microsimTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/microsim DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS microsim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS microsim_oiio_reader LIBRARY DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT microsimTargets NAMESPACE microsim:: DESTINATION ${MICROSIM_CMAKE_DIR})
configure_package_config_file(cmake/microsimConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/microsimConfig.cmake
                              INSTALL_DESTINATION ${MICROSIM_CMAKE_DIR})
# 0.x: a minor version may change the interface.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/microsimConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/microsimConfig.cmake ${CMAKE_BINARY_DIR}/microsimConfigVersion.cmake
        DESTINATION ${MICROSIM_CMAKE_DIR})

# An outside project built against an install tree in the build folder, then run.
if(MICROSIM_TESTS)
  add_test(NAME package_consumer
           COMMAND ${CMAKE_COMMAND}
                   -DBUILD_DIR=${CMAKE_BINARY_DIR}
                   -DSOURCE_DIR=${CMAKE_SOURCE_DIR}/tests/package_consumer
                   -DWORK_DIR=${CMAKE_BINARY_DIR}/package_consumer
                   -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
                   -DLAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER}
                   -P ${CMAKE_SOURCE_DIR}/tests/package_consumer/run.cmake)
  set_tests_properties(package_consumer PROPERTIES TIMEOUT 300)
endif()
