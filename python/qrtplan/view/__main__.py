"""qrtplan-view: qrtpland's channels live in Foxglove and/or into an MCAP file.

  qrtplan-view --ws 8765                        # live: ws://127.0.0.1:8765
  qrtplan-view --mcap session.mcap              # record until Ctrl-C
  qrtplan-view --from-log lcmlog-2026 --mcap s.mcap   # an lcm-logger log

docs/view.md says what it shows and how it keeps up with large scans.
"""

from __future__ import annotations

import argparse
import collections
import json
import signal
import sys
import threading
import time
import traceback

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"


def _parser():
    p = argparse.ArgumentParser(
        prog="qrtplan-view", description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="\n".join(__doc__.split("\n")[2:6]))
    p.add_argument("--lcm-url", default=DEFAULT_URL,
                   help="the daemon's LCM URL (default: %(default)s)")
    p.add_argument("--channels", default="QRT_.*",
                   help="LCM channels to take, a regular expression "
                   "(default: %(default)s)")
    p.add_argument("--ws", type=int, metavar="PORT",
                   help="serve the Foxglove WebSocket protocol on PORT")
    p.add_argument("--host", default="127.0.0.1",
                   help="the WebSocket server's address (default: "
                   "%(default)s; 0.0.0.0 for other machines)")
    p.add_argument("--mcap", metavar="FILE", help="write an MCAP file")
    p.add_argument("--from-log", metavar="LCMLOG",
                   help="convert an lcm-logger log instead of listening "
                   "(needs --mcap)")
    p.add_argument("--duration", type=float, metavar="S",
                   help="stop after S seconds (default: at SIGINT/SIGTERM)")
    p.add_argument("--scene", metavar="JSON",
                   help="take the arm (links, radii, tool) from this scene "
                   "file; default: the specification's arm")
    p.add_argument("--ghosts", type=int, default=12,
                   help="ghost arms along a plan at most (default: "
                   "%(default)s)")
    return p


class Intake:
    """The LCM thread only stores what arrives: every message but scans in
    a FIFO that is never trimmed, and of scans only the newest unshown one
    of each channel (an older one is counted as replaced). A worker thread
    shows them, the FIFO first, so a large scan never costs a joint state;
    a scan that has waited SCAN_WAIT_NS goes before the FIFO, so that a
    bridge that cannot keep up (the emulated VM) still draws a scan now
    and then, its FIFO only growing for a moment."""

    SCAN_WAIT_NS = 250_000_000

    def __init__(self, bridge, is_scan):
        self.bridge = bridge
        self.is_scan = is_scan
        self.fifo = collections.deque()
        self.scans: dict[str, tuple[bytes, int]] = {}
        self.cv = threading.Condition()
        self.stopping = False
        self.stats = {"messages_received": 0, "scans_received": 0,
                      "scans_replaced": 0, "scans_shown": 0,
                      "fifo_max": 0}

    def on_lcm(self, channel, data):
        t = time.time_ns()
        with self.cv:
            self.stats["messages_received"] += 1
            if self.is_scan(data):
                self.stats["scans_received"] += 1
                if channel in self.scans:
                    self.stats["scans_replaced"] += 1
                self.scans[channel] = (data, t)
            else:
                self.fifo.append((channel, data, t))
                self.stats["fifo_max"] = max(self.stats["fifo_max"],
                                             len(self.fifo))
            self.cv.notify()

    def run(self):
        while True:
            with self.cv:
                while not (self.fifo or self.scans or self.stopping):
                    self.cv.wait(0.5)
                oldest = min(self.scans, key=lambda c: self.scans[c][1],
                             default=None)
                if oldest is not None and (not self.fifo or (
                        time.time_ns() - self.scans[oldest][1] >
                        self.SCAN_WAIT_NS)):
                    data, t = self.scans.pop(oldest)
                    item = (oldest, data, t)
                    self.stats["scans_shown"] += 1
                elif self.fifo:
                    item = self.fifo.popleft()
                else:
                    return  # stopping, and all shown
            if item[1] is None:  # the once-a-second counters
                with self.cv:
                    st = dict(self.stats)
                self.bridge.log_counts(item[2], st)
            else:
                try:
                    self.bridge.feed(*item)
                except Exception:  # one bad message does not end the view
                    self.stats["errors"] = self.stats.get("errors", 0) + 1
                    if self.stats["errors"] == 1:
                        traceback.print_exc()


def _arm(scene_path):
    from qrtplan.kinematics import Arm
    if not scene_path:
        return Arm.default()
    with open(scene_path, encoding="utf-8") as f:
        return Arm.from_scene(json.load(f))


def from_log(args, bridge):
    import lcm
    import re
    pat = re.compile(args.channels)
    log = lcm.EventLog(args.from_log, "r")
    n = 0
    last = None
    for ev in log:
        if not pat.fullmatch(ev.channel):
            continue
        last = ev.timestamp * 1000
        bridge.feed(ev.channel, ev.data, last)
        n += 1
    if last is not None:
        bridge.log_counts(last, {"lcm_log": args.from_log, "events": n})
    print(f"qrtplan-view: {n} events of {args.from_log} -> {args.mcap}: "
          f"{json.dumps(bridge.counts, sort_keys=True)}", file=sys.stderr)
    return 0


def live(args, bridge):
    import lcm
    from .bridge import CLOUDS, carried_type
    lc = lcm.LCM(args.lcm_url)
    intake = Intake(bridge, lambda d: carried_type(d) in CLOUDS)
    lc.subscribe(args.channels, intake.on_lcm)
    stop = threading.Event()
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, lambda *_: stop.set())
    worker = threading.Thread(target=intake.run, daemon=True)
    worker.start()
    end = time.monotonic() + args.duration if args.duration else None
    next_stats = time.monotonic() + 1.0
    while not stop.is_set() and (end is None or time.monotonic() < end):
        try:
            lc.handle_timeout(50)
        except OSError:  # interrupted by the signal that stops us
            if not stop.is_set():
                raise
        if time.monotonic() >= next_stats:
            next_stats += 1.0
            with intake.cv:
                intake.fifo.append(("", None, time.time_ns()))
                intake.cv.notify()
    with intake.cv:
        intake.stopping = True
        intake.cv.notify()
    worker.join()
    bridge.log_counts(time.time_ns(), intake.stats)
    st = dict(intake.stats, shown=bridge.counts)
    print(f"qrtplan-view: {json.dumps(st, sort_keys=True)}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.from_log and not args.mcap:
        _parser().error("--from-log needs --mcap FILE")
    if not (args.ws or args.mcap):
        _parser().error("give --ws PORT, --mcap FILE or both")
    import foxglove
    from .bridge import Bridge
    ctx = foxglove.Context()
    writer = server = None
    if args.mcap:
        writer = foxglove.open_mcap(args.mcap, allow_overwrite=True,
                                    context=ctx)
    if args.ws and not args.from_log:
        server = foxglove.start_server(name="qrtplan-view", host=args.host,
                                       port=args.ws, context=ctx)
        print(f"qrtplan-view: Foxglove WebSocket on "
              f"ws://{args.host}:{server.port}", file=sys.stderr)
    bridge = Bridge(ctx, _arm(args.scene), ghosts=args.ghosts)
    try:
        rc = from_log(args, bridge) if args.from_log else live(args, bridge)
    finally:
        if writer is not None:
            writer.close()
        if server is not None:
            server.stop()
    return rc


if __name__ == "__main__":
    sys.exit(main())
