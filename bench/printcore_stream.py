#!/usr/bin/python3
# bench/printcore_stream.py PORT FILE [BAUD] - stream FILE to PORT with
# Printrun's printcore class (the code the `printcore` command runs) and
# print a JSON report with the keys of `stratum send --json`.
#
# The `printcore` command itself sleeps 2 s after connecting and polls for the
# end once a second, so timing it from outside would measure its sleeps.  This
# driver starts the clock when the job starts (startprint: "N-1 M110", then
# the file) and stops it in the end callback, which printcore calls once the
# last line's "ok" has come back.  "bytes" counts every byte printcore wrote
# in between: line numbers, checksums and newlines included, resends and its
# M110 lines too, i.e. what went over the wire towards the printer.
import json
import sys
import threading
import time

from printrun import gcoder
from printrun.printcore import printcore


def main():
    if len(sys.argv) < 3:
        print("usage: printcore_stream.py PORT FILE [BAUD]", file=sys.stderr)
        return 2
    port, path = sys.argv[1], sys.argv[2]
    baud = int(sys.argv[3]) if len(sys.argv) > 3 else 115200
    with open(path) as f:
        gcode = gcoder.LightGCode([line.strip() for line in f])

    stats = {"bytes": 0, "lines": 0, "resends": 0, "errors": 0}
    counting = threading.Event()
    done = threading.Event()
    times = {}

    def on_send(command, gline):
        if counting.is_set():
            stats["bytes"] += len(command) + 1

    def on_printsend(gline):
        stats["lines"] += 1

    def on_recv(line):
        if line.lower().startswith("resend") or line.startswith("rs"):
            stats["resends"] += 1
        elif line.startswith("Error"):
            stats["errors"] += 1

    def on_end():
        times["end"] = time.monotonic()
        counting.clear()
        done.set()

    p = printcore()
    p.sendcb = on_send
    p.printsendcb = on_printsend
    p.recvcb = on_recv
    p.endcb = on_end
    p.errorcb = lambda msg: None  # counted from the received lines instead
    p.connect(port, baud)
    deadline = time.monotonic() + 20
    while not p.online and time.monotonic() < deadline:
        time.sleep(0.01)
    if not p.online:
        print("printcore_stream.py: %s did not answer within 20 s" % port, file=sys.stderr)
        p.disconnect()
        return 69
    # As the printcore command does (it sleeps 2 s after connecting): let the
    # reply to printcore's connect probe (M105) arrive before the job, or it
    # would count as an "ok" for the first line and keep two lines in flight.
    time.sleep(1.0)
    counting.set()
    times["start"] = time.monotonic()
    p.startprint(gcode)
    finished = done.wait(3600)
    p.disconnect()
    if not finished:
        print("printcore_stream.py: the job did not finish within an hour", file=sys.stderr)
        return 1
    secs = times["end"] - times["start"]
    capacity = baud / 10.0
    report = {
        "ok": True,
        "lines": stats["lines"],
        "resends": stats["resends"],
        "errors": stats["errors"],
        "seconds": round(secs, 3),
        "bytes": stats["bytes"],
        "lines_per_s": round(stats["lines"] / secs, 1),
        "bytes_per_s": round(stats["bytes"] / secs, 1),
        "link_fraction": round(stats["bytes"] / secs / capacity, 4),
    }
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
