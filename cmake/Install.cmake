# What `cmake --install` puts where, and the Debian packages made of it (CPack, at the end).
# Components, one package each:
#   hmc           the programs (hmc, hmc-sim, hmc-uf2), the udev rule, man pages, completions,
#                 docs and the example motion files
#   libhmc-dev    libhmc.a, its headers, the CMake package (find_package(hmc)) and hmc.pc
#   hmc-desk      the desktop panel, when it is built
#   hmc-emu       the board emulator and its bootloader (they need Unicorn, which hmc does not)
#   hmc-firmware  the SAMD21 images from the firmware preset (cmake --preset firmware), read from
#                 HMC_FIRMWARE_DIR at install time: build that preset first
# Programs that other folders add install the same way: one hmc_program() line below, and their
# name in the SEE ALSO list of hmc(1).
# Debian puts libraries, and the .pc and CMake files beside them, in the multiarch directory,
# under any prefix (ld.so, pkg-config and find_package search it); GNUInstallDirs does so only
# for /usr, so the packages would not.
if(NOT DEFINED CMAKE_INSTALL_LIBDIR AND CMAKE_LIBRARY_ARCHITECTURE AND EXISTS /etc/debian_version)
  set(CMAKE_INSTALL_LIBDIR lib/${CMAKE_LIBRARY_ARCHITECTURE} CACHE PATH "Object code libraries (lib/<multiarch>)")
endif()
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(hmc_install_files ${PROJECT_BINARY_DIR}/install-files)
set(HMC_BOARD_VARIANT "seed" CACHE STRING
    "The board variant the firmware images in HMC_FIRMWARE_DIR were built for (the firmware preset's HMC_BOARD, default seed), named in the hmc-firmware package")
set(HMC_FIRMWARE_DIR ${PROJECT_SOURCE_DIR}/build/firmware/firmware/targets/samd21 CACHE PATH
    "Where the firmware preset wrote the images that the hmc-firmware component installs")

# ---- Programs and their man pages ---------------------------------------------------------
find_program(HMC_HELP2MAN help2man)
if(NOT HMC_HELP2MAN)
  message(STATUS "install: help2man not found, so no man pages (scripts/setup installs it)")
endif()

# hmc_program(target component summary [SUBCOMMANDS] [SEE_ALSO names...]): installs the program
# and its man page, generated from its --help.
function(hmc_program target component summary)
  cmake_parse_arguments(arg "SUBCOMMANDS" "" "SEE_ALSO" ${ARGN})
  if(NOT TARGET ${target})
    return()
  endif()
  install(TARGETS ${target} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT ${component})
  if(NOT HMC_HELP2MAN)
    return()
  endif()
  get_target_property(name ${target} OUTPUT_NAME)
  set(out ${hmc_install_files}/man/${target})
  add_custom_command(OUTPUT ${out}/stamp
                     COMMAND ${CMAKE_COMMAND} -E rm -rf ${out}
                     COMMAND ${CMAKE_COMMAND} -DHELP2MAN=${HMC_HELP2MAN} -DPROGRAM=$<TARGET_FILE:${target}>
                             -DNAME=${name} -DVERSION=${PROJECT_VERSION} "-DSUMMARY=${summary}"
                             -DOUT_DIR=${out} -DSUBCOMMANDS=${arg_SUBCOMMANDS} "-DSEE_ALSO=${arg_SEE_ALSO}"
                             -DSTAMP=${out}/stamp -P ${PROJECT_SOURCE_DIR}/cmake/man_pages.cmake
                     DEPENDS ${target} ${PROJECT_SOURCE_DIR}/cmake/man_pages.cmake
                     COMMENT "${name}: man pages from its --help"
                     VERBATIM)
  add_custom_target(${target}_man ALL DEPENDS ${out}/stamp)
  install(DIRECTORY ${out}/ DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT ${component}
          FILES_MATCHING PATTERN "*.1.gz")
endfunction()

set(hmc_programs "")
foreach(target hmc_sim hmc_uf2_tool hmc_desk hmc_emu hmc_emu_bootloader_tool)
  if(TARGET ${target})
    get_target_property(name ${target} OUTPUT_NAME)
    list(APPEND hmc_programs ${name})
  endif()
endforeach()
hmc_program(hmc_cli hmc "drive the Hybrid Motor Controller board: frames, moves, motion files, flashing"
            SUBCOMMANDS SEE_ALSO ${hmc_programs})
hmc_program(hmc_sim hmc "the Hybrid Motor Controller's firmware on a simulated board" SEE_ALSO hmc)
hmc_program(hmc_uf2_tool hmc "convert and check UF2 images for the SAMD21 bootloader" SEE_ALSO hmc)
hmc_program(hmc_desk hmc-desk "desktop panel for the Hybrid Motor Controller board" SEE_ALSO hmc)
hmc_program(hmc_emu hmc-emu "the SAMD21 board emulated, running the firmware image" SEE_ALSO hmc hmc-sim hmc-emu-bootloader)
hmc_program(hmc_emu_bootloader_tool hmc-emu "the SAMD21 bootloader emulated, for bossac and UF2 copies" SEE_ALSO hmc-emu)

# ---- Shell completion: `hmc completion bash|zsh`, where bash-completion and zsh look --------
# bash-completion.pc names its directory when it is installed; under our prefix it stays relative.
find_package(PkgConfig QUIET)
set(bash_completion_dir ${CMAKE_INSTALL_DATADIR}/bash-completion/completions)
if(PkgConfig_FOUND)
  pkg_get_variable(completionsdir bash-completion completionsdir)
  if(completionsdir)
    cmake_path(IS_PREFIX CMAKE_INSTALL_PREFIX "${completionsdir}" NORMALIZE under_prefix)
    if(under_prefix)
      cmake_path(RELATIVE_PATH completionsdir BASE_DIRECTORY ${CMAKE_INSTALL_PREFIX} OUTPUT_VARIABLE bash_completion_dir)
    endif()
  endif()
endif()
add_custom_command(OUTPUT ${hmc_install_files}/completion/hmc ${hmc_install_files}/completion/_hmc
                   COMMAND ${CMAKE_COMMAND} -E make_directory ${hmc_install_files}/completion
                   COMMAND sh -c "\"$1\" completion bash > \"$2\" && \"$1\" completion zsh > \"$3\""
                           sh $<TARGET_FILE:hmc_cli> ${hmc_install_files}/completion/hmc
                           ${hmc_install_files}/completion/_hmc
                   DEPENDS hmc_cli
                   COMMENT "hmc: bash and zsh completion from its command tree"
                   VERBATIM)
add_custom_target(hmc_completion ALL DEPENDS ${hmc_install_files}/completion/hmc ${hmc_install_files}/completion/_hmc)
install(FILES ${hmc_install_files}/completion/hmc DESTINATION ${bash_completion_dir} COMPONENT hmc)
install(FILES ${hmc_install_files}/completion/_hmc DESTINATION ${CMAKE_INSTALL_DATADIR}/zsh/vendor-completions
        COMPONENT hmc)

# ---- The udev rule ------------------------------------------------------------------------
# udev's own directory when udev.pc says where it is; else lib/udev/rules.d under the prefix,
# so that an install into a user's prefix needs no root. A udevdir under the prefix stays
# relative, so `cmake --install --prefix` and the packages move it with everything else.
set(HMC_UDEV_RULES_DIR "" CACHE PATH "Where the udev rule goes (empty: udev.pc's udevdir, else lib/udev under the prefix)")
set(udev_rules_dir ${HMC_UDEV_RULES_DIR})
if(NOT udev_rules_dir AND PkgConfig_FOUND)
  pkg_get_variable(udevdir udev udevdir)
  if(udevdir)
    set(udev_rules_dir ${udevdir}/rules.d)
    cmake_path(IS_PREFIX CMAKE_INSTALL_PREFIX "${udev_rules_dir}" NORMALIZE under_prefix)
    if(under_prefix)
      cmake_path(RELATIVE_PATH udev_rules_dir BASE_DIRECTORY ${CMAKE_INSTALL_PREFIX})
    endif()
  endif()
endif()
if(NOT udev_rules_dir)
  set(udev_rules_dir lib/udev/rules.d)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/udev/70-hmc.rules DESTINATION ${udev_rules_dir} COMPONENT hmc)

# ---- Docs and examples --------------------------------------------------------------------
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT hmc)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs COMPONENT hmc
        FILES_MATCHING PATTERN "*.md" PATTERN "*.png" PATTERN "*.svg" PATTERN "*.json")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples COMPONENT hmc
        FILES_MATCHING PATTERN "*.json" PATTERN "*.txt" PATTERN "README.md" PATTERN "CMakeLists.txt" EXCLUDE
        PATTERN "installed" EXCLUDE)
set(dev_docdir ${CMAKE_INSTALL_DATADIR}/doc/libhmc-dev)
install(FILES ${PROJECT_SOURCE_DIR}/examples/hostlib_example.cpp DESTINATION ${dev_docdir}/examples COMPONENT libhmc-dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/installed DESTINATION ${dev_docdir}/examples COMPONENT libhmc-dev)

# ---- libhmc: the library, its headers, the CMake package and hmc.pc -------------------------
set(hmc_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/hmc)
target_include_directories(hmc PUBLIC $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
install(TARGETS hmc EXPORT hmcTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT libhmc-dev)
# A stripping install (`cmake --install --strip`, the packages) keeps the archive's symbols but
# drops its debug sections, as Debian strips static libraries.
install(CODE "
  if(CMAKE_INSTALL_DO_STRIP)
    execute_process(COMMAND ${CMAKE_STRIP} --strip-debug --remove-section=.comment --remove-section=.note
                            --enable-deterministic-archives
                            \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/$<TARGET_FILE_NAME:hmc>\"
                    COMMAND_ERROR_IS_FATAL ANY)
  endif()" COMPONENT libhmc-dev)
foreach(module protocol link session motion profile grbl)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/hostlib/${module}/include/hmc DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
          COMPONENT libhmc-dev)
endforeach()
# The protocol's facts from their one source, under the name the public headers include.
install(FILES ${PROJECT_SOURCE_DIR}/firmware/core/protocol_facts.h ${PROJECT_SOURCE_DIR}/firmware/core/crc16.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hmc COMPONENT libhmc-dev)
install(EXPORT hmcTargets NAMESPACE hmc:: DESTINATION ${hmc_cmake_dir} COMPONENT libhmc-dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hmcConfig.cmake.in ${hmc_install_files}/hmcConfig.cmake
                              INSTALL_DESTINATION ${hmc_cmake_dir})
write_basic_package_version_file(${hmc_install_files}/hmcConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${hmc_install_files}/hmcConfig.cmake ${hmc_install_files}/hmcConfigVersion.cmake
        DESTINATION ${hmc_cmake_dir} COMPONENT libhmc-dev)

# hmc.pc and hmc-json.pc find their prefix from where they are (${pcfiledir}), so a staged or
# relocated install works as well as the packaged one.
set(pkgconfig_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
cmake_path(RELATIVE_PATH CMAKE_INSTALL_PREFIX BASE_DIRECTORY ${CMAKE_INSTALL_PREFIX}/${pkgconfig_dir}
           OUTPUT_VARIABLE pc_prefix_from_pcfiledir)
foreach(pc hmc hmc-json)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${pc}.pc.in ${hmc_install_files}/${pc}.pc @ONLY)
  install(FILES ${hmc_install_files}/${pc}.pc DESTINATION ${pkgconfig_dir} COMPONENT libhmc-dev)
endforeach()

# ---- Firmware images ----------------------------------------------------------------------
set(firmware_images hmc-firmware.bin hmc-firmware.hex hmc-firmware.uf2 hmc-firmware-nobl.bin hmc-firmware-nobl.hex)
configure_file(${PROJECT_SOURCE_DIR}/packaging/firmware-README.in ${hmc_install_files}/firmware/README @ONLY)
# Asked for by name (the hmc-firmware package), missing images are an error; in a plain
# `cmake --install` of everything, they are skipped with a note.
install(CODE "
  foreach(image ${firmware_images})
    if(NOT EXISTS \"${HMC_FIRMWARE_DIR}/\${image}\")
      set(hint \"build the firmware preset first (cmake --preset firmware && cmake --build --preset firmware) or set HMC_FIRMWARE_DIR\")
      if(CMAKE_INSTALL_COMPONENT STREQUAL \"hmc-firmware\")
        message(FATAL_ERROR \"hmc-firmware: ${HMC_FIRMWARE_DIR}/\${image} is missing: \${hint}\")
      endif()
      message(STATUS \"hmc-firmware: no images in ${HMC_FIRMWARE_DIR}, none installed: \${hint}\")
      break()
    endif()
  endforeach()" COMPONENT hmc-firmware)
list(TRANSFORM firmware_images PREPEND ${HMC_FIRMWARE_DIR}/ OUTPUT_VARIABLE firmware_image_paths)
set(firmware_destination ${CMAKE_INSTALL_DATADIR}/hmc/firmware)
install(FILES ${firmware_image_paths} ${hmc_install_files}/firmware/README
        DESTINATION ${firmware_destination} COMPONENT hmc-firmware OPTIONAL)
# An installed `hmc flash` finds them from where it is itself: <bindir>/../share/hmc/firmware.
cmake_path(RELATIVE_PATH firmware_destination BASE_DIRECTORY ${CMAKE_INSTALL_BINDIR}
           OUTPUT_VARIABLE firmware_from_bindir)
target_compile_definitions(hmc_cli PRIVATE HMC_FIRMWARE_FROM_BINDIR="${firmware_from_bindir}")

include(${PROJECT_SOURCE_DIR}/packaging/Debian.cmake)
