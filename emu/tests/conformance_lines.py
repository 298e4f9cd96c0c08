#!/usr/bin/python3
"""Prints, as raw bytes, the input of every conformance vector a board answers on its serial
line: the `line` vectors (each followed by LF) and the `stream` vectors, in the seed's checksum
mode, in file order — the vectors conformance_over_uart.py plays one at a time, as one burst.
Usage: conformance_lines.py VECTORS_DIR > input.bin
"""
import sys

from conformance_over_uart import vectors


def main(directory):
    inputs = [data for _, data, _ in vectors(directory)]
    out = b"".join(inputs)
    sys.stdout.buffer.write(out)
    print(f"conformance_lines: {len(inputs)} vectors, {len(out)} bytes", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1])
