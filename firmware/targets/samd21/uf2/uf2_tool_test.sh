#!/bin/sh
# The hmc-uf2 program as the firmware build runs it: convert a known .bin, check the result,
# and fail the check on a damaged file. Usage: uf2_tool_test.sh HMC_UF2 WORK_DIR
set -eu
tool=$1
dir=$2
mkdir -p "$dir"
cd "$dir"
# A known 700-byte image: the bytes 0..255 repeated.
i=0
: > image.bin
while [ $i -lt 700 ]; do
  printf "\\$(printf %o $((i % 256)))" >> image.bin
  i=$((i + 1))
done
[ "$(wc -c < image.bin)" -eq 700 ]
"$tool" convert image.bin image.uf2
[ "$(wc -c < image.uf2)" -eq 1536 ]
"$tool" check image.uf2 image.bin
"$tool" check image.uf2 image.bin --base 0x2000 --family 0x68ED2B88
if "$tool" check image.uf2 image.bin --base 0 2>/dev/null; then
  echo "a UF2 for 0x2000 passed as one for 0" >&2
  exit 1
fi
# Damage one payload byte (block 1, offset 32): the check must fail.
cp image.uf2 damaged.uf2
printf '\377' | dd of=damaged.uf2 bs=1 seek=544 conv=notrunc 2>/dev/null
if "$tool" check damaged.uf2 image.bin 2>/dev/null; then
  echo "a damaged UF2 passed the check" >&2
  exit 1
fi
if "$tool" frobnicate image.bin out.uf2 2>/dev/null; then exit 1; fi
echo "hmc-uf2 tool test passed"
