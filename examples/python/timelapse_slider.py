#!/usr/bin/python3
"""A timelapse on a camera slider: home, then shoot-move-shoot along the rail in millimetres.

The slider is examples/camera-slider.toml (GT2 belt, 20-tooth pulley: 80 steps per mm). Between
frames the carriage moves one slice of the travel with a gentle ramp, waits for the vibration to
settle, and flashes strip 1 white as the shutter cue (wire the strip's data line to a trigger, or
just watch it). Ctrl-C stops the carriage at once.

    examples/python/timelapse_slider.py                        # the simulated board
    examples/python/timelapse_slider.py --port /dev/ttyUSB0 --frames 240 --settle 2
"""
import argparse
import os
import time

import hmc

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", default="sim://timelapse?fresh", help="the board (default: the simulated one)")
    parser.add_argument("--profile", default=os.path.join(HERE, "..", "camera-slider.toml"))
    parser.add_argument("--start", type=float, default=10, help="first frame at this many mm")
    parser.add_argument("--end", type=float, default=300, help="last frame at this many mm")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--settle", type=float, default=0.5, help="seconds to wait before each shot")
    args = parser.parse_args()

    with hmc.open(args.port, profile=args.profile) as board:
        print(f"board: {board.description}")
        board.home("slide")
        board.move("slide", to=hmc.mm(args.start), speed="50mm/s")
        step = (args.end - args.start) / max(args.frames - 1, 1)
        for frame in range(args.frames):
            if frame > 0:
                board.move("slide", to=hmc.mm(args.start + frame * step), speed="10mm/s", accel="50mm/s2")
            time.sleep(args.settle)
            board.led(1, "#000000ff")  # shutter cue
            board.led(1, "off")
            where = board.status().motors[0]
            print(f"frame {frame + 1}/{args.frames} at {where.units:.2f} mm ({where.position} steps)")
        board.move("slide", to=hmc.mm(args.start), speed="50mm/s")
        print("done: back at the start")


if __name__ == "__main__":
    main()
