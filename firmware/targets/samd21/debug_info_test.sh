#!/usr/bin/env bash
# The firmware preset compiles with -g, so that hmc-emu can name the source line of an address
# (docs/emu.md); debug information must not change a byte of what is flashed. Builds the images
# again without -g and compares their .bin files with the preset's, byte for byte.
# Usage: debug_info_test.sh SOURCE_DIR IMAGE_DIR
# Without the preset's images the test is skipped (exit 77), unless CI is set: then it fails.
set -uo pipefail
src=$(realpath "$1")
images=$(realpath -m "$2")
# shellcheck source=SCRIPTDIR/../../../cli/sim_test_lib.sh
source "$src/cli/sim_test_lib.sh"
require_built "$images/hmc-firmware.bin" "$images/hmc-firmware-nobl.bin" "$images/hmc-firmware.elf"

# Line tables of the project's own sources come from -g alone (newlib's and libgcc's objects
# bring small DWARF sections of their own either way).
own_lines() { arm-none-eabi-readelf --debug-dump=rawline "$1" 2>/dev/null | grep -c 'controller\.cpp'; }
check_match "the preset's image has line tables of the sources" "^[1-9]" "$(own_lines "$images/hmc-firmware.elf")"

# ccache, when there is one, makes every run after the first cheap.
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$src" -B "$work/nodebug" -G Ninja --toolchain "$src/cmake/arm-none-eabi.cmake" \
  -DCMAKE_BUILD_TYPE=MinSizeRel -DCMAKE_C_FLAGS_MINSIZEREL="-Os -DNDEBUG" \
  -DCMAKE_CXX_FLAGS_MINSIZEREL="-Os -DNDEBUG" "${launcher[@]}" >"$work/configure.log" 2>&1
check "configure without -g: exit code" 0 $?
out=firmware/targets/samd21
cmake --build "$work/nodebug" --target "$out/hmc-firmware.bin" "$out/hmc-firmware-nobl.bin" \
  >"$work/build.log" 2>&1
check "build without -g: exit code" 0 $?
check "no line tables of the sources without -g" 0 "$(own_lines "$work/nodebug/$out/hmc-firmware.elf")"
for image in hmc-firmware hmc-firmware-nobl; do
  cmp "$images/$image.bin" "$work/nodebug/$out/$image.bin" >"$work/cmp" 2>&1
  check "$image.bin identical with and without -g" "0 " "$? $(cat "$work/cmp")"
done

echo "$checks checks, $failures failures"
[[ $failures -eq 0 ]]
