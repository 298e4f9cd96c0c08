#!/usr/bin/python3
"""Prints, as raw bytes, the input of every conformance vector a board answers on its serial
line: the `line` vectors (each followed by LF) and the `stream` vectors, in the seed's checksum
mode, in file order. Usage: conformance_lines.py VECTORS_DIR > input.bin
"""
import json
import pathlib
import sys


def main(directory):
    out = bytearray()
    count = 0
    for path in sorted(pathlib.Path(directory).glob("*.json")):
        if path.name.startswith("behaviour_"):
            continue
        for vector in json.loads(path.read_text(encoding="utf-8"))["vectors"]:
            if vector.get("checksum_mode", "sum") != "sum":
                continue
            data = vector["input"].encode("latin-1")
            if vector["kind"] == "line":
                out += data + b"\n"
            elif vector["kind"] == "stream":
                out += data
                if not data.endswith((b"\n", b"\r")):
                    out += b"\n"
            else:
                continue
            count += 1
    sys.stdout.buffer.write(bytes(out))
    print(f"conformance_lines: {count} vectors, {len(out)} bytes", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1])
