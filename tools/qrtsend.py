#!/usr/bin/env python3
"""Send qrtpland a plan request signed with an operator key.

  qrtsend.py --key keys/operator.key --joints 30 40 -20 [--wait 5]
  qrtsend.py --key keys/operator.key --xyz 0.4 0.2 0.3 [--facing front] [--elbow up]

The goal is joints in degrees (alpha, sigma, eta) or an end-effector point
in metres, for which --facing and --elbow ask for an IK branch (docs/spec.md
section Kinematics, Branches; default any); without --start the daemon
starts from the measured joints.
With --wait SECONDS it prints the plan's status (exit 0 for ok, 1 else).
"""
import argparse
import os
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.environ.get("QRT_LCMTYPES_PY",
                                  os.path.join(REPO, "build", "lcmtypes", "python")))
import lcm  # noqa: E402
from qrtplan import plan_request_t, plan_t  # noqa: E402

import qrtauth  # noqa: E402

# the request's values of plan_request_t's IK_* constants
FACING = {"any": plan_request_t.IK_ANY, "front": plan_request_t.IK_FACING_FRONT,
          "back": plan_request_t.IK_FACING_BACK}
ELBOW = {"any": plan_request_t.IK_ANY, "up": plan_request_t.IK_ELBOW_UP,
         "down": plan_request_t.IK_ELBOW_DOWN}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--key", required=True, help="the operator's NAME.key")
    goal = ap.add_mutually_exclusive_group(required=True)
    goal.add_argument("--joints", nargs=3, type=float, metavar="DEG")
    goal.add_argument("--xyz", nargs=3, type=float, metavar="M")
    ap.add_argument("--start", nargs=3, type=float, metavar="DEG")
    ap.add_argument("--facing", choices=FACING, default="any",
                    help="with --xyz: the IK branch's facing")
    ap.add_argument("--elbow", choices=ELBOW, default="any",
                    help="with --xyz: the IK branch's elbow")
    ap.add_argument("--request-id", type=int, default=None,
                    help="echoed in the plans (default: the time in ms)")
    ap.add_argument("--lcm-url", default="udpm://239.255.76.67:7667?ttl=0")
    ap.add_argument("--channel", default="QRT_PLAN_REQUEST")
    ap.add_argument("--plan-channel", default="QRT_PLAN")
    ap.add_argument("--wait", type=float, default=0.0, metavar="SECONDS")
    a = ap.parse_args()
    if a.joints and (a.facing != "any" or a.elbow != "any"):
        ap.error("--facing and --elbow apply to --xyz goals only")
    try:
        signer = qrtauth.Signer(a.key)
    except (OSError, qrtauth.KeyFileError) as e:
        sys.exit(f"qrtsend: {e}")
    r = plan_request_t()
    r.utime = time.time_ns() // 1000
    r.request_id = a.request_id if a.request_id is not None else r.utime // 1000
    r.goal_kind = plan_request_t.GOAL_XYZ if a.xyz else plan_request_t.GOAL_JOINTS
    r.goal = list(a.xyz or a.joints)
    r.has_start = a.start is not None
    r.start_deg = list(a.start) if a.start else [0.0, 0.0, 0.0]
    r.ik_facing = FACING[a.facing]
    r.ik_elbow = ELBOW[a.elbow]
    lc = lcm.LCM(a.lcm_url)
    got = []
    if a.wait > 0:
        lc.subscribe(a.plan_channel, lambda c, d: got.append(plan_t.decode(d)))
    lc.publish(a.channel, signer.seal(a.channel, r.encode()))
    print(f"request {r.request_id}: sent as '{signer.name}'")
    end = time.time() + a.wait
    while time.time() < end:
        lc.handle_timeout(50)
        mine = [p for p in got if p.request_id == r.request_id]
        if mine:
            p = mine[0]
            print(f"request {r.request_id}: {p.status}: {p.detail}")
            return 0 if p.status == "ok" else 1
    if a.wait > 0:
        print(f"request {r.request_id}: no plan within {a.wait:g} s "
              "(refused? see the daemon's log and status)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
