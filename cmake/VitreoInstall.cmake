# `cmake --install`: the rig as installed software, in the GNU layout (GNUInstallDirs) under
# CMAKE_INSTALL_PREFIX — README "Installing the rig", rig/system/README.md.
#
#   bin/                          vitreo, vitreo-cmd, vitreo-report, vitreo-cases, vitreo-devices, vitreo-calibrate
#   share/vitreo/scenes/          the cases, their materials library and surgical scripts (scripts/)
#   share/vitreo/config/          example rig files (and the simulated devices' scripts, sim/)
#   share/doc/vitreo/             README.md and the documents it refers to (rig/system/README.md: the service)
#   lib/systemd/system/           vitreo.service
#   lib/sysusers.d/vitreo.conf    the user and group vitreo
#   lib/tmpfiles.d/vitreo.conf    /etc/vitreo/rig.toml from the installed example, when there is none
#   lib/udev/rules.d/70-vitreo.rules  /dev/vitreo/* names and group access for the rig's devices
#
# The installed executables find share/vitreo from their own path (rig/files/data_dir.hpp), so the
# tree can be staged with DESTDIR or moved. The unit, the tmpfiles line and the rig file's place
# name absolute paths, fixed when the build is configured: choose the prefix then
# (-DCMAKE_INSTALL_PREFIX=/usr puts the rig file in /etc/vitreo), not with `cmake --install --prefix`.
include(GNUInstallDirs)

# systemd and udev look under PREFIX/lib (not the multiarch LIBDIR) for /usr and /usr/local alike.
set(VITREO_SYSTEMD_UNIT_DIR "lib/systemd/system" CACHE STRING "systemd system units, relative to the prefix")
set(VITREO_SYSUSERS_DIR "lib/sysusers.d" CACHE STRING "sysusers.d snippets, relative to the prefix")
set(VITREO_TMPFILES_DIR "lib/tmpfiles.d" CACHE STRING "tmpfiles.d snippets, relative to the prefix")
set(VITREO_UDEV_RULES_DIR "lib/udev/rules.d" CACHE STRING "udev rules, relative to the prefix")

set(VITREO_DATA_DIR ${CMAKE_INSTALL_DATADIR}/vitreo)  # rig/files/CMakeLists.txt finds it from bin/
set(VITREO_INSTALL_FULL_BINDIR ${CMAKE_INSTALL_FULL_BINDIR})
set(VITREO_INSTALL_FULL_DATADIR ${CMAKE_INSTALL_FULL_DATADIR}/vitreo)
set(VITREO_INSTALL_FULL_DOCDIR ${CMAKE_INSTALL_FULL_DOCDIR})
set(VITREO_INSTALL_FULL_SYSCONFDIR ${CMAKE_INSTALL_FULL_SYSCONFDIR})
set(VITREO_RIG_FILE ${CMAKE_INSTALL_FULL_SYSCONFDIR}/vitreo/rig.toml)

install(TARGETS vitreo vitreo-cmd vitreo-report vitreo-cases vitreo-devices vitreo-calibrate
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

install(DIRECTORY ${PROJECT_SOURCE_DIR}/scenes/ DESTINATION ${VITREO_DATA_DIR}/scenes
        FILES_MATCHING PATTERN "*.toml" PATTERN "*.md")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/rig/config/ DESTINATION ${VITREO_DATA_DIR}/config
        FILES_MATCHING PATTERN "*.toml" PATTERN "*.sim")

# README.md and the documents it points users to, at the same relative paths (the cases' own
# READMEs are beside them in share/vitreo/scenes/).
foreach(doc README.md firmware-protocol/PROTOCOL.md drivers/README.md core/README.md core/metrics/README.md
            rig/calibration/README.md rig/report/README.md rig/runtime/README.md rig/system/README.md
            rig/telemetry/CHANNELS.md rig/telemetry/RECORDING.md)
  get_filename_component(_doc_dir ${doc} DIRECTORY)
  install(FILES ${PROJECT_SOURCE_DIR}/${doc} DESTINATION ${CMAKE_INSTALL_DOCDIR}/${_doc_dir})
endforeach()

# The rig process as a service, its user, its rig file's place, its devices' names.
configure_file(${PROJECT_SOURCE_DIR}/rig/system/vitreo.service.in ${PROJECT_BINARY_DIR}/rig/system/vitreo.service @ONLY)
configure_file(${PROJECT_SOURCE_DIR}/rig/system/vitreo.tmpfiles.conf.in ${PROJECT_BINARY_DIR}/rig/system/vitreo.tmpfiles.conf @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/rig/system/vitreo.service DESTINATION ${VITREO_SYSTEMD_UNIT_DIR})
install(FILES ${PROJECT_SOURCE_DIR}/rig/system/vitreo.sysusers.conf DESTINATION ${VITREO_SYSUSERS_DIR} RENAME vitreo.conf)
install(FILES ${PROJECT_BINARY_DIR}/rig/system/vitreo.tmpfiles.conf DESTINATION ${VITREO_TMPFILES_DIR} RENAME vitreo.conf)
install(FILES ${PROJECT_SOURCE_DIR}/rig/system/70-vitreo.rules DESTINATION ${VITREO_UDEV_RULES_DIR})
