#!/usr/bin/python3
"""A pan-tilt scan with LED cues: a grid of views, strip 2 green while moving, white at each view.

The head is examples/pan-tilt-head.toml (pan through 3:1, tilt through 2:1 and inverted), so the
grid is in degrees. Each view holds for --dwell seconds (take a photo, a measurement, a look).
Leaving the `with` block stops both motors whatever happened.

    examples/python/pan_tilt_scan.py
    examples/python/pan_tilt_scan.py --port tcp://192.168.1.50:4000 --dwell 1
"""
import argparse
import os
import time

import hmc

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", default="sim://pantilt?fresh", help="the board (default: the simulated one)")
    parser.add_argument("--profile", default=os.path.join(HERE, "..", "pan-tilt-head.toml"))
    parser.add_argument("--pan", type=float, nargs="+", default=[30, 90, 150, 210])
    parser.add_argument("--tilt", type=float, nargs="+", default=[-20, -45])
    parser.add_argument("--dwell", type=float, default=0.3)
    args = parser.parse_args()

    with hmc.open(args.port, profile=args.profile) as head:
        print(f"board: {head.description}")
        head.led(2, "#ff000000")  # red: homing
        head.home()               # pan, then tilt, against their switches
        for tilt in args.tilt:
            head.move("tilt", to=hmc.deg(tilt))
            for pan in args.pan:
                head.led(2, (0, 255, 0))  # green: moving
                head.move("pan", to=hmc.deg(pan))
                head.led(2, (0, 0, 0, 255))  # white: at a view
                s = head.status()
                print(f"view pan {s.motors[0].units:.1f} deg, tilt {s.motors[1].units:.1f} deg")
                time.sleep(args.dwell)
        head.led(2, "off")
        head.move("tilt", to=hmc.deg(0))
        head.move("pan", to=hmc.deg(0))
        print("scan done")


if __name__ == "__main__":
    main()
