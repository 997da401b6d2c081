# Install rules: the public headers, the libraries, the `brittle` CLI and a CMake package, so that
# find_package(brittle) works after `cmake --install`.
#
# The libraries are shared (top-level CMakeLists.txt), so their private dependencies stay out of
# the exported link interface: a consumer finds Eigen, and the loader finds the rest through the
# libraries' own DT_NEEDED entries and run paths.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(BRITTLE_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/brittle)
# Relocatable: a library finds its siblings next to itself, the CLI finds them from the bin dir.
# Dependencies outside the system directories keep their link directories, as in the build tree.
file(RELATIVE_PATH brittleLibFromBin /${CMAKE_INSTALL_BINDIR} /${CMAKE_INSTALL_LIBDIR})

# core is header-only (an INTERFACE target): its headers and its export entry, no library file.
set_target_properties(brittle_core PROPERTIES EXPORT_NAME core)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/core/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set(brittleInstalledTargets brittle_core)
foreach(module descriptors database runtime precompute)
  set_target_properties(brittle_${module} PROPERTIES EXPORT_NAME ${module}
    INSTALL_RPATH "$ORIGIN" INSTALL_RPATH_USE_LINK_PATH ON)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${module}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  list(APPEND brittleInstalledTargets brittle_${module})
endforeach()
if(TARGET brittle)
  set_target_properties(brittle PROPERTIES EXPORT_NAME cli
    INSTALL_RPATH "$ORIGIN/${brittleLibFromBin}" INSTALL_RPATH_USE_LINK_PATH ON)
  list(APPEND brittleInstalledTargets brittle)
endif()
install(TARGETS ${brittleInstalledTargets} EXPORT brittleTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT brittleTargets NAMESPACE brittle:: DESTINATION ${BRITTLE_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/brittleConfig.cmake.in
  ${PROJECT_BINARY_DIR}/brittleConfig.cmake INSTALL_DESTINATION ${BRITTLE_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/brittleConfigVersion.cmake
  COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/brittleConfig.cmake ${PROJECT_BINARY_DIR}/brittleConfigVersion.cmake
  DESTINATION ${BRITTLE_INSTALL_CMAKEDIR})

install(FILES ${PROJECT_SOURCE_DIR}/database/PACK_SCHEMA.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
