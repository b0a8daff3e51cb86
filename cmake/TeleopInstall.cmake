# Installation (GNUInstallDirs), the exported CMake package (find_package(teleop): teleop::idl,
# teleop::common, teleop::sim, teleop::world_harness, teleop::master and, with the tools,
# teleop::recording) and the Debian package (cpack -G DEB). Included by the top-level
# CMakeLists.txt after the targets.
include(CMakePackageConfigHelpers)

set(TELEOP_INSTALL_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/teleop)
set(TELEOP_INSTALL_DATA_DIR ${CMAKE_INSTALL_DATADIR}/teleop)

# --- libraries: teleop_<name> is exported as teleop::<name>, like its alias in the build tree
set(teleop_libraries teleop_idl teleop_common teleop_sim teleop_world_harness teleop_master)
if(TARGET teleop_recording)
  list(APPEND teleop_libraries teleop_recording)
endif()
foreach(lib ${teleop_libraries})
  string(REGEX REPLACE "^teleop_" "" export_name ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${export_name})
endforeach()
if(TELEOP_EIGEN_NO_MALLOC)
  # a consumer's Eigen is configured as the libraries' was
  target_compile_definitions(teleop_common INTERFACE
    $<INSTALL_INTERFACE:EIGEN_RUNTIME_NO_MALLOC>)
endif()
install(TARGETS ${teleop_libraries} EXPORT teleopTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  INCLUDES DESTINATION ${TELEOP_INSTALL_INCLUDE_DIR})

# --- headers, as the sources include them ("common/util/version.hpp", "teleop/idl/Teleop.h")
foreach(dir common server client idl)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${TELEOP_INSTALL_INCLUDE_DIR}/${dir}
    COMPONENT dev FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h"
    PATTERN "apps" EXCLUDE PATTERN "experiments" EXCLUDE)
endforeach()
install(DIRECTORY ${PROJECT_BINARY_DIR}/idl/gen/teleop/idl/
  DESTINATION ${TELEOP_INSTALL_INCLUDE_DIR}/teleop/idl COMPONENT dev FILES_MATCHING PATTERN "*.h")

# --- programs: the session's always, the viewer and the tools when they are built
set(teleop_programs teleop_server teleop_master_app)
foreach(prog teleop_viewer teleop_record teleop_play teleop_monitor teleop_bridge teleop_campaign
    teleop_experiment)
  if(TARGET ${prog})
    list(APPEND teleop_programs ${prog})
  endif()
endforeach()
install(TARGETS ${teleop_programs} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)

# --- data: found by common/util/data_dir.hpp in <prefix>/share/teleop
install(DIRECTORY ${PROJECT_SOURCE_DIR}/deploy/scenes ${PROJECT_SOURCE_DIR}/deploy/profiles
  ${PROJECT_SOURCE_DIR}/deploy/data DESTINATION ${TELEOP_INSTALL_DATA_DIR} COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/tests/charts/ DESTINATION ${TELEOP_INSTALL_DATA_DIR}/charts
  COMPONENT runtime FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/tests/reference/
  DESTINATION ${TELEOP_INSTALL_DATA_DIR}/reference COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/README.md
  ${PROJECT_SOURCE_DIR}/CHANGELOG.md DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)

# --- the CMake package: teleopConfig.cmake finds the dependencies, then the targets
set(TELEOP_CONFIG_HAVE_EVDEV OFF)
if(LIBEVDEV_FOUND)
  set(TELEOP_CONFIG_HAVE_EVDEV ON)
endif()
set(TELEOP_CONFIG_HAVE_RECORDING OFF)
if(TARGET teleop_recording)
  set(TELEOP_CONFIG_HAVE_RECORDING ON)
endif()
install(EXPORT teleopTargets NAMESPACE teleop:: DESTINATION ${TELEOP_INSTALL_CMAKE_DIR}
  COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/teleopConfig.cmake.in
  ${PROJECT_BINARY_DIR}/teleopConfig.cmake INSTALL_DESTINATION ${TELEOP_INSTALL_CMAKE_DIR}
  PATH_VARS TELEOP_INSTALL_DATA_DIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/teleopConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/teleopConfig.cmake ${PROJECT_BINARY_DIR}/teleopConfigVersion.cmake
  DESTINATION ${TELEOP_INSTALL_CMAKE_DIR} COMPONENT dev)

# --- the Debian package: `cpack -G DEB` in the build folder (one package, programs and libraries)
set(CPACK_PACKAGE_NAME teleop)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "Networked haptic teleoperation of deformable objects (server, master, observers; Fast DDS)")
set(CPACK_PACKAGE_CONTACT "teleop maintainers <teleop-maintainers@localhost>")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_LICENSE "Apache-2.0")
# the shared libraries the programs load, found by dpkg-shlibdeps (dpkg-dev)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# programs and static libraries without their debug information (the build tree keeps it)
set(CPACK_STRIP_FILES ON)
# the charts of the programs' --out folders; the headers the libraries' users compile against
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
  "libeigen3-dev, libfastrtps-dev, libfastcdr-dev, libode-dev, libassimp-dev, libyaml-cpp-dev, libssl-dev, pkg-config")
include(CPack)
