#!/usr/bin/env python3
"""Ask a running qrtpland for a plan and print it.

  plan_client.py --key keys/op.key --start -100 0 0 --goal 100 0 0

Signs a plan request with an operator key (qrtpland --gen-key NAME --role
operator), publishes it on QRT_PLAN_REQUEST, waits for the plan that
answers it on QRT_PLAN and prints its status and waypoints. Exit 0 for an
ok plan, 1 for any other status or none in time, 2 for a bad key.

Needs the PyPI packages lcm and pynacl, tools/qrtauth.py (the signing), and
the Python message types lcm-gen made: QRT_LCMTYPES_PY, else
build/lcmtypes/python (installed: PREFIX/share/qrtplan/python).
"""
import argparse
import os
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "tools"))
sys.path.insert(0, os.environ.get("QRT_LCMTYPES_PY",
                                  os.path.join(REPO, "build", "lcmtypes", "python")))
import lcm  # noqa: E402
from qrtplan import plan_request_t, plan_t  # noqa: E402

import qrtauth  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--key", required=True, help="an operator's NAME.key")
    ap.add_argument("--goal", nargs=3, type=float, required=True,
                    metavar="DEG", help="alpha sigma eta")
    ap.add_argument("--start", nargs=3, type=float, metavar="DEG",
                    help="default: the joints the drives report")
    ap.add_argument("--lcm-url", default="udpm://239.255.76.67:7667?ttl=0")
    ap.add_argument("--wait", type=float, default=10.0, metavar="SECONDS")
    a = ap.parse_args()
    try:
        signer = qrtauth.Signer(a.key)
    except (OSError, qrtauth.KeyFileError) as e:
        print(f"plan_client: {e}", file=sys.stderr)
        return 2

    req = plan_request_t()
    req.utime = time.time_ns() // 1000
    req.request_id = req.utime  # echoed in the plans that answer it
    req.goal_kind = plan_request_t.GOAL_JOINTS
    req.goal = a.goal
    req.has_start = a.start is not None
    req.start_deg = a.start or [0.0, 0.0, 0.0]

    lc = lcm.LCM(a.lcm_url)
    answers = []
    lc.subscribe("QRT_PLAN", lambda channel, data: answers.append(plan_t.decode(data)))
    # the daemon takes the request only with a valid signature over the
    # channel's name and the message (docs/security.md)
    lc.publish("QRT_PLAN_REQUEST", signer.seal("QRT_PLAN_REQUEST", req.encode()))

    end = time.monotonic() + a.wait
    while time.monotonic() < end:
        lc.handle_timeout(50)
        for p in answers:
            if p.request_id == req.request_id:
                print(f"status {p.status}: {p.detail}")
                for w in p.waypoints_deg:
                    print("waypoint %.6f %.6f %.6f" % tuple(w))
                if p.status == "ok":
                    print(f"cost_deg {p.cost_deg:.6f}")
                return 0 if p.status == "ok" else 1
    print(f"no plan within {a.wait:g} s (the request refused? see the "
          "daemon's log)", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
