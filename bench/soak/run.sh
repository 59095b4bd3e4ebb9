#!/usr/bin/env bash
# The soak benchmark of `gpodo live --gate` (bench/README.md, "The frame
# gate on DDS"): the node against a Cyclone DDS peer on loopback for
# DURATION seconds (default 600), with the learner and without it.
#
#   cargo build --release -p gpodo-experiments --features ros2
#   PYTHON=target/ci-python/bin/python bash bench/soak/run.sh [DURATION]
#   (RUNS=learning or RUNS=fixed for one of the two)
#
# Needs a Python with cyclonedds and mcap-ros2-support (CI's venv has
# them). Writes bench/soak/out/{learning,fixed}.json and prints the
# figures.
set -euo pipefail
cd "$(dirname "$0")/../.."
DURATION=${1:-600}
PYTHON=${PYTHON:-target/ci-python/bin/python}
GPODO=target/release/gpodo
OUT=bench/soak/out
mkdir -p "$OUT"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# A model of ExoTeR's residual, and a recording whose joint names and IMU
# the peer takes.
$GPODO --quiet simulate --preset exoter-prl --seed 3 --format mcap --training-runs 2 --training-run-secs 120 --test-max-secs 60 --out "$work/robot" >/dev/null
sed -e "s|../../tutorial/robot|$work/robot|g" -e "s|../../kinematics|$PWD/kinematics|g" docs/tutorials/on-the-robot.yaml > "$work/experiment.yaml"
$GPODO --quiet fit "$work/experiment.yaml" --regressor "exact GP: rbf" --save "$work/model.gpodo" >/dev/null

cat > "$work/cyclone.xml" <<'XML'
<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>
XML
joints=$(grep -A2 '^joints:' "$work/robot/topics.yaml" | sed -n 's/^ *topic: *//p' | head -1)
imu=$(sed -n 's/^imu: *//p' "$work/robot/topics.yaml" | head -1)
cat > "$work/topics.json" <<JSON
{"joints": "$joints", "imu": "$imu",
 "left_image": "/camera/left/image_raw", "right_image": "/camera/right/image_raw",
 "left_info": "/camera/left/camera_info", "right_info": "/camera/right/camera_info",
 "vo_odometry": "/vo/odometry", "decisions": "/gpodo/gate/decisions",
 "gated": ["/gated/camera/left/image_raw"]}
JSON
# The topic map on the wall clock's header stamps, at 100 Hz.
sed 's/^rate_hz: .*/rate_hz: 100.0/' "$work/robot/topics.yaml" > "$work/topics.yaml"

run() {
  local name=$1 online=$2
  sed -e '/^online:/d' -e 's|vo_odometry: /vo/pose|vo_odometry: /vo/odometry|' -e 's|^predictions: windows|predictions: every_sample|' docs/tutorials/gate.yaml > "$work/gate-$name.yaml"
  if [ "$online" = yes ]; then
    echo 'online: { regressor: { kind: ilgr, init_lengthscale: 2.0 } }' >> "$work/gate-$name.yaml"
  fi
  local domain=$((150 + RANDOM % 50))
  CYCLONEDDS_URI="file://$work/cyclone.xml" "$PYTHON" bench/soak/peer.py "$domain" \
    "$work/robot/test.mcap" "$work/topics.json" "$DURATION" "$OUT/$name.json" best_effort &
  local peer=$!
  $GPODO --quiet live --model "$work/model.gpodo" --rover kinematics/rovers/exoter.yaml \
    --topics "$work/topics.yaml" --gate "$work/gate-$name.yaml" --checkpoint "$work/$name-learner.json" \
    --domain-id "$domain" --dds-interface 127.0.0.1 --idle-exit-secs 10 > "$OUT/$name.log" 2>&1 &
  local node=$!
  # The node's resident memory every 30 s while the peer runs.
  local rss=()
  while kill -0 "$peer" 2>/dev/null; do
    sleep 30
    rss+=("$(ps -o rss= -p "$node" | tr -d ' ' || true)")
  done
  wait "$peer"
  wait "$node"
  "$PYTHON" - "$OUT/$name.json" "${rss[@]}" <<'PY'
import json, sys
path, rss = sys.argv[1], [int(v) for v in sys.argv[2:] if v]
r = json.load(open(path))
# From 120 s on, after the reliable writers' histories (ten pairs of
# images each) have filled.
at = {"30_s": rss[0], "120_s": rss[3], "end": rss[-1]}
r["rss_kib"] = {"every_30_s": rss, **{"at_" + k: v for k, v in at.items()},
                "growth_percent_from_30_s": 100.0 * (at["end"] - at["30_s"]) / at["30_s"],
                "growth_percent_from_120_s": 100.0 * (at["end"] - at["120_s"]) / at["120_s"]}
p99 = sorted(r.pop("node_latency_p99_ms"))
r["node_latency_p99_ms"] = {"median_over_reports": p99[len(p99) // 2], "max": p99[-1], "reports": len(p99)}
json.dump(r, open(path, "w"), indent=1)
print(json.dumps(r, indent=1))
PY
}

for which in "${RUNS:-learning fixed}"; do
  for name in $which; do
    case $name in
      learning) run learning yes ;;
      fixed) run fixed no ;;
    esac
  done
done
