# cmake --install BUILD [--prefix DIR]: headers, the static library microsim::microsim (with
# microsimConfig.cmake and its version file for find_package), the program, its image-reader
# module in lib/microsim (found from the program's folder, src/io/oiio_module.cpp) and the Python
# package (python/CMakeLists.txt).
include(CMakePackageConfigHelpers)
set(MICROSIM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/microsim)
install(TARGETS microsim_lib EXPORT microsimTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/microsim DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS microsim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS microsim_oiio_reader LIBRARY DESTINATION ${MICROSIM_PLUGIN_INSTALL_DIR})
# A project linking the installed library runs from its own folder: the module's folder goes into
# its RUNPATH, which dlopen searches for the module's bare name (the prefix as the exported targets
# find it, so a moved install tree still works).
target_link_options(microsim_lib INTERFACE
  "$<INSTALL_INTERFACE:LINKER:-rpath,$<INSTALL_PREFIX>/${MICROSIM_PLUGIN_INSTALL_DIR}>")
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

# The install tree alone (tests/install_tree.sh): program, package and Python module from a
# temporary prefix, with the build tree's image-reader module hidden. RUN_SERIAL: while it is
# hidden the build tree's programs cannot read images.
if(MICROSIM_TESTS)
  set(python_install_dir "")
  if(TARGET microsim_python)
    set(python_install_dir ${MICROSIM_PYTHON_INSTALL_DIR})
  endif()
  add_test(NAME install_tree
           COMMAND bash ${CMAKE_SOURCE_DIR}/tests/install_tree.sh ${CMAKE_BINARY_DIR}
                   $<TARGET_FILE:microsim_oiio_reader> ${CMAKE_SOURCE_DIR} ${CMAKE_BINARY_DIR}/install_tree ${Python3_EXECUTABLE}
                   "${python_install_dir}" ${CMAKE_CXX_COMPILER} "${CMAKE_CXX_COMPILER_LAUNCHER}")
  set_tests_properties(install_tree PROPERTIES TIMEOUT 600 RUN_SERIAL ON LABELS python)
endif()
