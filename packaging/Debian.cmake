# The Debian packages: one per install component (cmake/Install.cmake), built by
#   cpack --config build/default/CPackConfig.cmake -B DIR
# (scripts/package-test does, then installs them). The programs' Depends are computed by
# dpkg-shlibdeps; libhmc-dev's are written here, since a static library's needs are invisible to
# it. The firmware images come from the firmware preset's build (HMC_FIRMWARE_DIR).
#
# lintian: no errors or warnings. Informational tags (lintian -I) that remain, and why:
#   hardening-no-fortify-functions, hardening-no-bindnow: the presets build without Debian's
#     dpkg-buildflags (-D_FORTIFY_SOURCE=2, -Wl,-z,now); a distribution build would pass them.
#   binary-has-unneeded-section .comment: CPack's strip keeps the compiler's .comment note.
#   spelling-error-in-binary lengH: bytes of machine code that happen to read so, not text.
#   package-contains-documentation-outside-usr-share-doc: hmc-firmware's README stays beside
#     the images it describes (board variant, guessed pins).
#   wrong-section-according-to-package-name (kernel): the images are for the board's
#     microcontroller, not Linux firmware for /lib/firmware; "electronics" is their section.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME hmc)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
# Staged through DESTDIR, so that absolute destinations (udev's own directory, when udev.pc
# names one outside the configured prefix) land in the package, never on this machine.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "hmc maintainers <maintainers@users.noreply.h-seed-d1c99c47.example>")
set(CPACK_DEBIAN_PACKAGE_SECTION electronics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)

set(CPACK_COMPONENTS_ALL hmc libhmc-dev hmc-firmware)
if(TARGET hmc_desk)
  list(APPEND CPACK_COMPONENTS_ALL hmc-desk)
endif()
if(TARGET hmc_emu)
  list(APPEND CPACK_COMPONENTS_ALL hmc-emu)
endif()
if(TARGET hmc_python)
  list(APPEND CPACK_COMPONENTS_ALL python3-hmc)
endif()

foreach(pkg ${CPACK_COMPONENTS_ALL})
  string(TOUPPER ${pkg} component)
  set(CPACK_DEBIAN_${component}_PACKAGE_NAME ${pkg})
endforeach()

set(CPACK_COMPONENT_HMC_DESCRIPTION
    "tools for the Hybrid Motor Controller board
hmc drives the Hybrid Motor Controller, a SAMD21 board with three DRV8711
stepper drivers, servos, SK6812 LED strips, limit switches and a buzzer,
over its serial text protocol. This package has the hmc command line
(frames, moves, motion files, flashing), hmc-sim (the board's firmware on a
simulated board, no hardware needed), hmc-uf2, a udev rule for the board's
FT232R serial bridge, man pages and bash and zsh completion.")
set(CPACK_DEBIAN_HMC_PACKAGE_SUGGESTS "hmc-firmware, bossa-cli, openocd")

set(CPACK_COMPONENT_LIBHMC-DEV_DESCRIPTION
    "Hybrid Motor Controller host library (development files)
libhmc: typed commands and the frame codec of the Hybrid Motor Controller's
serial protocol, links (serial ports, pseudo-terminals, TCP, the simulated
board in-process), sessions that know the board's rules, and motion files. A
static library with its headers, a CMake package (find_package(hmc), target
hmc::hmc; hmc::json for the JSON forms) and pkg-config files (hmc, hmc-
json).")
set(CPACK_DEBIAN_LIBHMC-DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_LIBHMC-DEV_PACKAGE_DEPENDS "libserialport-dev")
set(CPACK_DEBIAN_LIBHMC-DEV_PACKAGE_SUGGESTS "nlohmann-json3-dev, pkgconf | pkg-config, cmake")

set(CPACK_COMPONENT_HMC-DESK_DESCRIPTION
    "desktop panel for the Hybrid Motor Controller board
hmc-desk shows the board's motors, switches, servos and LED strips and
drives them with the mouse, on a real board or the simulated one.")
set(CPACK_DEBIAN_HMC-DESK_PACKAGE_SUGGESTS "hmc")

set(CPACK_COMPONENT_HMC-EMU_DESCRIPTION
    "SAMD21 emulator for the Hybrid Motor Controller's firmware
hmc-emu runs the board's firmware image on an emulated SAMD21 (Cortex-M0+ on
the Unicorn engine, with the chip's peripherals and the board's DRV8711s),
serving the serial protocol like the real board. hmc-emu-bootloader plays
the SAM-BA bootloader and the UF2 drive, so bossac and hmc flash can be run
against it.")
# hmc-firmware: the image that `hmc --port emu://` runs by default.
set(CPACK_DEBIAN_HMC-EMU_PACKAGE_SUGGESTS "hmc, hmc-firmware, bossa-cli")

set(CPACK_COMPONENT_PYTHON3-HMC_DESCRIPTION
    "Python module for the Hybrid Motor Controller board
import hmc: open a board (serial, TCP, or the simulated one in-process),
move its steppers in the machine profile's millimetres and degrees, wait
for motions (Ctrl-C stops every motor), set servos and LED strips, read its
status and events, run motion files, and encode and decode the protocol's
frames with the codec's diagnostics.")
set(CPACK_DEBIAN_PYTHON3-HMC_PACKAGE_SECTION python)
# The module is built for one interpreter version (its file name says which).
set(CPACK_DEBIAN_PYTHON3-HMC_PACKAGE_DEPENDS "python3 (>= ${HMC_PYTHON_VERSION}), python3 (<< ${HMC_PYTHON_NEXT_VERSION})")
set(CPACK_DEBIAN_PYTHON3-HMC_PACKAGE_SUGGESTS "hmc")

set(CPACK_COMPONENT_HMC-FIRMWARE_DESCRIPTION
    "SAMD21 firmware images for the Hybrid Motor Controller (${HMC_BOARD_VARIANT})
The firmware of the Hybrid Motor Controller board as .bin, .hex and .uf2
images, behind the 8 KB bootloader and without it, which hmc flash finds by
itself. Built for the board variant ${HMC_BOARD_VARIANT} (pin map:
docs/firmware.md). Pins marked guessed in that map (step, direction and
chip-select lines, servos, switches, buzzer, boot LEDs) are unverified on
real hardware: see /usr/share/hmc/firmware/README before flashing.")
set(CPACK_DEBIAN_HMC-FIRMWARE_PACKAGE_ARCHITECTURE all)
set(CPACK_DEBIAN_HMC-FIRMWARE_PACKAGE_SHLIBDEPS OFF)
set(CPACK_DEBIAN_HMC-FIRMWARE_PACKAGE_SUGGESTS "hmc")

# Every package's copyright and changelog, in /usr/share/doc/<package> as Debian requires.
string(TIMESTAMP changelog_date "%a, %d %b %Y %H:%M:%S +0000" UTC)
find_program(HMC_GZIP gzip REQUIRED)
foreach(pkg ${CPACK_COMPONENTS_ALL})
  configure_file(${PROJECT_SOURCE_DIR}/packaging/changelog.in ${hmc_install_files}/debian/${pkg}/changelog @ONLY)
  execute_process(COMMAND ${HMC_GZIP} -9nf ${hmc_install_files}/debian/${pkg}/changelog)
  install(FILES ${PROJECT_SOURCE_DIR}/packaging/copyright ${hmc_install_files}/debian/${pkg}/changelog.gz
          DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/${pkg} COMPONENT ${pkg})
endforeach()

include(CPack)
