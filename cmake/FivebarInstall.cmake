# `cmake --install` (issue 13): headers, the static libraries and the package config that lets
# another project write
#   find_package(fivebar REQUIRED)
#   target_link_libraries(app PRIVATE fivebar::model fivebar::identification fivebar::trajectory)
# fivebar::sim (the SUNDIALS simulator) is exported too: identification and trajectory need it.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set_target_properties(fivebar_model PROPERTIES EXPORT_NAME model)
set_target_properties(fivebar_sim PROPERTIES EXPORT_NAME sim)
set_target_properties(fivebar_identification PROPERTIES EXPORT_NAME identification)
set_target_properties(fivebar_trajectory PROPERTIES EXPORT_NAME trajectory)

install(TARGETS fivebar_model fivebar_sim fivebar_identification fivebar_trajectory
        EXPORT fivebarTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
foreach(dir model identification trajectory)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()

set(FIVEBAR_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/fivebar)
install(EXPORT fivebarTargets NAMESPACE fivebar:: DESTINATION ${FIVEBAR_INSTALL_CMAKEDIR})
# the config repeats the find_package calls the exported link interfaces need
set(FIVEBAR_CONFIG_MPI ${FIVEBAR_TRAJECTORY_MPI})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/fivebarConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/fivebarConfig.cmake
                              INSTALL_DESTINATION ${FIVEBAR_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fivebarConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fivebarConfig.cmake
              ${PROJECT_BINARY_DIR}/fivebarConfigVersion.cmake
        DESTINATION ${FIVEBAR_INSTALL_CMAKEDIR})
