#!/usr/bin/python3
"""A status monitor: one line per motor every --every seconds, and every event as it comes.

Events (moves done, switches, the emergency switch, the link watchdog) are printed by an
on_event callback, which the library runs on this thread while status() and listen() read the
board. --demo sets motor 3 going back and forth so there is something to see.

    examples/python/status_monitor.py --port /dev/ttyUSB0
    examples/python/status_monitor.py --demo --duration 3
"""
import argparse
import time

import hmc


def show_event(event):
    print(f"  event: {event.text}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", default="sim://monitor?fresh", help="the board (default: the simulated one)")
    parser.add_argument("--every", type=float, default=0.5, help="seconds between status lines")
    parser.add_argument("--duration", type=float, default=0, help="stop after this many seconds (0: Ctrl-C)")
    parser.add_argument("--demo", action="store_true", help="move motor 3 back and forth meanwhile")
    args = parser.parse_args()

    with hmc.open(args.port) as board:
        print(f"board: {board.description}, firmware {board.firmware}")
        board.on_event(show_event)
        started = time.monotonic()
        direction = 1
        while args.duration == 0 or time.monotonic() - started < args.duration:
            if args.demo and board.status().motors[2].state == "idle":
                board.move(3, steps=direction * 800, speed=4000, wait=False)
                direction = -direction
            s = board.status()
            print(f"{time.monotonic() - started:6.2f} s  emergency {'PRESSED' if s.emergency else 'released'}")
            for m in s.motors:
                print(f"  motor {m.motor}: {m.state:8} at {m.position} steps of 1/{m.microstep}, {m.rate} steps/s"
                      f"{', homed' if m.homed else ''}")
            board.listen(args.every)
        board.wait()


if __name__ == "__main__":
    main()
