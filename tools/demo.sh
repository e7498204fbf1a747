#!/usr/bin/env bash
# The main job: plan the paper's scenes (scenes/*.json), check every plan with
# the independent oracle, and draw them into build/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/qrtplan
py=.venv/bin/python
out=build/demo
mkdir -p "$out"
printf '%-22s %-8s %9s %9s %11s %11s  %s\n' scene status waypoints cost_deg \
    convert_ms total_ms oracle
for scene in scenes/*.json; do
    name=$(basename "$scene" .json)
    # the whole mask first: the table shows its time as convert_ms
    "$bin" plan "$scene" --whole-mask -o "$out/$name.plan.json"
    "$bin" mask "$scene" -o "$out/$name.mask.json"
    verdict=$("$py" tools/oracle.py "$scene" "$out/$name.plan.json") || {
        echo "$name: ORACLE REJECTS THE PLAN: $verdict" >&2
        exit 1
    }
    "$py" tools/plot_plan.py "$scene" "$out/$name.plan.json" \
        "$out/$name.mask.json" "$out/$name"
    "$py" - "$out/$name.plan.json" "$name" "$verdict" <<'PY'
import json, sys
p = json.load(open(sys.argv[1]))
t = p["stats"]["time_us"]
print(f"{sys.argv[2]:<22} {p['status']:<8} {len(p.get('waypoints_deg', [])):>9} "
      f"{p.get('cost_deg', float('nan')):>9.2f} {t['convert'] / 1e3:>11.2f} "
      f"{t['total'] / 1e3:>11.2f}  {sys.argv[3].split(',')[0]}")
PY
done
echo
echo "Table 4 (one sphere, alpha -100 -> 100 across +-180): ours beside the paper's"
"$py" - "$out/table4_one_sphere.plan.json" <<'PY'
import json, sys
paper = [(-100, 0, 0), (-121.695, -14.1908, 0.1828), (-159.75, -42.4559, -49.5),
         (165.3354, -27.9574, -49.5), (144.0931, -10.6416, -49.5),
         (125.7179, -4.6067, -11.838), (100, 0, 0)]
ours = json.load(open(sys.argv[1])).get("waypoints_deg", [])
print(f"  {'#':>2}  {'ours (alpha, sigma, eta)':>30}   {'paper':>30}")
for i in range(max(len(ours), len(paper))):
    o = "(%8.2f, %7.2f, %7.2f)" % tuple(ours[i]) if i < len(ours) else ""
    q = "(%8.2f, %7.2f, %7.2f)" % paper[i] if i < len(paper) else ""
    print(f"  {i + 1:>2}  {o:>30}   {q:>30}")
PY
echo
tools/demo_can.sh
echo
echo "Plans, masks and pictures: $out/ (*_cspace.png, *_arm.png, can_trace.png," \
    "session.png); the closed loop's recording for Foxglove: $out/session.mcap"
