#!/usr/bin/env bash
# The closed loop on vcan0 (this host's, else in the tests' VM, which makes
# one: tools/vm/run.sh): servo_sim's three drives power up at the
# Table 4 start, qrtpland gets the Table 4 sphere as range scans (a freshly
# stamped one every 0.1 s, as a sensor sends them: the daemon moves the arm
# only on evidence younger than --max-scan-age) and the goal as a plan
# request, plans from the joints the drives report and moves them; the
# joints it publishes are traced into build/demo/can_trace.csv, checked
# with the oracle and drawn over the plan (can_trace.png). qrtplan-view
# records the session (build/demo/session.mcap, docs/view.md) and draws it
# (session.png).
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/demo
mkdir -p "$out"
if [ ! -e /sys/class/net/vcan0 ]; then
    # the VM has a vcan0, so this script goes on there; 77: no VM either
    echo "closed loop on CAN: this host has no vcan0, so in a VM that has" \
        "one (tools/vm/run.sh; about a minute)"
    rc=0
    tools/vm/run.sh --vm-only -- "$0" --in-vm || rc=$?
    if [ "$rc" -eq 77 ]; then
        echo "closed loop on CAN: skipped, no vcan0 here and no VM to make" \
            "one (sudo ip link add dev vcan0 type vcan &&" \
            "sudo ip link set up vcan0)"
        exit 0
    fi
    exit "$rc"
fi
slow=()
if [ "${1:-}" = --in-vm ]; then
    # the VM's emulated CPU delays heartbeats, as in the tests run there
    slow=(--heartbeat-timeout 1500)
fi
url="udpm://239.255.76.67:7790?ttl=0&recv_buf_size=4194304"
# the recording: listening before anything is published
rm -f "$out/session.mcap"
export PYTHONPATH=python${PYTHONPATH:+:$PYTHONPATH} # the package's source
.venv/bin/python -m qrtplan.view --lcm-url "$url" --mcap "$out/session.mcap" \
    2>"$out/view.log" &
view=$!
build/bin/servo_sim --iface vcan0 --start-deg -100,0,0 --servo-error 5 \
    2>"$out/servo_sim.log" &
sim=$!
# the senders' keys (docs/security.md): the daemon moves the arm only on
# requests and scans authenticated with them
keys=$out/keys
mkdir -p -m 700 "$keys"
for k in op:operator s0:sensor; do
    [ -f "$keys/${k%%:*}.key" ] || build/bin/qrtpland --gen-key "${k%%:*}" \
        --role "${k##*:}" --key-dir "$keys" >/dev/null
done
build/bin/qrtpland --lcm-url "$url" --can vcan0 --keys "$keys" --speed 60 --accel 120 \
    "${slow[@]}" 2>"$out/qrtpland.log" &
daemon=$!
trap 'kill $daemon $sim $view 2>/dev/null || true; wait 2>/dev/null' EXIT
sleep 1 # the recorder subscribed
rc=0
QRT_LCMTYPES_PY=build/lcmtypes/python .venv/bin/python - "$url" "$out" <<'PY' || rc=$?
import csv, os, sys, time
sys.path[:0] = ["tests/daemon", "tools", "tests/canlink"]
import conftest as cf, numpy as np, oracle
import qrtauth
import vm_checks
from vm_checks import ScanFeed
url, out = sys.argv[1], sys.argv[2]
vm_checks.sign_as(qrtauth.Signer(os.path.join(out, "keys", n + ".key"))
                  for n in ("op", "s0"))
lc = vm_checks.signing_lcm(url)
joints, plans = [], []
lc.subscribe("QRT_JOINT_STATE", lambda c, d: joints.append(cf.joint_state_t.decode(d)))
lc.subscribe("QRT_PLAN", lambda c, d: plans.append(cf.plan_t.decode(d)))
def pump(s, until):
    end = time.time() + s
    while time.time() < end and not until():
        lc.handle_timeout(10)
    return until()
scene, pts = cf.scene_points("table4_one_sphere.json")
pump(15, lambda: joints and joints[-1].drive_state == "ready")
feed = ScanFeed(url, cf, pts)  # the sensor: a fresh scan every 0.1 s
pump(1, lambda: feed.published > 0)
lc.publish("QRT_PLAN_REQUEST", cf.request([100, 0, 0], request_id=1).encode())
pump(10, lambda: any(j.moving for j in joints))
ok = pump(60, lambda: joints and not joints[-1].moving and
          abs(oracle.wrap180(joints[-1].joints_deg[0] - 100)) < 0.05)
feed.stop()
q = np.array([j.joints_deg for j in joints])
with open(os.path.join(out, "can_trace.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["utime", "alpha_deg", "sigma_deg", "eta_deg", "drive_state"])
    for j in joints:
        w.writerow([j.utime, *j.joints_deg, j.drive_state])
c = oracle.clearances(oracle.Arm(scene), q, pts)
plan = next((p for p in plans if p.status == "ok"), None)
print(f"closed loop on CAN: {'goal reached' if ok else 'GOAL NOT REACHED'}, "
      f"{len(q)} joint states, min clearance {c.min():.4f} m, plan "
      f"{[list(map(lambda v: round(v, 1), w)) for w in plan.waypoints_deg] if plan else None}")
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
fig, ax = plt.subplots(figsize=(7, 4.5))
t = (np.array([j.utime for j in joints]) - joints[0].utime) / 1e6
for k, name in enumerate(("alpha", "sigma", "eta")):
    tk, yk = t, q[:, k]
    if k == 0:  # alpha wraps at +-180: a gap there, not a line across
        seam = np.where(np.abs(np.diff(yk)) > 180)[0] + 1
        tk, yk = np.insert(tk, seam, np.nan), np.insert(yk, seam, np.nan)
    ax.plot(tk, yk, label=f"{name} (drives' PDOs)")
ax.set_xlabel("time (s)")
ax.set_ylabel("joint angle (degrees; alpha wraps at +-180)")
ax.set_title("Table 4 on the simulated drives: qrtpland -> CiA 402 -> servo_sim")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(out, "can_trace.png"), dpi=110)
sys.exit(0 if ok and c.min() >= 0 else 1)
PY
# the daemon stops, then the recorder closes its file
kill "$daemon" "$sim" 2>/dev/null || true
wait "$daemon" "$sim" 2>/dev/null || true
sleep 0.5
kill -INT "$view"
vrc=0
wait "$view" || vrc=$?
[ "$vrc" -eq 0 ] || { echo "qrtplan-view exited with $vrc ($out/view.log)" >&2; rc=1; }
.venv/bin/python -m qrtplan.view.render "$out/session.mcap" "$out/session.png" ||
    { echo "session.png: the renderer failed" >&2; rc=1; }
echo "recorded: $out/session.mcap ($(du -k "$out/session.mcap" | cut -f1) KB;" \
    "$(tail -n 1 "$out/view.log")), drawn: $out/session.png"
[ "$rc" -eq 0 ] || echo "closed loop on CAN: exit $rc" >&2
exit "$rc"
